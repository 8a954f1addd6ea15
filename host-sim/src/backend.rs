//! Where the controller's set-points go: simulated drives on a virtual CAN bus, real drives on
//! SocketCAN, or a simulated arm with no bus at all.

use std::str::FromStr;

use armgate_core::command::{ArmModel, Drives, SimulatedDrives};
use armgate_core::config::ValidRobot;
use armgate_core::drives::{BusState, CanBus, DriveManager, DriveSettings, TxError, VirtualBus};
use armgate_core::kinematics::Joints;
use armgate_protocol::can::CanFrame;

use crate::socketcan::{self, SocketCan};

/// The `--can` choice.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CanChoice {
    /// Simulated Whistles on a virtual bus.
    Sim,
    /// Linux SocketCAN on this interface.
    SocketCan(String),
    /// No bus: a simulated arm.
    Off,
}

impl FromStr for CanChoice {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "sim" => Ok(Self::Sim),
            "off" => Ok(Self::Off),
            _ => match s.strip_prefix("socketcan:") {
                Some(iface) if !iface.is_empty() => Ok(Self::SocketCan(iface.to_owned())),
                _ => Err(format!("`{s}`: expected sim, off or socketcan:IFACE")),
            },
        }
    }
}

/// The drives behind the controller.
pub enum Backend {
    /// A simulated arm, no bus.
    Direct {
        drives: Box<SimulatedDrives>,
        period: f64,
    },
    /// The drive manager on a bus.
    Can {
        manager: Box<DriveManager>,
        bus: Bus,
    },
}

/// The bus under the drive manager.
pub enum Bus {
    /// Simulated Whistles; time advances with the control loop.
    Virtual(Box<VirtualBus>),
    /// A real interface.
    Socket(SocketCan),
}

impl Backend {
    /// Opens the drives chosen with `--can`, with the joints at `start`. Like the seed's robot
    /// component, CAN drives are started at once.
    pub fn open(
        choice: &CanChoice,
        config: &ValidRobot,
        start: &Joints,
        arm: impl FnOnce() -> ArmModel,
    ) -> Result<Self, String> {
        let bus = match choice {
            CanChoice::Off => {
                return Ok(Self::Direct {
                    drives: Box::new(SimulatedDrives::new(arm())),
                    period: config.control_period,
                });
            }
            CanChoice::Sim => Bus::Virtual(Box::new(VirtualBus::for_robot_at(config, start))),
            CanChoice::SocketCan(iface) => {
                Bus::Socket(SocketCan::open(iface).map_err(|e| socketcan::explain(iface, &e))?)
            }
        };
        let mut manager = DriveManager::new(config, &DriveSettings::default())
            .map_err(|e| format!("drives: {e} (try --can off)"))?;
        manager
            .start()
            .map_err(|e| format!("drives: cannot start: {e:?}"))?;
        Ok(Self::Can {
            manager: Box::new(manager),
            bus,
        })
    }

    /// A short description for the start-up line.
    pub fn describe(&self) -> &'static str {
        match self {
            Self::Direct { .. } => "simulated arm, no bus",
            Self::Can { bus, .. } => match bus {
                Bus::Virtual(_) => "simulated Whistles on a virtual CAN bus",
                Bus::Socket(_) => "SocketCAN",
            },
        }
    }

    /// Runs the bus up to time `t` and takes the drives' answers (before the control step).
    pub fn receive(&mut self, t: f64) -> Result<(), String> {
        if let Self::Can { manager, bus } = self {
            if let Bus::Virtual(virtual_bus) = bus {
                virtual_bus
                    .advance(t)
                    .map_err(|e| format!("virtual CAN bus: {e:?}"))?;
            }
            manager.receive(bus);
        }
        Ok(())
    }

    /// Sends this tick's command (after the control step).
    pub fn transmit(&mut self, t: f64, command: Option<&Joints>) {
        match self {
            Self::Direct { drives, period } => drives.apply(command, *period),
            Self::Can { manager, bus } => manager.transmit(t, command, bus),
        }
    }

    /// The measured joints.
    pub fn measured(&self) -> Joints {
        match self {
            Self::Direct { drives, .. } => drives.measured(),
            Self::Can { manager, .. } => manager.measured(),
        }
    }

    /// The drives as the command handler sees them.
    pub fn drives(&self) -> &dyn Drives {
        match self {
            Self::Direct { drives, .. } => drives.as_ref(),
            Self::Can { manager, .. } => manager.as_ref(),
        }
    }

    /// The same, mutable.
    pub fn drives_mut(&mut self) -> &mut dyn Drives {
        match self {
            Self::Direct { drives, .. } => drives.as_mut(),
            Self::Can { manager, .. } => manager.as_mut(),
        }
    }
}

impl CanBus for Bus {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        let sent = match self {
            Self::Virtual(bus) => bus.try_transmit(frame),
            Self::Socket(bus) => bus.try_transmit(frame),
        };
        if sent.is_ok() {
            crate::pcap::can(frame);
        }
        sent
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        let frame = match self {
            Self::Virtual(bus) => bus.try_receive(),
            Self::Socket(bus) => bus.try_receive(),
        };
        frame.inspect(crate::pcap::can)
    }

    fn state(&self) -> BusState {
        match self {
            Self::Virtual(bus) => bus.state(),
            Self::Socket(bus) => bus.state(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn can_choices_parse() {
        assert_eq!("sim".parse(), Ok(CanChoice::Sim));
        assert_eq!("off".parse(), Ok(CanChoice::Off));
        assert_eq!(
            "socketcan:can0".parse(),
            Ok(CanChoice::SocketCan("can0".into()))
        );
        assert!("socketcan:".parse::<CanChoice>().is_err());
        assert!("pcan".parse::<CanChoice>().is_err());
    }
}

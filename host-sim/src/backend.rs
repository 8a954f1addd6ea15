//! Where the controller's set-points go: simulated drives on a virtual CAN bus, real drives on
//! SocketCAN, or a simulated arm with no bus at all.

use std::str::FromStr;

use armgate_core::command::Drives;
use armgate_core::config::ValidRobot;
use armgate_core::cycle::{CanDrives, DriveSide};
use armgate_core::drives::{BusState, CanBus, DriveSettings, LifecycleError, TxError};
use armgate_core::kinematics::Joints;
use armgate_core::motion::Refusal;
use armgate_core::sim::VirtualBus;
use armgate_core::sim::{ArmModel, SimulatedDrives};
use armgate_protocol::can::CanFrame;
use armgate_protocol::client::{DriveStatus, Text};

use armgate_socketcan::{self as socketcan, LinuxBus, Pacer, SocketCan};

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

/// The drives behind the controller: one [`DriveSide`] chosen at run time.
pub enum Backend {
    /// A simulated arm, no bus.
    Direct(Box<SimulatedDrives>),
    /// The drive manager on a bus.
    Can(Box<CanDrives<Bus>>),
}

/// The bus under the drive manager: simulated Whistles (their time advances with the control
/// loop) or a real interface, every frame that crosses it captured (`--pcap`, `--mcap`).
pub struct Bus(pub LinuxBus<&'static mut VirtualBus>);

impl Backend {
    /// Opens the drives chosen with `--can`, with the joints at `start` (SocketCAN writes held
    /// to the robot file's bit rate if `paced`: `--pace-can`). Like the seed's robot
    /// component, CAN drives are started at once.
    pub fn open(
        choice: &CanChoice,
        paced: bool,
        config: &ValidRobot,
        start: &Joints,
        arm: impl FnOnce() -> ArmModel,
    ) -> Result<Self, String> {
        let bus = match choice {
            CanChoice::Off => return Ok(Self::Direct(Box::new(SimulatedDrives::new(arm())))),
            // The process's one simulated bus, for as long as it runs.
            CanChoice::Sim => {
                LinuxBus::Simulated(Box::leak(Box::new(VirtualBus::for_robot_at(config, start))))
            }
            CanChoice::SocketCan(iface) => {
                let pacer = paced.then(|| Pacer::new(config.drives.can_bitrate));
                LinuxBus::SocketCan(
                    SocketCan::open(iface, pacer).map_err(|e| socketcan::explain(iface, &e))?,
                )
            }
        };
        let mut drives = CanDrives::started(config, &DriveSettings::default(), Bus(bus))
            .map_err(|e| format!("drives: {e} (try --can off)"))?;
        drives.manager_mut().place_undriven(start);
        Ok(Self::Can(Box::new(drives)))
    }

    /// A short description for the start-up line.
    pub fn describe(&self) -> &'static str {
        match self {
            Self::Direct(_) => "simulated arm, no bus",
            Self::Can(drives) => match drives.bus().0 {
                LinuxBus::Simulated(_) => "simulated Whistles on a virtual CAN bus",
                LinuxBus::SocketCan(_) => "SocketCAN",
            },
        }
    }

    /// What the SocketCAN adapter ignored or could not do, for the exit summary.
    pub fn socketcan_summary(&self) -> Option<String> {
        let Self::Can(drives) = self else {
            return None;
        };
        let LinuxBus::SocketCan(socket) = &drives.bus().0 else {
            return None;
        };
        let c = socket.counters();
        Some(format!(
            "SocketCAN: {} extended/remote frames ignored, {} error frames ignored, {} bus-offs, {} frames refused by a full transmit queue, {} other socket errors",
            c.foreign_frames, c.error_frames, c.bus_offs, c.queue_full, c.socket_errors
        ))
    }

    /// The one in use, as a [`DriveSide`].
    fn side(&self) -> &dyn DriveSide {
        match self {
            Self::Direct(drives) => drives.as_ref(),
            Self::Can(drives) => drives.as_ref(),
        }
    }

    /// The same, mutable.
    fn side_mut(&mut self) -> &mut dyn DriveSide {
        match self {
            Self::Direct(drives) => drives.as_mut(),
            Self::Can(drives) => drives.as_mut(),
        }
    }
}

impl Drives for Backend {
    fn start(&mut self) -> Result<(), LifecycleError> {
        self.side_mut().start()
    }

    fn stop(&mut self) -> Result<(), LifecycleError> {
        self.side_mut().stop()
    }

    fn recalibrate(&mut self, q: &[f64]) -> Result<(), Refusal> {
        self.side_mut().recalibrate(q)
    }

    fn temperatures(&self) -> Joints {
        self.side().temperatures()
    }

    fn is_operational(&self) -> bool {
        self.side().is_operational()
    }

    fn status(&self) -> DriveStatus {
        self.side().status()
    }

    fn fault_code(&self) -> Option<u8> {
        self.side().fault_code()
    }

    fn fault(&self) -> Option<Text> {
        self.side().fault()
    }

    fn has_fault(&self) -> bool {
        self.side().has_fault()
    }

    fn notice(&self) -> Option<Text> {
        self.side().notice()
    }
}

impl DriveSide for Backend {
    fn receive(&mut self, now: f64) -> bool {
        self.side_mut().receive(now)
    }

    fn measured(&self) -> Joints {
        self.side().measured()
    }

    fn transmit(&mut self, now: f64, elapsed: f64, command: Option<&Joints>) {
        self.side_mut().transmit(now, elapsed, command);
    }
}

impl CanBus for Bus {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        let sent = self.0.try_transmit(frame);
        if sent.is_ok() {
            crate::pcap::can(frame);
            crate::record::can(frame);
        }
        sent
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        self.0.try_receive().inspect(|frame| {
            crate::pcap::can(frame);
            crate::record::can(frame);
        })
    }

    fn state(&self) -> BusState {
        self.0.state()
    }

    fn advance_to(&mut self, now: f64) -> bool {
        self.0.advance_to(now)
    }

    fn recover(&mut self) {
        self.0.recover();
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

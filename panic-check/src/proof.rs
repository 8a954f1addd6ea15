//! The bare-metal entry point that calls everything under proof, and the panic handler that
//! cannot link.

use core::hint::black_box;

use armgate_core::config::{
    BaseConfig, BlendConfig, CartesianLimits, CollisionConfig, DrivesConfig, IkConfig, JointConfig,
    JointDrive, JointType, MotionConfig, RobotConfig, Streaming, ToolConfig, ValidRobot,
    WorkspaceConfig,
};
use armgate_core::cycle::{
    CanDrives, Cycle, Datagram, Dropped, Link, Outgoing, Signing, UnsignedAccess,
};
use armgate_core::drives::{BusState, CanBus, DriveSettings, TxError};
use armgate_protocol::can::CanFrame;
use armgate_protocol::client::signed::{KEY_LEN, SigningKey};
use armgate_protocol::client::{Message, Request};

/// A bus whose every answer is unknown to the optimiser.
struct OpaqueBus;

impl CanBus for OpaqueBus {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        black_box(frame);
        black_box(Ok(()))
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        let id: u16 = black_box(0x581);
        let len: usize = black_box(8);
        let data: [u8; 8] = black_box([0; 8]);
        CanFrame::new(id, data.get(..len).unwrap_or(&[])).ok()
    }

    fn state(&self) -> BusState {
        black_box(BusState::ErrorActive)
    }
}

/// A robot description the optimiser cannot see into; validated as the firmware validates
/// its embedded one.
fn robot() -> Option<ValidRobot> {
    let joint = JointConfig {
        kind: JointType::Revolute,
        alpha: 0.0,
        a: 0.0,
        d: 0.25,
        theta: 0.0,
        beta: 0.0,
        min: -3.0,
        max: 3.0,
        max_velocity: 0.5,
        max_acceleration: 1.0,
        max_rate: 1.0,
        max_jerk: None,
        max_following_error: None,
        drive: JointDrive {
            node_id: 101,
            counts_per_rev: 1 << 20,
            home: 0.0,
            max_speed: 1.0,
            max_acceleration: None,
        },
        link_radius: None,
    };
    let mut joints = heapless::Vec::new();
    for _ in 0..black_box(6) {
        joints.push(joint.clone()).ok()?;
    }
    let config = RobotConfig {
        name: heapless::String::try_from("panic-check").ok()?,
        control_period: 54.0 * 360e-6,
        joints,
        tool: ToolConfig::default(),
        base: BaseConfig::default(),
        drives: DrivesConfig {
            can_bitrate: 500_000,
            unit_mode: 5,
            max_bus_load: 0.7,
            // Opaque: both schedules' code is linked and checked.
            streaming: black_box(Streaming::Pdo),
            pdo_fallback: black_box(true),
            pdo_lead: black_box(Some(3)),
            pdo_lead_raise: black_box(Some(2)),
            time_stamp_every: black_box(Some(2)),
        },
        cartesian: CartesianLimits {
            max_velocity: [0.1; 6],
            max_acceleration: [0.1; 6],
            max_jerk: None,
        },
        workspace: WorkspaceConfig {
            bounds: [-2.0, 2.0, -2.0, 2.0, -2.0, 2.0],
            boxes: heapless::Vec::new(),
        },
        ik: IkConfig::default(),
        blend: BlendConfig::default(),
        motion: MotionConfig::default(),
        collision: CollisionConfig::default(),
    };
    black_box(config).validate().ok()
}

/// The client side, opaque: any datagram of any length may be waiting, any send may fail.
struct OpaqueLink;

impl Link<()> for OpaqueLink {
    fn receive(&mut self) -> Option<Datagram<()>> {
        let datagram: [u8; 64] = black_box([0; 64]);
        let bytes = datagram.get(..black_box(44)).unwrap_or(&[]);
        black_box(true).then(|| Datagram::new(bytes, ()))
    }

    fn send(&mut self, datagram: &Datagram<()>, kind: Outgoing) -> Result<(), Dropped> {
        black_box((datagram, kind));
        black_box(Ok(()))
    }
}

/// Everything under proof, once per loop: the firmware's control cycle (`Cycle::tick`: the
/// drive manager, the command handler's tick and requests, notices) at an arbitrary clock, and
/// one datagram through the parser. `_start` is the linker's default entry, the root from which
/// it keeps code.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn _start() -> ! {
    let Some(robot) = robot() else { halt() };
    let Ok(drives) = CanDrives::started(&robot, &DriveSettings::default(), OpaqueBus) else {
        halt()
    };
    // Signed or not, any policy: the signature checks are under proof too.
    let signing = Signing {
        key: black_box(Some(SigningKey::new(&black_box([7; KEY_LEN])))),
        unsigned: black_box(UnsignedAccess::Read),
    };
    let mut cycle: Cycle<_, ()> = Cycle::new(&robot, drives).with_signing(signing);
    let mut link = OpaqueLink;
    loop {
        black_box(cycle.tick(black_box(0), &mut link).time);
        // A datagram of any length and content through the parser.
        let datagram: [u8; 64] = black_box([0; 64]);
        let bytes = datagram.get(..black_box(31)).unwrap_or(&[]);
        let _ = black_box(Message::new_checked(bytes).and_then(|m| Request::parse(&m)));
    }
}

fn halt() -> ! {
    loop {
        black_box(());
    }
}

/// Defined nowhere: a call to it that survives optimisation fails the link.
#[allow(unsafe_code)]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    unsafe extern "C" {
        fn armgate_panic_path_survived_optimisation() -> !;
    }
    // SAFETY: never runs; the binary links only if no call to this handler is left.
    unsafe { armgate_panic_path_survived_optimisation() }
}

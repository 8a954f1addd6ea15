//! The firmware on Linux: the board's tasks — control, network stack, UDP server, status — on
//! embassy's std executor, with the board's peripherals swapped behind the seams they use:
//!
//! * Ethernet MAC and PHY → a TAP device (`embassy-net-tuntap`), named by `ARMGATE_TAP`
//!   (default `tap0`), which must exist (tools/firmware-e2e.sh creates it inside a
//!   network namespace);
//! * FDCAN1 → the simulated bus of simulated Whistles (as the `sim-drives` build), or with
//!   `ARMGATE_CAN=socketcan:IFACE` a SocketCAN interface (`ARMGATE_PACE_CAN=1`: writes held
//!   to the robot file's bit rate, for a bus without bit timing), e.g. to
//!   `armgate-sim --whistles` on the other side (docs/drives.md, "SocketCAN");
//! * the independent watchdog → [`Watchdog`], which does nothing;
//! * clocks → embassy-time's std driver; the chip's unique id → a fixed one ([`HOST_UID`]);
//! * the robot embedded in flash → the same, unless `ARMGATE_ROBOT_FILE` names a robot file to
//!   load instead, and `ARMGATE_START` (comma-separated joint values) puts the simulated drives'
//!   encoders somewhere else than home, and `ARMGATE_KEY_FILE` / `ARMGATE_ALLOW_UNSIGNED`
//!   replace the build's signing settings: what the end-to-end tests need to run the same
//!   sessions against this and against `armgate-sim`.
//!
//! One difference from the board remains: the control task shares the single executor thread
//! with the network tasks instead of preempting them from an interrupt executor, which changes
//! when ticks start, not what they compute. defmt's log goes nowhere here (a defmt log needs
//! the board's linker script and probe); the start-up line is printed on stderr.

use armgate_core::config::{ValidRobot, load_file};
use armgate_core::cycle::{Cycle, Signing, StateFile};
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::sim::replay::{self, Replay};
use armgate_protocol::client::signed::read_key_file;
use armgate_socketcan::LinuxBus;
use embassy_executor::{Executor, SpawnError, SpawnToken, Spawner};
use embassy_net_tuntap::TunTapDevice;
use static_cell::StaticCell;

use crate::{config, control, drives, net, settings, telemetry};

/// The network driver on the host.
pub type NetDevice = TunTapDevice;

/// The unique id the MAC address and the stack's seed derive from.
const HOST_UID: &[u8] = b"armgate-host";

/// The host has no independent watchdog: the methods the control task calls do nothing.
pub struct Watchdog;

impl Watchdog {
    /// Would start the watchdog.
    pub fn unleash(&mut self) {}

    /// Would feed it.
    pub fn pet(&mut self) {}
}

static EXECUTOR: StaticCell<Executor> = StaticCell::new();
static ROBOT: StaticCell<ValidRobot> = StaticCell::new();

/// defmt needs a global logger; on the host its frames are dropped.
#[defmt::global_logger]
struct NoLog;

// SAFETY: the logger keeps no state, so any sequence of calls is sound.
#[allow(unsafe_code)]
unsafe impl defmt::Logger for NoLog {
    fn acquire() {}
    unsafe fn flush() {}
    unsafe fn release() {}
    unsafe fn write(_bytes: &[u8]) {}
}

defmt::timestamp!("{=u64:us}", embassy_time::Instant::now().as_micros());

/// `defmt::panic!` on the host: the process ends.
#[defmt::panic_handler]
fn defmt_panic() -> ! {
    eprintln!("armgate-firmware: defmt panic (its message is in the defmt log)");
    std::process::abort()
}

/// Starts the tasks; never returns.
pub fn main() {
    let tap = std::env::var("ARMGATE_TAP").unwrap_or_else(|_| "tap0".to_owned());
    let robot: &'static ValidRobot = match load_robot() {
        Ok(robot) => ROBOT.init(robot),
        Err(e) => {
            eprintln!("armgate-firmware: {e}");
            std::process::exit(1);
        }
    };
    let start = match start_joints(robot) {
        Ok(start) => start,
        Err(e) => {
            eprintln!("armgate-firmware: ARMGATE_START: {e}");
            std::process::exit(1);
        }
    };
    // The simulated Whistles' encoders and the undriven joints at the start pose.
    let started = || {
        let mut drives = drives::new(robot, drives::bus::simulated_at(robot, &start));
        drives.manager_mut().place_undriven(&start);
        drives
    };
    if let Ok(replay) = std::env::var("ARMGATE_REPLAY") {
        let drives = started();
        match replay_exchange(robot, drives, &replay) {
            Ok(()) => std::process::exit(0),
            Err(e) => {
                eprintln!("armgate-firmware: ARMGATE_REPLAY: {e}");
                std::process::exit(1);
            }
        }
    }
    let signing = match signing() {
        Ok(signing) => signing,
        Err(e) => {
            eprintln!("armgate-firmware: {e}");
            std::process::exit(1);
        }
    };
    let mut device = match TunTapDevice::new(&tap) {
        Ok(device) => device,
        Err(e) => {
            eprintln!(
                "armgate-firmware: cannot open TAP device {tap}: {e} (create it as root: \
                 `ip tuntap add dev {tap} mode tap && ip link set {tap} up`, or run \
                 tools/firmware-e2e.sh)"
            );
            std::process::exit(1);
        }
    };
    device.set_hardware_address(net::mac_address(HOST_UID));
    let bus = match can_bus(robot, &start) {
        Ok(bus) => bus,
        Err(e) => {
            eprintln!("armgate-firmware: ARMGATE_CAN: {e}");
            std::process::exit(1);
        }
    };
    let bus_text = drives::bus::describe(&bus);
    let mut drives = drives::new(robot, bus);
    drives.manager_mut().place_undriven(&start);
    let (stack, runner) = net::stack(device, HOST_UID);
    let signing_note = match (&signing.0.key, &signing.1) {
        (Some(key), Some(store)) => format!(
            ", signing for controller {} (unsigned: {}; replay state {})",
            key.controller(),
            signing.0.unsigned,
            store.path().display()
        ),
        _ => ", signing off (no key)".to_owned(),
    };
    eprintln!(
        "armgate-firmware (host): {} ({} joints, {:.2} ms period, embedded robot {} bytes, drives: {}) on udp://{}:{}, via {tap}{signing_note}",
        robot.name.as_str(),
        robot.dof(),
        robot.control_period * 1e3,
        config::embedded_len(),
        bus_text,
        settings::ADDRESS,
        settings::PORT
    );
    let executor = EXECUTOR.init(Executor::new());
    executor.run(|spawner| {
        spawn(
            spawner,
            "control",
            control::run(robot, drives, Watchdog, signing),
        );
        spawn(spawner, "network stack", net::runner(runner));
        spawn(spawner, "UDP server", net::udp_server(stack));
        spawn(spawner, "status", telemetry::run(stack));
    })
}

/// The FDCAN seam on Linux: `ARMGATE_CAN` = `sim` (the default: simulated Whistles with their
/// encoders at `start`) or `socketcan:IFACE`, paced with `ARMGATE_PACE_CAN=1`.
fn can_bus(robot: &ValidRobot, start: &[f64]) -> Result<drives::bus::Bus, String> {
    match std::env::var("ARMGATE_CAN").as_deref() {
        Err(_) | Ok("sim") => Ok(drives::bus::simulated_at(robot, start)),
        Ok(choice) => match choice.strip_prefix("socketcan:") {
            Some(iface) if !iface.is_empty() => {
                let paced = std::env::var("ARMGATE_PACE_CAN").is_ok_and(|v| v == "1");
                drives::bus::socketcan(robot, iface, paced)
            }
            _ => Err(format!("`{choice}`: expected sim or socketcan:IFACE")),
        },
    }
}

/// `ARMGATE_REPLAY="FILE TICKS"`: the cycle as the control task builds it, on the recorded
/// exchange, its transcript on stdout (what `armgate-sim --replay` must match).
fn replay_exchange(
    robot: &ValidRobot,
    drives: drives::BoardDrives,
    replay: &str,
) -> Result<(), String> {
    let Some((file, ticks)) = replay.split_once(' ') else {
        return Err("expected `FILE TICKS`".into());
    };
    let ticks: u64 = ticks.trim().parse().map_err(|e| format!("{ticks}: {e}"))?;
    let text = std::fs::read_to_string(file).map_err(|e| format!("{file}: {e}"))?;
    let recording = Replay::parse(&text).map_err(|e| format!("{file}: {e}"))?;
    let mut cycle: Cycle<drives::BoardDrives, ()> = Cycle::new(robot, drives);
    let transcript = recording.run(&mut cycle, ticks, |drives| match drives.bus() {
        LinuxBus::Simulated(bus) => replay::can_drives(drives.manager(), bus),
        LinuxBus::SocketCan(_) => "SocketCAN".into(),
    });
    print!("{transcript}");
    Ok(())
}

/// Where the replay reservation is kept across restarts on Linux: a state file.
pub type ReplayStore = Option<StateFile>;

/// The build's signing settings, or the key file `ARMGATE_KEY_FILE` names, the controller id
/// `ARMGATE_CONTROLLER_ID` gives and the access `ARMGATE_ALLOW_UNSIGNED` gives (no, read, all)
/// at run time; with a key, the replay state file `ARMGATE_STATE_FILE` names (default: as
/// `armgate-sim`'s, by the controller's id).
fn signing() -> Result<(Signing, ReplayStore), String> {
    let mut signing = settings::signing();
    let controller = match std::env::var("ARMGATE_CONTROLLER_ID") {
        Ok(text) => text
            .parse()
            .map_err(|e| format!("ARMGATE_CONTROLLER_ID: `{text}`: {e}"))?,
        Err(_) => settings::CONTROLLER_ID,
    };
    if let Some(path) = std::env::var_os("ARMGATE_KEY_FILE") {
        let key = read_key_file(std::path::Path::new(&path))
            .map_err(|e| format!("ARMGATE_KEY_FILE: {e}"))?;
        signing.key = Some(key);
    }
    signing.key = signing.key.map(|k| k.for_controller(controller));
    if let Ok(text) = std::env::var("ARMGATE_ALLOW_UNSIGNED") {
        signing.unsigned = text
            .parse()
            .map_err(|e| format!("ARMGATE_ALLOW_UNSIGNED: `{text}`: {e}"))?;
    }
    let store = match signing.key {
        None => None,
        Some(_) => {
            let path = std::env::var_os("ARMGATE_STATE_FILE").map_or_else(
                || StateFile::default_path(controller),
                std::path::PathBuf::from,
            );
            Some(StateFile::open(&path).map_err(|e| format!("ARMGATE_STATE_FILE: {e}"))?)
        }
    };
    Ok((signing, store))
}

/// The embedded robot, or the one `ARMGATE_ROBOT_FILE` names.
fn load_robot() -> Result<ValidRobot, String> {
    match std::env::var_os("ARMGATE_ROBOT_FILE") {
        Some(path) => load_file(&path).map_err(|e| format!("{}: {e}", path.display())),
        None => {
            config::load().map_err(|_| "the embedded robot does not decode or validate".to_owned())
        }
    }
}

/// The joints `ARMGATE_START` gives (default: the drives' home positions).
fn start_joints(robot: &ValidRobot) -> Result<Joints, String> {
    let home = robot.home();
    let Ok(text) = std::env::var("ARMGATE_START") else {
        return Ok(home);
    };
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>().map_err(|e| format!("`{v}`: {e}")))
        .collect::<Result<_, _>>()?;
    Chain::new(robot)
        .check(&values)
        .map_err(|e| format!("{e} (the robot has {} joints)", robot.dof()))
}

/// Spawns a task, or ends the process saying which one could not be.
fn spawn<S>(spawner: Spawner, name: &str, task: Result<SpawnToken<S>, SpawnError>) {
    match task {
        Ok(task) => spawner.spawn(task),
        Err(e) => {
            eprintln!("armgate-firmware: cannot spawn the {name} task: {e:?}");
            std::process::exit(1);
        }
    }
}

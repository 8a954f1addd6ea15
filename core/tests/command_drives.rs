//! The command handler over the drive manager and simulated Whistles on a virtual bus: what
//! refusals and the status request `SQ` say while the drives start, run, fault and stop
//! (docs/protocol.md).
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// The seed deployed rounded angles such as 1.5708.
#![allow(clippy::approx_constant)]

mod common;

use armgate_core::command::{CommandHandler, DriveStatus, Drives, Motion};
use armgate_core::cycle::CanDrives;
use armgate_core::drives::DriveSettings;
use armgate_core::motion::Mode;
use armgate_core::sim::VirtualBus;

struct Rig {
    handler: CommandHandler,
    drives: CanDrives<VirtualBus>,
    period: f64,
    now: f64,
    notices: Vec<String>,
}

impl Rig {
    /// ranger-mk1 at home, its drives just told to start (as at power-up), one tick done.
    fn new() -> Self {
        let config = common::robot("ranger-mk1");
        let bus = VirtualBus::for_robot(&config);
        let drives = CanDrives::started(&config, &DriveSettings::default(), bus).unwrap();
        let mut rig = Self {
            handler: CommandHandler::new(&config),
            drives,
            period: config.control_period,
            now: 0.0,
            notices: Vec::new(),
        };
        rig.tick();
        rig
    }

    /// One cycle as the firmware and armgate-sim run it; the first at t = 0.
    fn tick(&mut self) {
        let (manager, bus) = self.drives.split_mut();
        bus.advance(self.now).unwrap();
        manager.receive(bus);
        let measured = manager.measured();
        let out = self
            .handler
            .tick(self.now, &measured, &mut self.drives)
            .unwrap();
        let (manager, bus) = self.drives.split_mut();
        manager.transmit(self.now, out.command.as_ref(), bus);
        while let Some(text) = self.handler.next_notice() {
            self.notices.push(text.as_str().to_owned());
        }
        self.now += self.period;
    }

    fn ticks_until(&mut self, done: impl Fn(&Self) -> bool) {
        for _ in 0..1000 {
            if done(self) {
                return;
            }
            self.tick();
        }
        panic!("never happened; drives {:?}", self.drives.status());
    }

    fn request(&mut self, cmd: &str, values: [f32; 7], index: u8) -> [u8; 31] {
        let mut d = [0u8; 31];
        d[..2].copy_from_slice(cmd.as_bytes());
        for (k, v) in values.iter().enumerate() {
            d[2 + 4 * k..6 + 4 * k].copy_from_slice(&v.to_le_bytes());
        }
        d[30] = index;
        self.handler.handle(&d, &mut self.drives)
    }

    fn text(&mut self, cmd: &str, values: [f32; 7]) -> String {
        let reply = self.request(cmd, values, 0);
        let end = reply.iter().position(|b| *b == 0).unwrap();
        String::from_utf8(reply[..end].to_vec()).unwrap()
    }

    fn status(&mut self) -> [f32; 7] {
        let reply = self.request("SQ", [0.0; 7], 0);
        assert_eq!((&reply[..2], reply[30]), (&b"QS"[..], 0));
        core::array::from_fn(|k| {
            f32::from_le_bytes(reply[2 + 4 * k..6 + 4 * k].try_into().unwrap())
        })
    }
}

const CARTESIAN: [f32; 7] = [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
/// A goal 5 cm above ranger-mk1's home pose, same orientation (yaw −π/2), at least 1 s.
const UP: [f32; 7] = [0.0, 0.02, 0.716, 0.0, 0.0, -1.5708, 1.0];

#[test]
fn sq_reports_booting_drives_in_literal_bytes() {
    let mut rig = Rig::new();
    // Mode 0, drives starting (1), no fault, 6 joints, holding, 0 refused, 0 s.
    let mut expected = [0u8; 31];
    expected[..2].copy_from_slice(b"QS");
    expected[6..10].copy_from_slice(&[0x00, 0x00, 0x80, 0x3F]); // f1 = 1.0
    expected[14..18].copy_from_slice(&[0x00, 0x00, 0xC0, 0x40]); // f3 = 6.0
    assert_eq!(rig.request("SQ", [0.0; 7], 0), expected);
    let mut name = [0u8; 31];
    name[..12].copy_from_slice(b"QSranger-mk1");
    name[30] = 1;
    assert_eq!(rig.request("SQ", [0.0; 7], 1), name);
    let mut bad = [0u8; 31];
    bad[..21].copy_from_slice(b"ER24 Cmd SQ bad index");
    assert_eq!(rig.request("SQ", [0.0; 7], 8), bad);
    // The refusal counted, and the snapshot a shell reads agrees with the wire.
    let status = rig.handler.status(&rig.drives);
    assert_eq!(
        (status.mode, status.drives, status.fault, status.joints),
        (Mode::Off, DriveStatus::Starting, None, 6)
    );
    assert_eq!((status.motion, status.refused), (Motion::Holding, 1));
    assert_eq!(rig.status()[5], 1.0);
}

#[test]
fn refusals_follow_the_drives_through_start_fault_and_stop() {
    let mut rig = Rig::new();
    assert_eq!(&rig.request("CM", CARTESIAN, 0)[..2], b"MC");
    assert_eq!(&rig.request("GT", UP, 0)[..2], b"TG");
    // Booting: BG says why, ON is accepted (already starting), OF could stop it.
    assert_eq!(rig.text("BG", [0.0; 7]), "ER20 Cmd BG drives starting");
    assert_eq!(&rig.request("ON", [0.0; 7], 0)[..2], b"NO");
    rig.ticks_until(|r| r.drives.status() == DriveStatus::Running);
    assert_eq!(rig.status()[..3], [2.0, 2.0, 0.0]);
    assert_eq!(rig.text("ON", [0.0; 7]), "ER11 Arm already on");

    // A drive stops answering: ER30 once, then every motion request names the fault.
    rig.drives.bus_mut().drive_mut(103).unwrap().faults.silent = true;
    rig.ticks_until(|r| r.drives.status() == DriveStatus::Faulted);
    assert_eq!(rig.notices, ["ER30 J3 drive not answering"]);
    assert_eq!(rig.status()[1..3], [4.0, 30.0]);
    assert_eq!(rig.text("BG", [0.0; 7]), "ER20 Cmd BG drive fault 30");
    assert_eq!(rig.text("OF", [0.0; 7]), "ER10 Arm stopped by fault");

    // ON clears the fault; once running, the move is accepted and SQ shows it.
    rig.drives.bus_mut().drive_mut(103).unwrap().faults.silent = false;
    assert_eq!(&rig.request("ON", [0.0; 7], 0)[..2], b"NO");
    rig.ticks_until(|r| r.drives.status() == DriveStatus::Running);
    assert_eq!(rig.status()[2], 0.0);
    assert_eq!(&rig.request("BG", [0.0; 7], 0)[..2], b"GB");
    rig.tick();
    assert_eq!(rig.status()[4], 2.0, "a Cartesian move runs");
    assert_eq!(rig.text("BG", [0.0; 7]), "ER20 Cmd BG busy");

    // OF while moving: the arm decelerates (SQ motion 6, index 2 cause 3),
    // then the drives stop.
    assert_eq!(&rig.request("OF", [0.0; 7], 0)[..2], b"FO");
    assert_eq!(rig.status()[1], 2.0);
    assert_eq!(rig.status()[4], 6.0);
    assert_eq!(rig.text("BG", [0.0; 7]), "ER20 Cmd BG busy");
    rig.ticks_until(|r| r.drives.status() != DriveStatus::Running);
    assert_eq!(rig.status()[1], 3.0);
    assert_eq!(rig.text("BG", [0.0; 7]), "ER20 Cmd BG drives stopping");
    assert_eq!(rig.text("ON", [0.0; 7]), "ER11 Arm still stopping");
    assert_eq!(rig.text("OF", [0.0; 7]), "ER10 Arm already stopping");
    rig.ticks_until(|r| r.drives.status() == DriveStatus::Off);
    assert_eq!(rig.text("BG", [0.0; 7]), "ER20 Cmd BG drives off");
    assert_eq!(rig.text("OF", [0.0; 7]), "ER10 Arm already off");
}

#[test]
fn recalibration_waits_until_the_drives_settle_after_mode_off() {
    let mut rig = Rig::new();
    rig.ticks_until(|r| r.drives.status() == DriveStatus::Running);
    let here: [f32; 7] = [1.5708, 0.0, 1.5708, 0.0, 1.5708, 0.0, 0.0];
    assert_eq!(&rig.request("CM", CARTESIAN, 0)[..2], b"MC");
    rig.tick();
    assert_eq!(rig.text("RC", here), "ER20 Cmd RC needs mode 0");
    assert_eq!(&rig.request("ST", [0.0; 7], 0)[..2], b"TS");
    assert_eq!(&rig.request("CM", [0.0; 7], 0)[..2], b"MC");
    // The last tick still streamed a set-point.
    assert_eq!(rig.text("RC", here), "ER20 Cmd RC drives settling");
    rig.tick();
    assert_eq!(&rig.request("RC", here, 0)[..2], b"CR");
}

/// `SQ` index 2 names the cause of each stop that ends in a hold (docs/safety.md): a mode
/// change while moving (2), a joint-rate stream whose requests stopped (6), and the client
/// watchdog (8, with its notice); a new motion clears it.
#[test]
fn sq_index_2_names_mode_change_stream_timeout_and_silent_client_stops() {
    let mut rig = Rig::new();
    rig.ticks_until(|r| r.drives.status() == DriveStatus::Running);
    let cause = |rig: &mut Rig| {
        let reply = rig.request("SQ", [0.0; 7], 2);
        assert_eq!((&reply[..2], reply[30]), (&b"QS"[..], 2));
        f32::from_le_bytes(reply[2..6].try_into().unwrap())
    };
    let at_rest = |r: &Rig| r.handler.status(&r.drives).motion == Motion::Holding;

    // CM while a Cartesian move runs: decelerates (f4 = 6), then the joint mode holds.
    assert_eq!(&rig.request("CM", CARTESIAN, 0)[..2], b"MC");
    assert_eq!(&rig.request("GT", UP, 0)[..2], b"TG");
    assert_eq!(&rig.request("BG", [0.0; 7], 0)[..2], b"GB");
    for _ in 0..10 {
        rig.tick();
    }
    assert_eq!(rig.status()[4], 2.0, "a Cartesian move runs");
    assert_eq!(cause(&mut rig), 0.0, "a running move has no cause in force");
    let joint = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    assert_eq!(&rig.request("CM", joint, 0)[..2], b"MC");
    assert_eq!(rig.status()[4], 6.0);
    rig.ticks_until(at_rest);
    assert_eq!(cause(&mut rig), 2.0);

    // One jW and then silence: the stream ramps to rest by itself.
    let rates = [0.0, 0.0, 0.0, 0.0, 0.0, 0.05, 0.0];
    assert_eq!(&rig.request("jW", rates, 0)[..2], b"Wj");
    rig.tick();
    assert_eq!(cause(&mut rig), 0.0, "a new motion clears the cause");
    rig.ticks_until(at_rest);
    assert_eq!(cause(&mut rig), 6.0);

    // A move whose client asked for a 200 ms watchdog and then said nothing.
    assert_eq!(&rig.request("CM", CARTESIAN, 0)[..2], b"MC");
    assert_eq!(&rig.request("GT", UP, 0)[..2], b"TG");
    assert_eq!(&rig.request("BG", [0.0; 7], 0)[..2], b"GB");
    let watchdog = [200.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    assert_eq!(&rig.request("WD", watchdog, 0)[..2], b"DW");
    rig.notices.clear();
    rig.ticks_until(|r| !r.notices.is_empty());
    assert_eq!(rig.notices, ["ER41 client silent 200 ms"]);
    rig.ticks_until(at_rest);
    assert_eq!(cause(&mut rig), 8.0);
}

//! The line check of `BG` and `VE` (each point of a line checked for the whole arm, issue 35)
//! runs in slices of at most `LINE_SLICE` work (a few points), one a tick in the cycle's
//! planning slot, as `KG`'s search does: the request is answered when the check ends, with the
//! answer the whole check gives at once (on every robot, over many seeded lines and sequences); other clients
//! are served meanwhile, the checking client's next requests wait behind it, and a stop from
//! anyone cancels it (`ER42`).
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use std::collections::VecDeque;
use std::f64::consts::FRAC_PI_2;
use std::net::SocketAddr;

use armgate_core::config::ValidRobot;
use armgate_core::cycle::{Cycle, Datagram, Dropped, LINE_SLICE, Link, Outgoing};
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::math;
use armgate_core::rng::SplitMix64;
use armgate_core::sim::{ArmModel, IdealArm, SimulatedDrives};
use common::clients::reply_text;
use common::datagram;

const CARTESIAN: [f32; 7] = [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
const NONE: [f32; 7] = [0.0; 7];
/// Lines (and sequences) per robot.
const LINES: usize = 24;
/// Ticks a check may take at most: every solve of the budget, one a tick, and more.
const MAX_TICKS: usize = 2_000;

fn a() -> SocketAddr {
    SocketAddr::from(([192, 168, 1, 2], 5000))
}

fn b() -> SocketAddr {
    SocketAddr::from(([192, 168, 1, 3], 6000))
}

/// Requests for the next tick; the replies, whole.
#[derive(Default)]
struct Raw {
    requests: VecDeque<Datagram<SocketAddr>>,
    replies: Vec<(SocketAddr, [u8; 31])>,
}

impl Link<SocketAddr> for Raw {
    fn receive(&mut self) -> Option<Datagram<SocketAddr>> {
        self.requests.pop_front()
    }

    fn send(&mut self, datagram: &Datagram<SocketAddr>, kind: Outgoing) -> Result<(), Dropped> {
        if kind == Outgoing::Reply {
            let mut bytes = [0; 31];
            bytes.copy_from_slice(&datagram.payload()[..31]);
            self.replies.push((datagram.peer, bytes));
        }
        Ok(())
    }
}

#[derive(Clone)]
struct Rig {
    cycle: Cycle<SimulatedDrives, SocketAddr>,
}

impl Rig {
    /// The arm at `q`, in Cartesian mode.
    fn new(config: &ValidRobot, q: Joints) -> Self {
        let drives = SimulatedDrives::new(ArmModel::Ideal(IdealArm::new(q)));
        let mut rig = Self {
            cycle: Cycle::new(config, drives),
        };
        rig.tick(&mut Raw::default());
        assert_eq!(
            &rig.cycle.answer(&datagram("CM", CARTESIAN, 0), a())[..2],
            b"MC"
        );
        rig
    }

    fn tick(&mut self, link: &mut Raw) {
        let due = self.cycle.next_due_us();
        self.cycle.tick(due, link).step.unwrap();
    }

    /// `cmd` from A between ticks, its work done at once: the whole check's answer.
    fn at_once(&mut self, cmd: &str, values: [f32; 7], index: u8) -> [u8; 31] {
        self.cycle.answer(&datagram(cmd, values, index), a())
    }

    /// `cmd` from A through the ticks: its answer and the ticks it took.
    fn ticked(&mut self, cmd: &str, values: [f32; 7]) -> ([u8; 31], usize) {
        let mut link = Raw::default();
        link.requests
            .push_back(Datagram::new(&datagram(cmd, values, 0), a()));
        for ticks in 1..=MAX_TICKS {
            self.tick(&mut link);
            if let Some((_, reply)) = link.replies.pop() {
                assert!(link.replies.is_empty());
                return (reply, ticks);
            }
        }
        panic!("no answer to {cmd} within {MAX_TICKS} ticks");
    }

    fn joints(&mut self) -> Vec<f32> {
        let reply = self.cycle.answer(&datagram("jP", NONE, 0), b());
        common::floats(&reply).to_vec()
    }
}

/// A configuration drawn within the middle half of every joint's range.
fn configuration(chain: &Chain, rng: &mut SplitMix64) -> Joints {
    let mut q = chain.mid_range();
    for ((v, lo), hi) in q.iter_mut().zip(chain.min()).zip(chain.max()) {
        *v += 0.25 * (hi - lo) * (2.0 * rng.next_f64() - 1.0);
    }
    q
}

/// `GT`'s or `VP`'s values for a pose up to 30 cm and 0.6 rad (per angle) from `from`.
fn nearby(from: &math::Frame, rng: &mut SplitMix64) -> [f32; 7] {
    let mut r = || 2.0 * rng.next_f64() - 1.0;
    let p = from.translation.vector;
    let [roll, pitch, yaw] = math::rpy(&from.rotation);
    [
        p.x + 0.3 * r(),
        p.y + 0.3 * r(),
        p.z + 0.3 * r(),
        roll + 0.6 * r(),
        pitch + 0.6 * r(),
        yaw + 0.6 * r(),
        0.0,
    ]
    .map(|v| v as f32)
}

/// Over seeded lines (`GT`, `BG`) and two-leg sequences (`VP` 0, `VP` 1, `VE`) on every
/// robot, from random configurations: the cycle's answer, after the check ran a slice a tick,
/// is the whole check's answer at once, byte for byte (the planned duration included); a
/// check of more than `LINE_SLICE` work takes more than one tick.
#[test]
fn sliced_checks_answer_as_the_whole_check_on_every_robot() {
    let (mut accepted, mut refused, mut sliced) = (0, 0, 0);
    for (name, config) in common::all_robots() {
        let chain = Chain::new(&config);
        let mut rng = SplitMix64::new(0x5_11CE);
        for k in 0..LINES {
            let q = configuration(&chain, &mut rng);
            let start = chain.forward(&q).unwrap();
            let mut rig = Rig::new(&config, q);
            let cmd = if k % 3 == 2 {
                let first = nearby(&start, &mut rng);
                let second = nearby(&start, &mut rng);
                let vp0 = rig.at_once("VP", first, 0);
                let vp1 = rig.at_once("VP", second, 1);
                if &vp0[..2] != b"PV" || &vp1[..2] != b"PV" {
                    continue;
                }
                "VE"
            } else {
                if &rig.at_once("GT", nearby(&start, &mut rng), 0)[..2] != b"TG" {
                    continue;
                }
                "BG"
            };
            let mut whole = rig.clone();
            let expected = whole.at_once(cmd, NONE, 0);
            let (answer, ticks) = rig.ticked(cmd, NONE);
            assert_eq!(
                reply_text(&answer),
                reply_text(&expected),
                "{name}, line {k}: {cmd}"
            );
            assert_eq!(answer, expected, "{name}, line {k}: {cmd}");
            if expected.starts_with(b"ER") {
                refused += 1;
            } else {
                accepted += 1;
                // The move started, as the whole check's did.
                let moving = |r: &Rig| r.cycle.handler().controller().is_moving();
                assert!(moving(&rig) && moving(&whole), "{name}, line {k}");
            }
            sliced += usize::from(ticks > 1);
        }
    }
    println!("{accepted} accepted, {refused} refused, {sliced} over more than one tick");
    assert!(
        accepted > 20 && refused > 20,
        "{accepted} accepted, {refused} refused"
    );
    assert!(sliced > 20, "{sliced} checks took more than one tick");
}

/// ranger-mk1 from a well-conditioned start, with a goal 25 cm away: a check of many points.
fn long_line() -> Rig {
    let config = common::robot("ranger-mk1");
    let q = Joints::from_slice(&[FRAC_PI_2, 0.8, 0.5, 0.5, 1.5, 0.5]).unwrap();
    let start = Chain::new(&config).forward(&q).unwrap();
    let mut rig = Rig::new(&config, q);
    let p = start.translation.vector;
    let [roll, pitch, yaw] = math::rpy(&start.rotation);
    let goal = [
        p.x + 0.15,
        p.y - 0.15,
        p.z + 0.1,
        roll,
        pitch,
        yaw + 0.2,
        0.0,
    ];
    assert_eq!(&rig.at_once("GT", goal.map(|v| v as f32), 0)[..2], b"TG");
    rig
}

/// While A's `BG` is checked, a slice a tick, B's reads are answered every tick and A's next
/// request waits behind its `BG`, answered after it.
#[test]
fn another_client_is_served_while_a_line_is_checked() {
    let mut rig = long_line();
    let mut link = Raw::default();
    for (cmd, client) in [("BG", a()), ("jP", a())] {
        link.requests
            .push_back(Datagram::new(&datagram(cmd, NONE, 0), client));
    }
    let mut ticks = 0;
    let answer = loop {
        link.requests
            .push_back(Datagram::new(&datagram("SQ", NONE, 0), b()));
        rig.tick(&mut link);
        ticks += 1;
        assert!(ticks < MAX_TICKS, "no answer");
        let replies: Vec<_> = link.replies.drain(..).collect();
        assert!(
            replies.iter().any(|(c, r)| *c == b() && &r[..2] == b"QS"),
            "B's status waited"
        );
        let to_a: Vec<_> = replies.iter().filter(|(c, _)| *c == a()).collect();
        if let Some((_, first)) = to_a.first() {
            // A's jP only after its BG.
            assert_eq!(&first[..2], b"GB", "{}", reply_text(first));
            break to_a.get(1).map(|(_, r)| *r);
        }
    };
    println!("BG answered after {ticks} ticks (line work {LINE_SLICE} a tick)");
    assert!(ticks > 2, "the check took {ticks} ticks");
    let jp = answer.unwrap_or_else(|| {
        rig.tick(&mut link);
        link.replies.pop().unwrap().1
    });
    assert_eq!(&jp[..2], b"Pj");
}

/// A stop from another client cancels a `BG` still being checked: `ER42`, and the arm stays.
#[test]
fn a_stop_cancels_a_line_check_in_progress() {
    let mut rig = long_line();
    let before = rig.joints();
    let mut link = Raw::default();
    link.requests
        .push_back(Datagram::new(&datagram("BG", NONE, 0), a()));
    rig.tick(&mut link);
    assert!(link.replies.is_empty(), "still checking");
    link.requests
        .push_back(Datagram::new(&datagram("ST", NONE, 0), b()));
    rig.tick(&mut link);
    let replies: Vec<_> = link
        .replies
        .drain(..)
        .map(|(c, r)| (c, reply_text(&r)))
        .collect();
    assert_eq!(
        replies,
        [
            (a(), "ER42 Cmd BG cancelled by ST".to_string()),
            (b(), "TS".to_string())
        ]
    );
    for _ in 0..100 {
        rig.tick(&mut link);
    }
    assert!(link.replies.is_empty(), "nothing more");
    assert_eq!(rig.joints(), before);
}

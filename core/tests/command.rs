//! The command handler: literal datagrams in, literal replies out (spec §2, docs/protocol.md).
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// The seed deployed rounded angles such as 1.5708.
#![allow(clippy::approx_constant)]

mod common;
mod drives_rig;

use common::{datagram, floats};

use armgate_core::command::Drives;
use armgate_core::config::ValidRobot;
use armgate_core::cycle::Cycle;
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::math;
use armgate_core::rng::SplitMix64;
use armgate_core::sim::IdealArm;
use armgate_core::sim::{ArmModel, SimulatedDrives};

/// The core's cycle with a simulated arm; requests answered between ticks, notices kept with
/// the tick's time.
struct Rig {
    cycle: Cycle<SimulatedDrives, ()>,
    client: drives_rig::Client,
    now: f64,
}

impl Rig {
    fn new(config: &ValidRobot, q0: &[f64]) -> Self {
        let arm = IdealArm::new(Joints::from_slice(q0).unwrap());
        let mut rig = Self {
            cycle: Cycle::new(config, SimulatedDrives::new(ArmModel::Ideal(arm))),
            client: drives_rig::Client::default(),
            now: 0.0,
        };
        rig.tick();
        rig
    }

    fn tick(&mut self) {
        let due = self.cycle.next_due_us();
        let outcome = self.cycle.tick(due, &mut self.client);
        outcome.step.unwrap();
        self.now = outcome.time;
    }

    /// Ticks for `seconds`.
    fn run_for(&mut self, seconds: f64) {
        let until = self.now + seconds;
        while self.now < until {
            self.tick();
        }
    }

    fn send(&mut self, datagram: &[u8]) -> [u8; 31] {
        self.cycle.answer(datagram, ())
    }

    fn request(&mut self, cmd: &str, values: [f32; 7], index: u8) -> [u8; 31] {
        self.send(&datagram(cmd, values, index))
    }

    /// The text of an ER/WN reply, or panics.
    fn text(&mut self, cmd: &str, values: [f32; 7], index: u8) -> String {
        text_of(&self.request(cmd, values, index))
    }
}

fn text_of(reply: &[u8; 31]) -> String {
    let end = reply.iter().position(|b| *b == 0).unwrap();
    assert!(
        reply[end..].iter().all(|b| *b == 0),
        "not zero-filled: {reply:?}"
    );
    String::from_utf8(reply[..end].to_vec()).unwrap()
}

const MK1_READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];

fn mk1() -> Rig {
    Rig::new(&common::robot("ranger-mk1"), &MK1_READY)
}

#[test]
fn worked_example_gt_and_its_reply() {
    let mut rig = mk1();
    // spec §2.9: GT to (0.5, 0.2, 0.1), RPY 0, T = 5 s.
    let gt: [u8; 31] = [
        0x47, 0x54, 0x00, 0x00, 0x00, 0x3F, 0xCD, 0xCC, 0x4C, 0x3E, 0xCD, 0xCC, 0xCC, 0x3D, 0, 0,
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x00, 0xA0, 0x40, 0x00,
    ];
    let mut expected = gt;
    expected[..2].copy_from_slice(b"TG");
    assert_eq!(rig.send(&gt), expected);
}

#[test]
fn worked_examples_cm_bg_and_vp() {
    let mut rig = mk1();
    let cm2: [u8; 31] =
        core::array::from_fn(|k| [0x43, 0x4D, 0, 0, 0, 0x40].get(k).copied().unwrap_or(0));
    let mut mc2 = cm2;
    mc2[..2].copy_from_slice(b"MC");
    assert_eq!(rig.send(&cm2), mc2);
    rig.tick();
    // BG before any goal is rejected, zero-filled.
    assert_eq!(rig.text("BG", [0.0; 7], 0), "ER20 Cmd BG no goal");
    // A reachable goal 5 cm from the current pose, then BG → `47 42`, f6 the planned duration
    // (5 cm at ranger-mk1's Cartesian limits: 4.47 s), zeros elsewhere.
    let ps = floats(&rig.request("PS", [0.0; 7], 0));
    let reply = rig.request(
        "GL",
        [ps[0] + 0.05, ps[1], ps[2], ps[3], ps[4], ps[5], ps[6]],
        0,
    );
    assert_eq!(&reply[..2], b"LG");
    let bg = rig.request("BG", [0.0; 7], 0);
    let planned = floats(&bg)[6];
    assert!((4.4..4.6).contains(&planned), "{planned}");
    let mut gb = [0u8; 31];
    gb[..2].copy_from_slice(&[0x47, 0x42]);
    gb[26..30].copy_from_slice(&planned.to_le_bytes());
    assert_eq!(bg, gb);
    // The same datagram again within a second is a resend: its reply again, not carried out
    // twice. Later, while still moving, BG is rejected.
    rig.tick();
    assert_eq!(rig.request("BG", [0.0; 7], 0), gb);
    rig.run_for(1.1);
    assert_eq!(rig.text("BG", [0.0; 7], 0), "ER20 Cmd BG busy");
    // VP via point 3 = (0.5, −0.2, 0.4), yaw −1.5708, T = 2 (spec §2.9).
    let vp: [u8; 31] = [
        0x56, 0x50, 0x00, 0x00, 0x00, 0x3F, 0xCD, 0xCC, 0x4C, 0xBE, 0xCD, 0xCC, 0xCC, 0x3E, 0, 0,
        0, 0, 0, 0, 0, 0, 0xF9, 0x0F, 0xC9, 0xBF, 0x00, 0x00, 0x00, 0x40, 0x03,
    ];
    let pv = rig.send(&vp);
    assert_eq!(&pv[..2], b"PV");
    assert_eq!(pv[30], 3);
    let values = floats(&pv);
    assert_eq!(&values[..3], &[0.5, -0.2, 0.4]);
    assert!((values[5] + 1.5708).abs() < 1e-6 && values[3].abs() < 1e-6);
    assert_eq!(values[6], 2.0);
}

#[test]
fn fixed_seed_defects_vc_rc_and_stale_bytes() {
    let mut rig = mk1();
    let cv = rig.request("VC", [0.0; 7], 0);
    assert_eq!(&cv[..2], b"CV");
    assert!(cv[2..].iter().all(|b| *b == 0));
    // RC answers CR (the seed sent nothing) and takes effect.
    let target = [1.0f32, 0.5, -0.3, 0.1, 1.7, 0.2];
    let mut values = [0.0; 7];
    values[..6].copy_from_slice(&target);
    assert_eq!(&rig.request("RC", values, 0)[..2], b"CR");
    rig.tick();
    let jp = floats(&rig.request("jP", [0.0; 7], 0));
    for (a, b) in jp.iter().zip(target) {
        assert!((a - b).abs() < 1e-6);
    }
    // Angles outside the joint limits are refused (joint 5's range is [0.785, 3.926]).
    let mut outside = values;
    outside[4] = 0.0;
    assert_eq!(rig.text("RC", outside, 0), "ER26 Cmd RC j5 < 0.785");
    // RC outside mode 0 is refused.
    rig.request("CM", [1.0, 0., 0., 0., 0., 0., 0.], 0);
    assert_eq!(rig.text("RC", values, 0), "ER20 Cmd RC needs mode 0");
    // jG's f6 is zero, not stale.
    let mut jg = [0.0f32; 7];
    jg[..6].copy_from_slice(&[1.5708, 0.6, -0.4, 0.2, 1.8, 0.1]);
    jg[6] = 9.0;
    assert_eq!(floats(&rig.request("jG", jg, 0))[6], 0.0);
}

#[test]
fn short_long_and_unknown_datagrams() {
    let mut rig = mk1();
    assert_eq!(text_of(&rig.send(&[])), "ER01 Msg ?? undersized.");
    assert_eq!(text_of(&rig.send(b"P")), "ER01 Msg P? undersized.");
    assert_eq!(text_of(&rig.send(b"PS")), "ER01 Msg PS undersized.");
    assert_eq!(text_of(&rig.send(&[b'P'; 29])), "ER01 Msg PP undersized.");
    // 30 bytes: accepted with index 0.
    assert_eq!(&rig.send(&datagram("PS", [0.0; 7], 0)[..30])[..2], b"SP");
    // 32 and 100 bytes: truncated to 31.
    let mut long = datagram("TM", [0.0; 7], 0).to_vec();
    long.resize(100, 0xAA);
    assert_eq!(&rig.send(&long[..32])[..2], b"MT");
    assert_eq!(&rig.send(&long)[..2], b"MT");
    assert_eq!(rig.text("XY", [0.0; 7], 0), "ER00 Cmd XY not understood");
    assert_eq!(rig.text("bg", [0.0; 7], 0), "ER00 Cmd bg not understood");
}

#[test]
fn bad_numbers_indices_and_goals_get_their_texts() {
    let mut rig = mk1();
    for field in 0..7 {
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let mut v = [0.0f32, 0.6, 1.0, 0.0, 0.0, 0.0, 1.0];
            v[field] = bad;
            assert_eq!(
                rig.text("GL", v, 0),
                "ER23 Cmd GL bad number",
                "GL f{field}"
            );
            let mut v = [0.0f32, 0.6, 1.0, 0.0, 0.0, 0.0, 1.0];
            v[field] = bad;
            assert_eq!(
                rig.text("GT", v, 0),
                "ER23 Cmd GT bad number",
                "GT f{field}"
            );
            assert_eq!(
                rig.text("VP", v, 2),
                "ER23 Cmd VP bad number",
                "VP f{field}"
            );
            assert_eq!(
                rig.text("jV", v, 2),
                "ER23 Cmd jV bad number",
                "jV f{field}"
            );
        }
    }
    assert_eq!(
        rig.text("CM", [f32::NAN, 0., 0., 0., 0., 0., 0.], 0),
        "ER23 Cmd CM bad number"
    );
    assert_eq!(
        rig.text("CM", [3.0, 0., 0., 0., 0., 0., 0.], 0),
        "ER23 Cmd CM bad number"
    );
    assert_eq!(
        rig.text("GL", [0.0, 0.6, 1.0, 0.0, 0.0, 0.0, 0.0], 0),
        "ER23 Cmd GL bad number"
    );
    let via = [0.0f32, 0.6, 1.0, 0.0, 0.0, 0.0, 1.0];
    assert_eq!(rig.text("VP", via, 20), "ER24 Cmd VP bad index");
    assert_eq!(rig.text("VP", via, 255), "ER24 Cmd VP bad index");
    let q = [1.5708f32, 0.6, -0.4, 0.2, 1.8, 0.1, 1.0];
    assert_eq!(rig.text("jV", q, 20), "ER24 Cmd jV bad index");
    assert_eq!(rig.text("jV", q, 255), "ER24 Cmd jV bad index");
    assert_eq!(&rig.request("jV", q, 19)[..2], b"Vj");
    // Inside the column around the base, and outside the bounds.
    assert_eq!(
        rig.text("GT", [0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 1.0], 0),
        "ER25 Cmd GT outside workspace"
    );
    assert_eq!(
        rig.text("GT", [9.0, 0.0, 0.2, 0.0, 0.0, 0.0, 1.0], 0),
        "ER25 Cmd GT outside workspace"
    );
    // Joint 5 below its 0.785 limit.
    assert_eq!(
        rig.text("jG", [1.5708, 0.6, -0.4, 0.2, 0.0, 0.1, 0.0], 0),
        "ER26 Cmd jG j5 < 0.785"
    );
    // A negative duration is clamped.
    assert_eq!(
        floats(&rig.request("GT", [0.5, 0.6, 1.0, 0.0, 0.0, 0.0, -3.0], 0))[6],
        0.0
    );
}

#[test]
fn commands_in_the_wrong_mode_are_rejected() {
    let mut rig = mk1();
    let q = [1.5708f32, 0.6, -0.4, 0.2, 1.8, 0.1, 0.0];
    assert_eq!(&rig.request("jG", q, 0)[..2], b"Gj");
    rig.request("CM", [2.0, 0., 0., 0., 0., 0., 0.], 0);
    assert_eq!(rig.text("jB", [0.0; 7], 0), "ER20 Cmd jB needs mode 1");
    assert_eq!(rig.text("jE", [0.0; 7], 0), "ER20 Cmd jE needs mode 1");
    rig.request("CM", [1.0, 0., 0., 0., 0., 0., 0.], 0);
    assert_eq!(rig.text("VE", [0.0; 7], 0), "ER20 Cmd VE needs mode 2");
    rig.request("GT", [0.5, 0.6, 1.0, 0.0, 0.0, 0.0, 0.0], 0);
    assert_eq!(rig.text("BG", [0.0; 7], 0), "ER20 Cmd BG needs mode 2");
    // jB needs a jG first (the seed drove every joint to 0, spec §9 item 8).
    let mut fresh = mk1();
    fresh.request("CM", [1.0, 0., 0., 0., 0., 0., 0.], 0);
    assert_eq!(fresh.text("jB", [0.0; 7], 0), "ER20 Cmd jB no goal");
    // Motion is refused while the drives are off, and ON/OF report their state.
    assert_eq!(&fresh.request("OF", [0.0; 7], 0)[..2], b"FO");
    assert_eq!(fresh.text("OF", [0.0; 7], 0), "ER10 Arm already off");
    fresh.request("jG", q, 0);
    assert_eq!(fresh.text("jB", [0.0; 7], 0), "ER20 Cmd jB drives off");
    assert_eq!(&fresh.request("ON", [0.0; 7], 0)[..2], b"NO");
    assert_eq!(fresh.text("ON", [0.0; 7], 0), "ER11 Arm already on");
    assert_eq!(&fresh.request("jB", [0.0; 7], 0)[..2], b"Bj");
}

#[test]
fn eight_joint_arm_is_commanded_in_two_banks() {
    let start = [0.1, 0.4, -0.2, 0.8, 0.1, 0.5, 0.2, 0.1];
    let mut rig = Rig::new(&common::robot("ranger-mk2"), &start);
    rig.request("CM", [1.0, 0., 0., 0., 0., 0., 0.], 0);
    let goal = [0.2f32, 0.5, -0.1, 0.7, 0.2, 0.4, 0.3, 0.0];
    // Bank 1 alone is refused on an 8-joint arm.
    let mut bank1 = [0.0f32; 7];
    bank1[..6].copy_from_slice(&goal[..6]);
    assert_eq!(rig.text("jG", bank1, 0), "ER24 Cmd jG bad index");
    let mut bank2 = [0.0f32; 7];
    bank2[..2].copy_from_slice(&goal[6..8]);
    let echo = rig.request("jG", bank2, 0x80);
    assert_eq!((&echo[..2], echo[30]), (&b"Gj"[..], 0x80));
    assert_eq!(&rig.request("jG", bank1, 0)[..2], b"Gj");
    assert_eq!(&rig.request("jB", [0.0; 7], 0)[..2], b"Bj");
    for _ in 0..2000 {
        rig.tick();
    }
    let low = floats(&rig.request("jP", [0.0; 7], 0));
    let high = rig.request("jP", [0.0; 7], 0x80);
    assert_eq!(high[30], 0x80);
    let high = floats(&high);
    for (got, want) in low.iter().take(6).chain(high.iter().take(2)).zip(goal) {
        assert!((got - want).abs() < 1e-6, "{low:?} {high:?}");
    }
    assert_eq!(low[6], goal[6]);
    assert_eq!(&high[2..], &[0.0; 5]);
    // Temperatures: bank 2 carries joints 7 and 8, then −1000 padding.
    let t = floats(&rig.request("TM", [0.0; 7], 0x80));
    assert_eq!(&t[..3], &[30.0, 30.0, -1000.0]);
    // Bank 2 on a six-joint arm is refused.
    assert_eq!(mk1().text("jG", bank2, 0x80), "ER24 Cmd jG bad index");
}

#[test]
fn unsolicited_warnings_are_relayed_and_rate_limited() {
    // Bounds that end at x = 0.3 m: turning the base to q1 = 0.5 takes the tool out.
    let config = common::robot("ranger-mk1")
        .edit(|config| config.workspace.bounds[1] = 0.3)
        .unwrap();
    // Joint moves out of the workspace are refused up front now; an arm already outside (after
    // a recalibration, at start-up) is reported (ER21), not stopped.
    let mut outside = MK1_READY;
    outside[0] = 0.5;
    let mut rig = Rig::new(&config, &MK1_READY);
    rig.request("CM", [1.0, 0., 0., 0., 0., 0., 0.], 0);
    let mut v = [0.0f32; 7];
    for (d, q) in v.iter_mut().zip(outside) {
        *d = q as f32;
    }
    assert_eq!(&rig.request("jG", v, 0)[..2], b"Gj");
    assert_eq!(rig.text("jB", [0.0; 7], 0), "ER25 Cmd jB outside workspace");
    let mut rig = Rig::new(&config, &outside);
    rig.request("CM", [1.0, 0., 0., 0., 0., 0., 0.], 0);
    let mut texts = Vec::new();
    for _ in 0..3000 {
        rig.tick();
        for notice in rig.client.notices.drain(..) {
            texts.push((rig.now, text_of(&notice.payload().try_into().unwrap())));
        }
    }
    let er21: Vec<f64> = texts
        .iter()
        .filter(|(_, t)| t == "ER21 Work space limit.")
        .map(|(n, _)| *n)
        .collect();
    assert!(!er21.is_empty(), "{texts:?}");
    assert!(er21.len() > 10, "{texts:?}");
    assert!(er21.windows(2).all(|w| w[1] - w[0] >= 0.2 - 1e-9));
    // The arm got there all the same.
    let jp = floats(&rig.request("jP", [0.0; 7], 0));
    assert!((jp[0] - 0.5).abs() < 1e-6);
}

#[test]
fn random_datagrams_never_panic_and_ps_still_answers() {
    let mut rig = mk1();
    let mut rng = SplitMix64::new(99);
    let commands = [
        "BG", "CM", "GL", "GT", "jB", "jC", "jE", "jG", "jP", "jR", "jV", "ON", "OF", "PS", "RC",
        "SQ", "ST", "TM", "VC", "VE", "VP",
    ];
    for k in 0..20_000 {
        let len = (rng.next_u64() % 40) as usize;
        let mut d: Vec<u8> = (0..len).map(|_| rng.next_u64() as u8).collect();
        if len >= 2 && k % 2 == 0 {
            let c = commands[(rng.next_u64() % commands.len() as u64) as usize];
            d[..2].copy_from_slice(c.as_bytes());
        }
        let reply = rig.send(&d);
        assert_eq!(reply.len(), 31);
        if k % 50 == 0 {
            rig.tick();
        }
    }
    rig.request("ON", [0.0; 7], 0);
    rig.tick();
    assert_eq!(&rig.request("PS", [0.0; 7], 0)[..2], b"SP");
    assert!(rig.cycle.drives().temperatures().len() == 6);
}

#[test]
fn bank_2_reads_are_refused_on_a_six_joint_arm() {
    // docs/protocol.md: "On a six-joint arm, bit 7 is refused."
    let mut rig = mk1();
    for (cmd, text) in [
        ("jP", b"ER24 Cmd jP bad index"),
        ("TM", b"ER24 Cmd TM bad index"),
    ] {
        let mut expected = [0u8; 31];
        expected[..21].copy_from_slice(text);
        assert_eq!(rig.request(cmd, [0.0; 7], 0x80), expected);
    }
    // Bank 1 still answers, index 0.
    let pj = rig.request("jP", [0.0; 7], 0);
    assert_eq!((&pj[..2], pj[30]), (&b"Pj"[..], 0));
}

/// `SQ` 5 reports the present branch of the arm at `present`; `KS` lists every closed-form
/// solution of `target_q`'s pose; `KG` moves the joints to the solution on its branch (joint
/// mode), and `SQ` 5 then reports that branch. The branches listed.
fn list_choose_and_report(
    rig: &mut Rig,
    chain: &Chain,
    present: &[f64],
    target_q: &[f64],
) -> Vec<u8> {
    let sq = rig.request("SQ", [0.0; 7], 5);
    assert_eq!((&sq[..2], sq[30]), (&b"QS"[..], 5));
    // The configuration as arms name it.
    let branch = chain.configuration(present).unwrap();
    assert_eq!(floats(&sq)[0], f32::from(branch));

    let pose = chain.forward(target_q).unwrap();
    let [r, p, y] = math::rpy(&pose.rotation);
    let t = pose.translation.vector;
    let values = [t.x, t.y, t.z, r, p, y, 0.0].map(|v| v as f32);
    let first = rig.request("KS", values, 0);
    assert_eq!(&first[..2], b"SK");
    let count = floats(&first)[6] as u8;
    assert!(count >= 2, "{count}");
    let mut branches = Vec::new();
    let mut target_branch = None;
    for k in 0..count {
        let sk = rig.request("KS", values, k);
        let q = floats(&sk);
        assert!(!branches.contains(&sk[30]));
        branches.push(sk[30]);
        // f6 is the count: joints 1–6 (7.. are bank 2's).
        if q.iter()
            .take(6)
            .zip(target_q)
            .all(|(a, b)| (f64::from(*a) - b).abs() < 1e-4)
        {
            target_branch = Some(sk[30]);
        }
    }
    let target_branch =
        target_branch.unwrap_or_else(|| panic!("the configuration is among the solutions"));
    assert_eq!(rig.request("KS", values, count)[30], 0xFF);
    // KG needs joint mode and a branch 0..=7 or 8 (nearest).
    assert!(
        rig.text("KG", values, target_branch)
            .starts_with("ER20 Cmd KG needs mode 1")
    );
    rig.request("CM", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    rig.tick();
    assert!(rig.text("KG", values, 9).starts_with("ER24"));
    // A branch without a solution within the limits is refused as such (a 7–8 joint arm's
    // `KG` without a `KR` choice tries other θ3, θ5: it may find one).
    let flags = chain.configuration_flags();
    let redundant = !chain.redundancy_parameters().is_empty();
    for other in (0..8).filter(|b| !redundant && !branches.contains(b) && b & !flags == 0) {
        assert_eq!(
            rig.text("KG", values, other),
            "ER44 Cmd KG branch past limits"
        );
    }
    let gk = rig.request("KG", values, target_branch);
    assert_eq!((&gk[..2], gk[30]), (&b"GK"[..], target_branch));
    for (a, b) in floats(&gk).iter().take(6).zip(target_q) {
        assert!((f64::from(*a) - b).abs() < 1e-4);
    }
    for _ in 0..1000 {
        rig.tick();
    }
    let jp = floats(&rig.request("jP", [0.0; 7], 0));
    for (a, b) in jp.iter().take(6).zip(target_q) {
        assert!((f64::from(*a) - b).abs() < 1e-4, "{jp:?}");
    }
    let sq = rig.request("SQ", [0.0; 7], 5);
    assert_eq!(floats(&sq)[0], f32::from(target_branch));
    branches
}

#[test]
fn closed_form_requests_list_choose_and_report_branches() {
    let chain = Chain::new(&common::robot("ranger-mk1"));
    let mut rig = mk1();
    let target_q: Vec<f64> = MK1_READY.iter().map(|q| q + 0.1).collect();
    list_choose_and_report(&mut rig, &chain, &MK1_READY, &target_q);
    // A robot without a closed form: KS answers f6 = −1.
    let numeric = common::robot("hybrid")
        .edit(|c| c.joints.swap(1, 2))
        .unwrap();
    let mut numeric = Rig::new(&numeric, &[0.0; 6]);
    let sk = numeric.request("KS", [0.5, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0], 0);
    assert_eq!((floats(&sk)[6], sk[30]), (-1.0, 0xFF));
    // A redundant arm: the solutions for the present θ3.
    let present = [0.1, 0.5, 0.3, -1.0, 0.2, 0.8, 0.1];
    let iiwa_chain = Chain::new(&common::robot("iiwa14"));
    let mut iiwa = Rig::new(&common::robot("iiwa14"), &present);
    let pose = iiwa_chain.forward(&present).unwrap();
    let [r, p, y] = math::rpy(&pose.rotation);
    let t = pose.translation.vector;
    let values = [t.x, t.y, t.z, r, p, y, 0.0].map(|v| v as f32);
    let sk = iiwa.request("KS", values, 0);
    assert!(floats(&sk)[6] >= 1.0, "{:?}", floats(&sk));
    // Joints 7.. of the same solution: bank 2. Refused on six joints.
    let upper = iiwa.request("KS", values, 0x80);
    assert_eq!((&upper[..2], upper[30]), (&b"SK"[..], sk[30]));
    let mut q: Vec<f64> = floats(&sk)[..6].iter().map(|v| f64::from(*v)).collect();
    q.push(f64::from(floats(&upper)[0]));
    assert!((q[2] - present[2]).abs() < 1e-6, "θ3 kept: {q:?}");
    let reached = iiwa_chain.forward(&q).unwrap();
    assert!((reached.translation.vector - t).norm() < 1e-5, "{q:?}");
    assert!(rig.text("KS", values, 0x80).starts_with("ER24"));
    let branch = iiwa_chain.configuration(&present).unwrap();
    assert_eq!(
        floats(&iiwa.request("SQ", [0.0; 7], 5))[0],
        f32::from(branch)
    );
}

/// Every other closed-form robot names its configurations (issue 37): `SQ` 5, `KS`, `KG` by
/// name, `ER44` for a configuration of the pose outside the limits; on a 7–8 joint arm for
/// the present θ3 (and θ5).
#[test]
fn closed_form_requests_name_configurations_on_every_robot() {
    for (name, present) in [
        ("puma560", vec![0.2, -0.7, 2.0, 0.3, 0.6, 0.1]),
        ("ur5", vec![0.2, -0.7, 2.0, 0.3, 0.6, 0.1]),
        ("iiwa14", vec![0.1, 0.5, 0.3, -1.0, 0.2, 0.8, 0.1]),
        ("ranger-mk2", vec![0.1, 0.5, 0.3, 1.0, 0.2, 0.8, 0.1, 0.2]),
    ] {
        let config = common::robot(name);
        let chain = Chain::new(&config);
        let mut rig = Rig::new(&config, &present);
        let target_q: Vec<f64> = present.iter().map(|q| q + 0.1).collect();
        // The redundancy values stay: the target's are the present ones.
        let mut target_q = target_q;
        for &p in chain.redundancy_parameters() {
            target_q[p] = present[p];
        }
        let branches = list_choose_and_report(&mut rig, &chain, &present, &target_q);
        assert!(branches.len() >= 2, "{name}: {branches:?}");
    }
}

/// hybrid (two slides, then four revolute joints): the same requests, on its closed form; it
/// has no wrist of three axes, so no configuration sets the wrist bit (docs/kinematics.md)
/// and `KG` with it is refused as a bad index (no such branch on this robot), not as one past
/// the limits.
#[test]
fn closed_form_requests_on_a_prismatic_base() {
    let config = common::robot("hybrid");
    let chain = Chain::new(&config);
    let present = [0.1, -0.2, 0.3, 0.4, -0.9, 0.2];
    let mut rig = Rig::new(&config, &present);
    let target_q: Vec<f64> = present.iter().map(|q| q + 0.1).collect();
    let branches = list_choose_and_report(&mut rig, &chain, &present, &target_q);
    assert!(branches.len() >= 2, "{branches:?}");
    assert!(branches.iter().all(|b| b & 4 == 0), "{branches:?}");
    let pose = chain.forward(&present).unwrap();
    let [r, p, y] = math::rpy(&pose.rotation);
    let t = pose.translation.vector;
    let values = [t.x, t.y, t.z, r, p, y, 0.0].map(|v| v as f32);
    assert!(
        rig.text("KG", values, 4)
            .starts_with("ER24 Cmd KG bad index")
    );
}

/// A `KG` to the pose the arm is at, as `armgate pose` prints it (six decimals), keeps the
/// present joints. hybrid's home is singular (axis 6 in line with axis 3): the exact solutions
/// of the printed pose, 3.5e-7 rad off, turn θ3 a quarter turn and run the slides 0.5 m out.
#[test]
fn kg_to_the_pose_the_arm_is_at_does_not_move_it() {
    let config = common::robot("hybrid");
    let chain = Chain::new(&config);
    let home = [0.0; 6];
    let mut rig = Rig::new(&config, &home);
    let printed = [0.0, -0.5, -0.5, 3.141593, 0.0, -1.570796, 0.0].map(|v: f64| v as f32);
    let [x, y, z, roll, pitch, yaw, _] = printed.map(f64::from);
    let target = math::Frame::from_parts(
        math::Vector3::new(x, y, z).into(),
        math::Rotation3::from_euler_angles(roll, pitch, yaw),
    );
    let far = chain.solve_all(&target, &home).unwrap();
    assert!(
        far.iter().all(|s| s.q.iter().any(|q| q.abs() > 0.4)),
        "{far:?}"
    );
    rig.request("CM", [1.0, 0., 0., 0., 0., 0., 0.], 0);
    for index in [8, chain.configuration(&home).unwrap()] {
        let reply = floats(&rig.request("KG", printed, index));
        assert!(reply[..6].iter().all(|q| q.abs() < 1e-9), "{reply:?}");
        for _ in 0..50 {
            rig.tick();
        }
    }
}

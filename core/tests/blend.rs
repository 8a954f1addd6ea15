//! Blended via points (issue 13 part 2): tolerance 0 is today's behaviour bit for bit; with a
//! tolerance the path passes each via point within it, without stopping, with continuous
//! velocity and within the limits.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::approx_constant
)]

mod common;

use armgate_core::config::ValidRobot;
use armgate_core::kinematics::Joints;
use armgate_core::math::Vector3;
use armgate_core::motion::{Controller, Mode};
use armgate_core::rng::SplitMix64;
use armgate_core::sim::IdealArm;
use common::experiments::{
    RECTANGLE, RECTANGLE_JERK, RectangleRun, blended, corner_passes, jerk_limited, off_rectangle,
    rectangle_config, run_rectangle,
};

/// FNV-1a over the bits of every value: a fingerprint of a whole set-point trace.
fn fingerprint(values: impl IntoIterator<Item = f64>) -> u64 {
    values.into_iter().fold(0xcbf2_9ce4_8422_2325, |h, v| {
        v.to_bits()
            .to_le_bytes()
            .iter()
            .fold(h, |h, b| (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3))
    })
}

const MK1_READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];

/// The four via points of the joint sequence on ranger-mk1 (the third with T = 3 s).
fn joint_points() -> Vec<([f64; 6], f64)> {
    (0..4)
        .map(|k| {
            let mut q = MK1_READY;
            q[0] += if k % 2 == 0 { 0.3 } else { -0.1 } * (k + 1) as f64;
            q[2] -= 0.2 * (k + 1) as f64;
            q[4] += 0.1 * k as f64;
            (q, if k == 2 { 3.0 } else { 0.0 })
        })
        .collect()
}

/// A joint sequence of four points on ranger-mk1 with an ideal arm: every joint command.
fn joint_sequence_commands(config: &ValidRobot) -> Vec<Joints> {
    run_joint_sequence(config, &joint_points(), &[])
}

/// Runs `points` (joints, minimum duration) as a joint sequence from MK1_READY with the slots'
/// own blend tolerances `blends` (slot, tolerance); every joint command until it finishes.
fn run_joint_sequence(
    config: &ValidRobot,
    points: &[([f64; 6], f64)],
    blends: &[(usize, f64)],
) -> Vec<Joints> {
    // The joint points are about the blends, not the workspace: their way leaves ranger-mk1's
    // bounds, which joint moves now refuse up front.
    let config = &config
        .clone()
        .edit(|c| {
            c.workspace.bounds = [-5.0, 5.0, -5.0, 5.0, -5.0, 5.0];
            c.workspace.boxes.clear();
        })
        .unwrap();
    let mut ctrl = Controller::new(config);
    let mut arm = IdealArm::new(Joints::from_slice(&MK1_READY).unwrap());
    let period = config.control_period;
    let mut now = 0.0;
    ctrl.step(now, &arm.measured()).unwrap();
    ctrl.set_mode(Mode::Joint).unwrap();
    for (k, (q, t)) in points.iter().enumerate() {
        ctrl.set_joint_via(k, q, *t).unwrap();
    }
    for (k, tolerance) in blends {
        assert_eq!(ctrl.set_joint_blend(*k, Some(*tolerance)), Ok(*tolerance));
    }
    ctrl.start_joint_sequence().unwrap();
    let mut commands = vec![arm.measured()];
    for _ in 0..100_000 {
        now += period;
        let out = ctrl.step(now, &arm.measured()).unwrap();
        arm.step(out.command.as_ref());
        commands.extend(out.command);
        if out.events.sequence_finished || out.events.sequence_aborted {
            assert!(out.events.sequence_finished);
            return commands;
        }
    }
    panic!("the joint sequence did not finish");
}

/// Fingerprints of the set-points before blending existed (commit 1ca5d57): a sequence with
/// tolerance 0 must reproduce them bit for bit. E8's was re-recorded when hybrid's global IK
/// became closed form (issue 26): the rectangle starts from another exact solution of its
/// first corner, so every tool position differs in its last bits.
const E8_FINGERPRINT: u64 = 0x0789_dce4_1b0a_4648;
const JOINT_FINGERPRINT: u64 = 0xe5fb_8be0_c917_ff8d;

#[test]
fn tolerance_zero_reproduces_the_unblended_set_points_bit_for_bit() {
    let e8 = run_rectangle(&rectangle_config(common::robot("hybrid")));
    let e8_print = fingerprint(
        e8.trace
            .iter()
            .flat_map(|t| t.tool.iter().copied().collect::<Vec<_>>()),
    );
    let joints = joint_sequence_commands(&common::robot("ranger-mk1"));
    let joint_print = fingerprint(
        joints[1..]
            .iter()
            .flat_map(|q| q.iter().copied().collect::<Vec<_>>()),
    );
    println!(
        "E8 {e8_print:#x} ({} ticks), joints {joint_print:#x} ({} ticks)",
        e8.trace.len(),
        joints.len()
    );
    assert_eq!(e8_print, E8_FINGERPRINT);
    assert_eq!(joint_print, JOINT_FINGERPRINT);
}

/// Per-axis checks on set-points sampled every `dt`: speed (first difference) within `v_max`,
/// acceleration (second difference) within `a_max`: the velocity is continuous and the limits
/// hold, whatever happens at the via points. Returns the lowest speed (norm over the axes)
/// around any of `corners`: within `radius` of one (0 where the motion stops there).
fn check_limits(
    samples: &[Vec<f64>],
    dt: f64,
    v_max: &[f64],
    a_max: &[f64],
    corners: &[&[f64]],
    radius: f64,
) -> f64 {
    check_limits_with_jerk(samples, dt, [v_max, a_max], None, corners, radius)
}

/// [`check_limits`], and with `j_max` also the jerk (third difference): the acceleration is
/// continuous.
fn check_limits_with_jerk(
    samples: &[Vec<f64>],
    dt: f64,
    [v_max, a_max]: [&[f64]; 2],
    j_max: Option<&[f64]>,
    corners: &[&[f64]],
    radius: f64,
) -> f64 {
    let speeds: Vec<Vec<f64>> = samples
        .windows(2)
        .map(|w| w[1].iter().zip(&w[0]).map(|(b, a)| (b - a) / dt).collect())
        .collect();
    for (k, v) in speeds.iter().enumerate() {
        for (axis, (s, limit)) in v.iter().zip(v_max).enumerate() {
            assert!(
                s.abs() <= limit * (1.0 + 1e-9),
                "tick {k} axis {axis}: speed {s} > {limit}"
            );
        }
    }
    let accelerations: Vec<Vec<f64>> = speeds
        .windows(2)
        .map(|w| w[1].iter().zip(&w[0]).map(|(b, a)| (b - a) / dt).collect())
        .collect();
    for (k, acc) in accelerations.iter().enumerate() {
        for (axis, (acc, limit)) in acc.iter().zip(a_max).enumerate() {
            assert!(
                acc.abs() <= limit * (1.0 + 1e-6),
                "tick {k} axis {axis}: acceleration {acc} > {limit}"
            );
        }
    }
    for (k, w) in accelerations.windows(2).enumerate() {
        for (axis, ((b, a), limit)) in w[1].iter().zip(&w[0]).zip(j_max.unwrap_or(&[])).enumerate()
        {
            let jerk = (b - a) / dt;
            assert!(
                jerk.abs() <= limit * (1.0 + 1e-6) + 1e-6,
                "tick {k} axis {axis}: jerk {jerk} > {limit}"
            );
        }
    }
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    samples
        .iter()
        .zip(&speeds)
        .filter(|(p, _)| {
            corners.iter().any(|c| {
                norm(
                    &p.iter()
                        .zip(c.iter())
                        .map(|(a, b)| a - b)
                        .collect::<Vec<_>>(),
                ) <= radius
            })
        })
        .map(|(_, v)| norm(v))
        .fold(f64::INFINITY, f64::min)
}

fn setpoints(run: &RectangleRun) -> Vec<Vec<f64>> {
    run.trace
        .iter()
        .map(|t| t.setpoint.iter().copied().collect())
        .collect()
}

#[test]
fn e8_blended_passes_each_corner_within_the_tolerance_without_stopping_and_within_the_limits() {
    let config = rectangle_config(common::robot("hybrid"));
    let stopping = run_rectangle(&config);
    let corners: Vec<Vector3<f64>> = RECTANGLE.iter().map(|p| Vector3::from(*p)).collect();
    let inner_corners: Vec<&[f64]> = RECTANGLE[1..4].iter().map(|c| &c[..]).collect();
    for tolerance in [0.002, 0.01, 0.05] {
        let run = run_rectangle(&blended(config.clone(), tolerance));
        // Each corner's overlap lasts √(tolerance / a_max) (the last half tolerance of a
        // deceleration at 0.1 m/s²): three corners.
        let saved = stopping.duration - run.duration;
        assert!(
            saved > 2.5 * (tolerance / 0.1f64).sqrt(),
            "{tolerance}: saved {saved} s"
        );
        for (k, pass) in corner_passes(&run).into_iter().enumerate() {
            // Corners are cut, but by no more than the tolerance.
            assert!(
                pass <= tolerance + 1e-9,
                "{tolerance}: corner {k} passed at {pass}"
            );
            assert!(
                pass > tolerance / 10.0,
                "{tolerance}: corner {k} not cut: {pass}"
            );
        }
        // Every set-point is on the rectangle or within the tolerance of a corner.
        for tick in &run.trace {
            let p = tick.setpoint;
            let on_edge = off_rectangle(&p);
            let near_corner = corners
                .iter()
                .map(|c| (p - c).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(
                on_edge < 1e-12 || near_corner <= tolerance + 1e-12,
                "{tolerance}: {p:?} at t = {} strays",
                tick.t
            );
        }
        let [v_max @ .., _, _, _] = config.cartesian.max_velocity;
        let [a_max @ .., _, _, _] = config.cartesian.max_acceleration;
        let slowest = check_limits(
            &setpoints(&run),
            config.control_period,
            &v_max,
            &a_max,
            &inner_corners,
            tolerance,
        );
        println!("{tolerance}: slowest {slowest}");
        assert!(
            slowest > 0.01,
            "{tolerance}: stops on the way ({slowest} m/s)"
        );
        assert_eq!(run.divergence_ticks, 0);
    }
    // The unblended rectangle stops at each corner.
    let [v_max @ .., _, _, _] = config.cartesian.max_velocity;
    let [a_max @ .., _, _, _] = config.cartesian.max_acceleration;
    let slowest = check_limits(
        &setpoints(&stopping),
        config.control_period,
        &v_max,
        &a_max,
        &inner_corners,
        0.002,
    );
    assert!(slowest < a_max[0] * config.control_period, "{slowest}");
}

#[test]
fn e8_blended_with_jerk_limited_profiles_keeps_acceleration_continuous() {
    let config = jerk_limited(rectangle_config(common::robot("hybrid")));
    let stopping = run_rectangle(&config);
    let inner_corners: Vec<&[f64]> = RECTANGLE[1..4].iter().map(|c| &c[..]).collect();
    let [v_max @ .., _, _, _] = config.cartesian.max_velocity;
    let [a_max @ .., _, _, _] = config.cartesian.max_acceleration;
    let [j_lin @ .., _, _, _] = RECTANGLE_JERK;
    for tolerance in [0.01, 0.05] {
        let run = run_rectangle(&blended(config.clone(), tolerance));
        assert!(
            run.duration < stopping.duration - 0.5,
            "{tolerance}: {}",
            run.duration
        );
        for (k, pass) in corner_passes(&run).into_iter().enumerate() {
            assert!(
                pass <= tolerance + 1e-9,
                "{tolerance}: corner {k} passed at {pass}"
            );
        }
        let slowest = check_limits_with_jerk(
            &setpoints(&run),
            config.control_period,
            [&v_max, &a_max],
            Some(&j_lin),
            &inner_corners,
            tolerance,
        );
        assert!(
            slowest > 0.005,
            "{tolerance}: stops on the way ({slowest} m/s)"
        );
    }
}

/// Checks a blended joint run: ends exactly at the last point, passes every intermediate
/// point within `tolerance[k]`, and keeps the joint generator's limits.
fn check_joint_run(
    config: &ValidRobot,
    points: &[([f64; 6], f64)],
    commands: &[Joints],
    tolerance: &[f64],
) -> f64 {
    assert_eq!(&commands.last().unwrap()[..], &points.last().unwrap().0[..]);
    for ((q, _), tol) in points.iter().zip(tolerance) {
        let pass = commands
            .iter()
            .map(|c| {
                c.iter()
                    .zip(q)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(pass <= tol + 1e-12, "passed {q:?} at {pass} > {tol}");
    }
    let samples: Vec<Vec<f64>> = commands.iter().map(|q| q.to_vec()).collect();
    let v_max = config.per_joint(|j| j.max_velocity);
    let a_max = config.per_joint(|j| j.max_acceleration);
    let inner: Vec<&[f64]> = points[..points.len() - 1]
        .iter()
        .map(|(q, _)| &q[..])
        .collect();
    let radius = tolerance.iter().copied().fold(0.001, f64::max);
    // Jerk-limited robots: the jerk too (third differences).
    let j_max = config.joint_jerk_limits();
    check_limits_with_jerk(
        &samples,
        config.control_period,
        [&v_max, &a_max],
        j_max.as_deref(),
        &inner,
        radius,
    )
}

/// A sweep on ranger-mk1 whose consecutive legs never reverse a joint.
fn sweep_points() -> Vec<([f64; 6], f64)> {
    let steps = [
        [0.3, 0.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, -0.3, 0.0, 0.2, 0.0],
        [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
        [0.1, 0.0, -0.2, 0.0, 0.1, 0.0],
    ];
    let mut q = MK1_READY;
    steps
        .iter()
        .map(|step| {
            q.iter_mut().zip(step).for_each(|(v, d)| *v += d);
            (q, 0.0)
        })
        .collect()
}

#[test]
fn joint_sequence_blends_within_the_tolerance_and_the_limits() {
    let config = common::robot("ranger-mk1");
    let points = sweep_points();
    let stopping = run_joint_sequence(&config, &points, &[]);
    let blended = run_joint_sequence(
        &config.clone().edit(|c| c.blend.joint = 0.05).unwrap(),
        &points,
        &[],
    );
    assert!(
        blended.len() + 30 < stopping.len(),
        "{} vs {} ticks",
        blended.len(),
        stopping.len()
    );
    let slowest = check_joint_run(&config, &points, &blended, &[0.05, 0.05, 0.05, 0.0]);
    println!("joint slowest {slowest}");
    assert!(slowest > 0.03, "stopped on the way ({slowest} rad/s)");
    // A slot's own 0 overrides the default: the arm stops exactly at point 1.
    let mixed = run_joint_sequence(
        &config.clone().edit(|c| c.blend.joint = 0.05).unwrap(),
        &points,
        &[(1, 0.0)],
    );
    check_joint_run(&config, &points, &mixed, &[0.05, 0.0, 0.05, 0.0]);
    // And a slot's own tolerance blends without a default.
    let own = run_joint_sequence(&config, &points, &[(0, 0.02), (2, 0.1)]);
    let slowest = check_joint_run(&config, &points, &own, &[0.02, 0.0, 0.1, 0.0]);
    println!("joint slowest with a stop {slowest}");
    assert!(
        slowest < 0.015,
        "does not stop at point 1 ({slowest} rad/s)"
    );
}

#[test]
fn jerk_limited_joint_sequences_blend_with_the_jerk_shared_on_common_joints() {
    let config = common::robot("ranger-mk1-jerk");
    let points = sweep_points();
    let stopping = run_joint_sequence(&config, &points, &[]);
    check_joint_run(&config, &points, &stopping, &[0.0; 4]);
    let blended = run_joint_sequence(
        &config.clone().edit(|c| c.blend.joint = 0.05).unwrap(),
        &points,
        &[],
    );
    assert!(
        blended.len() + 20 < stopping.len(),
        "{} vs {} ticks",
        blended.len(),
        stopping.len()
    );
    let slowest = check_joint_run(&config, &points, &blended, &[0.05, 0.05, 0.05, 0.0]);
    assert!(slowest > 0.02, "stopped on the way ({slowest} rad/s)");
    random_joint_sequences(&config, 7);
}

#[test]
fn random_joint_sequences_blend_within_the_tolerance_and_the_limits() {
    random_joint_sequences(&common::robot("ranger-mk1"), 13);
}

/// More of the same, for both profiles: `cargo test --release -p armgate-core --test blend --
/// --ignored`.
#[test]
#[ignore]
fn many_random_joint_sequences() {
    for seed in 100..125 {
        random_joint_sequences(&common::robot("ranger-mk1"), seed);
        random_joint_sequences(&common::robot("ranger-mk1-jerk"), seed);
    }
}

/// 40 random joint sequences (fixed `seed`) from MK1_READY with random per-slot tolerances:
/// each passes its points within them and keeps the limits.
fn random_joint_sequences(config: &ValidRobot, seed: u64) {
    let chain = armgate_core::kinematics::Chain::new(config);
    let mut rng = SplitMix64::new(seed);
    for case in 0..40 {
        let n = 2 + (rng.next_u64() % 5) as usize;
        let points: Vec<([f64; 6], f64)> = (0..n)
            .map(|_| {
                let mut q = MK1_READY;
                for (v, (lo, hi)) in q.iter_mut().zip(chain.min().iter().zip(chain.max())) {
                    *v = (*v + rng.uniform(-0.4, 0.4)).clamp(*lo, *hi);
                }
                let t = if rng.next_f64() < 0.3 {
                    rng.uniform(0.0, 4.0)
                } else {
                    0.0
                };
                (q, t)
            })
            .collect();
        let tolerances: Vec<f64> = (0..n)
            .map(|k| {
                if k + 1 < n {
                    rng.uniform(0.0, 0.2)
                } else {
                    0.0
                }
            })
            .collect();
        let blends: Vec<(usize, f64)> = tolerances.iter().copied().enumerate().collect();
        let commands = run_joint_sequence(config, &points, &blends);
        let _ = case;
        check_joint_run(config, &points, &commands, &tolerances);
    }
}

#[test]
fn a_via_point_at_a_joint_limit_is_reached_exactly() {
    let config = common::robot("ranger-mk1")
        .edit(|c| c.blend.joint = 0.1)
        .unwrap();
    let chain = armgate_core::kinematics::Chain::new(&config);
    let mut at_limit = MK1_READY;
    at_limit[1] = chain.max()[1];
    let mut after = at_limit;
    after[0] += 0.3;
    let points = [(at_limit, 0.0), (after, 0.0)];
    let commands = run_joint_sequence(&config, &points, &[]);
    check_joint_run(&config, &points, &commands, &[0.0, 0.0]);
    assert!(commands.iter().all(|q| q[1] <= chain.max()[1]));
}

/// `VT`/`jT` through the command handler, literal bytes in and out: set, echo, default again,
/// refusals; then a joint sequence whose slots were given tolerances this way blends.
#[test]
fn vt_and_jt_set_per_slot_tolerances_through_the_handler() {
    use armgate_core::command::CommandHandler;
    use armgate_core::sim::{ArmModel, SimulatedDrives};
    let config = common::robot("ranger-mk1")
        .edit(|c| c.blend.cartesian = 0.004)
        .unwrap();
    let mut drives = SimulatedDrives::new(ArmModel::Ideal(IdealArm::new(
        Joints::from_slice(&MK1_READY).unwrap(),
    )));
    let mut handler = CommandHandler::new(&config);
    let period = config.control_period;
    let mut now = 0.0;
    let mut tick = |handler: &mut CommandHandler, drives: &mut SimulatedDrives| {
        now += period;
        let out = handler.tick(now, &drives.measured(), drives).unwrap();
        drives.apply(out.command.as_ref(), period);
        out
    };
    tick(&mut handler, &mut drives);

    // VT slot 2 := 0.01: the reply TV echoes what is now in effect.
    let mut vt = [0u8; 31];
    vt[..6].copy_from_slice(&[b'V', b'T', 0x0a, 0xd7, 0x23, 0x3c]);
    vt[30] = 2;
    let mut tv = vt;
    tv[..2].copy_from_slice(b"TV");
    assert_eq!(handler.handle(&vt, &mut drives), tv);
    // f0 = −1: back to the robot file's 0.004 (0x3b83126f).
    vt[2..6].copy_from_slice(&(-1.0f32).to_le_bytes());
    tv[2..6].copy_from_slice(&[0x6f, 0x12, 0x83, 0x3b]);
    assert_eq!(handler.handle(&vt, &mut drives), tv);
    // NaN and slot 20 (or the bank bit) are refused.
    vt[2..6].copy_from_slice(&f32::NAN.to_le_bytes());
    assert_eq!(&handler.handle(&vt, &mut drives)[..4], b"ER23");
    vt[2..6].copy_from_slice(&0.01f32.to_le_bytes());
    for slot in [20, 0x82] {
        vt[30] = slot;
        assert_eq!(&handler.handle(&vt, &mut drives)[..4], b"ER24");
    }

    // A joint sequence with jT on every intermediate slot blends through them.
    let points = sweep_points();
    let mut cm = [0u8; 31];
    cm[..6].copy_from_slice(&[b'C', b'M', 0x00, 0x00, 0x80, 0x3f]); // mode 1
    assert_eq!(&handler.handle(&cm, &mut drives)[..2], b"MC");
    for (k, (q, t)) in points.iter().enumerate() {
        let mut jv = [0u8; 31];
        jv[..2].copy_from_slice(b"jV");
        for (i, v) in q.iter().chain([t]).enumerate() {
            jv[2 + 4 * i..6 + 4 * i].copy_from_slice(&(*v as f32).to_le_bytes());
        }
        jv[30] = k as u8;
        assert_eq!(&handler.handle(&jv, &mut drives)[..2], b"Vj");
        if k + 1 < points.len() {
            let mut jt = [0u8; 31];
            jt[..6].copy_from_slice(&[b'j', b'T', 0xcd, 0xcc, 0x4c, 0x3d]); // 0.05
            jt[30] = k as u8;
            let mut tj = jt;
            tj[..2].copy_from_slice(b"Tj");
            assert_eq!(handler.handle(&jt, &mut drives), tj);
        }
    }
    let mut je = [0u8; 31];
    je[..2].copy_from_slice(b"jE");
    assert_eq!(&handler.handle(&je, &mut drives)[..2], b"Ej");
    let mut commands = vec![drives.measured()];
    for _ in 0..10_000 {
        let out = tick(&mut handler, &mut drives);
        commands.extend(out.command);
        if out.events.sequence_finished {
            break;
        }
    }
    // The commands are f32 round trips of the points: compare within that.
    let sent: Vec<([f64; 6], f64)> = points
        .iter()
        .map(|(q, t)| (q.map(|v| f64::from(v as f32)), *t))
        .collect();
    let slowest = check_joint_run(&config, &sent, &commands, &[0.05, 0.05, 0.05, 0.0]);
    assert!(slowest > 0.03, "stopped on the way ({slowest} rad/s)");
}

/// Runs Cartesian via points (pose, minimum duration) from `q0` with a default tolerance; the
/// outputs of every tick until the sequence ends, or `None` if the sequence is refused.
fn run_cartesian_sequence(
    config: &ValidRobot,
    q0: &[f64],
    points: &[(armgate_core::math::Frame, f64)],
) -> Option<Vec<armgate_core::motion::StepOutput>> {
    let mut ctrl = Controller::new(config);
    let mut arm = IdealArm::new(Joints::from_slice(q0).unwrap());
    let mut now = 0.0;
    ctrl.step(now, &arm.measured()).unwrap();
    ctrl.set_mode(Mode::Cartesian).unwrap();
    for (k, (pose, t)) in points.iter().enumerate() {
        ctrl.set_cartesian_via(k, *pose, *t).unwrap();
    }
    ctrl.start_cartesian_sequence().ok()?;
    let mut outs = Vec::new();
    for _ in 0..200_000 {
        now += config.control_period;
        let out = ctrl.step(now, &arm.measured()).unwrap();
        arm.step(out.command.as_ref());
        outs.push(out);
        if out.events.sequence_finished || out.events.sequence_aborted {
            return Some(outs);
        }
    }
    panic!("the sequence did not end");
}

#[test]
fn random_cartesian_sequences_on_ranger_mk1_blend_within_the_tolerance_and_the_limits() {
    use armgate_core::math::Frame;
    let config = common::robot("ranger-mk1")
        .edit(|c| {
            c.cartesian.max_velocity = [0.1, 0.1, 0.1, 0.3, 0.3, 0.3];
            c.cartesian.max_acceleration = [0.2, 0.2, 0.2, 0.5, 0.5, 0.5];
            // Joints that can follow these Cartesian limits: the acceleration is now enforced
            // on every command (the joint limiter's last clamp), so ranger-mk1's 0.5 rad/s²
            // would slow the blends down below their Cartesian plan.
            for j in c.joints.iter_mut() {
                j.max_rate = 2.0;
                j.drive.max_speed = 2.0;
                j.max_acceleration = 4.0;
            }
        })
        .unwrap();
    let chain = armgate_core::kinematics::Chain::new(&config);
    let home = chain.forward(&MK1_READY).unwrap();
    let mut rng = SplitMix64::new(2026);
    let mut ran = 0;
    for case in 0..12 {
        let n = 2 + (rng.next_u64() % 4) as usize;
        let tolerance = rng.uniform(0.002, 0.03);
        let points: Vec<(Frame, f64)> = (0..n)
            .map(|_| {
                let offset = Vector3::new(
                    rng.uniform(-0.08, 0.08),
                    rng.uniform(-0.08, 0.08),
                    rng.uniform(-0.08, 0.08),
                );
                let mut pose = home;
                pose.translation.vector += offset;
                (
                    pose,
                    if rng.next_f64() < 0.3 {
                        rng.uniform(0.0, 3.0)
                    } else {
                        0.0
                    },
                )
            })
            .collect();
        let config = config
            .clone()
            .edit(|c| c.blend.cartesian = tolerance)
            .unwrap();
        let Some(outs) = run_cartesian_sequence(&config, &MK1_READY, &points) else {
            continue;
        };
        ran += 1;
        let last = outs.last().unwrap();
        let firsts: Vec<_> = outs
            .iter()
            .enumerate()
            .filter(|(_, o)| {
                o.events.workspace_limit || o.events.ik_divergence || o.events.rate_limit
            })
            .take(3)
            .map(|(k, o)| (k, o.events))
            .collect();
        assert!(
            last.events.sequence_finished,
            "case {case}: aborted {:?} after {} {firsts:?}",
            last.events,
            outs.len()
        );
        assert!(
            outs.iter().all(|o| !o.events.ik_divergence),
            "case {case}: WN22"
        );
        let samples: Vec<Vec<f64>> = outs
            .iter()
            .map(|o| {
                o.setpoint
                    .unwrap()
                    .translation
                    .vector
                    .iter()
                    .copied()
                    .collect()
            })
            .collect();
        let corners: Vec<Vec<f64>> = points[..n - 1]
            .iter()
            .map(|(p, _)| p.translation.vector.iter().copied().collect())
            .collect();
        let corner_refs: Vec<&[f64]> = corners.iter().map(|c| &c[..]).collect();
        let [v_max @ .., _, _, _] = config.cartesian.max_velocity;
        let [a_max @ .., _, _, _] = config.cartesian.max_acceleration;
        check_limits(
            &samples,
            config.control_period,
            &v_max,
            &a_max,
            &corner_refs,
            tolerance,
        );
        // Every set-point on a leg's segment or within the tolerance of a via point.
        let start = home.translation.vector;
        let mut polyline = vec![start];
        polyline.extend(points.iter().map(|(p, _)| p.translation.vector));
        for s in &samples {
            let p = Vector3::new(s[0], s[1], s[2]);
            let on_leg = polyline
                .windows(2)
                .map(|w| {
                    let d = w[1] - w[0];
                    let t = ((p - w[0]).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
                    (p - (w[0] + d * t)).norm()
                })
                .fold(f64::INFINITY, f64::min);
            let near = polyline[1..n]
                .iter()
                .map(|c| (p - c).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(
                on_leg < 1e-9 || near <= tolerance + 1e-9,
                "case {case}: {p:?} strays ({on_leg}, {near})"
            );
        }
        // Exactly at the last point.
        let goal = points[n - 1].0.translation.vector;
        assert_eq!(samples.last().unwrap()[..], *goal.as_slice());
    }
    assert!(ran >= 8, "only {ran} of 12 sequences were accepted");
}

#[test]
fn repeated_via_points_and_stretched_legs_blend_without_a_jump() {
    let config = common::robot("ranger-mk1")
        .edit(|c| c.blend.joint = 0.05)
        .unwrap();
    let sweep = sweep_points();
    // The same point twice (a zero-length leg, then one that only waits 1 s), and back.
    let points = [
        sweep[0],
        sweep[0],
        (sweep[0].0, 1.0),
        sweep[1],
        (sweep[2].0, 6.0),
        sweep[3],
    ];
    let commands = run_joint_sequence(&config, &points, &[]);
    check_joint_run(&config, &points, &commands, &[0.05; 5]);
}

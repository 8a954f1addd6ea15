//! What stop_bench measures of a run: the peaks over the limits, the time and distance to rest,
//! the deviation from the path, the arm's least clearance.

use armgate_core::math::{self, Vector3};
use armgate_protocol::client::{Hit, Obstacle};

use crate::Run;

/// One case's figures (the table's columns).
pub struct Figures {
    pub accel: f64,
    pub jerk: Option<f64>,
    pub cartesian: Option<f64>,
    pub time: f64,
    pub distance: f64,
    pub deviation: Option<f64>,
    /// The least gap of any link over the run's ticks (m) and to what.
    pub clearance: Option<(f64, Hit)>,
    pub note: String,
}

/// `L3/B1`, `L5/L2`, `L6/out`: a gap's link and obstacle.
pub fn between(hit: &Hit) -> String {
    match hit.obstacle {
        Obstacle::Box(b) => format!("L{}/B{b}", hit.link),
        Obstacle::Link(l) => format!("L{}/L{l}", hit.link),
        Obstacle::Bounds => format!("L{}/out", hit.link),
    }
}

/// The figures of `run` from tick `from` on; `line`: the straight path (its origin and
/// direction) to measure the deviation from; `boxed`: a box the tool must not enter.
pub fn measure(
    run: &Run,
    from: usize,
    line: Option<(Vector3<f64>, Vector3<f64>)>,
    boxed: Option<[f64; 6]>,
) -> Figures {
    let dt = run.config.control_period;
    let joints = &run.config.config().joints;
    let c = &run.commands;
    let vel = |k: usize| -> Vec<f64> {
        (0..c[k].len())
            .map(|j| (c[k][j] - c[k - 1][j]) / dt)
            .collect()
    };
    let acc = |k: usize| -> Vec<f64> {
        let (v1, v0) = (vel(k), vel(k - 1));
        v1.iter().zip(&v0).map(|(a, b)| (a - b) / dt).collect()
    };
    let (mut accel, mut jerk) = (0.0f64, 0.0f64);
    let mut rest = c.len() - 1;
    for k in from.max(3)..c.len() {
        let a = acc(k);
        let a0 = acc(k - 1);
        for j in 0..a.len() {
            accel = accel.max(a[j].abs() / joints[j].max_acceleration);
            if let Some(jm) = joints[j].max_jerk {
                jerk = jerk.max((a[j] - a0[j]).abs() / dt / jm);
            }
        }
    }
    for k in (from.max(2)..c.len()).rev() {
        if vel(k).iter().any(|v| v.abs() > 1e-9) {
            rest = k;
            break;
        }
        rest = k;
    }
    let mut distance = 0.0;
    let mut deviation = 0.0f64;
    for k in from.max(1)..=rest.min(c.len() - 1) {
        let (p0, p1) = (run.pose(&c[k - 1]), run.pose(&c[k]));
        distance += (p1 - p0).norm();
        if let Some((origin, dir)) = line {
            let d = p1 - origin;
            deviation = deviation.max((d - dir * d.dot(&dir)).norm());
        }
    }
    // Any tick's tool position strictly inside the box put across the way.
    let inside = boxed.is_some_and(|[x0, x1, y0, y1, z0, z1]| {
        c.iter().any(|q| {
            let p = run.pose(q);
            x0 < p.x && p.x < x1 && y0 < p.y && p.y < y1 && z0 < p.z && p.z < z1
        })
    });
    Figures {
        accel,
        jerk: joints.iter().any(|j| j.max_jerk.is_some()).then_some(jerk),
        cartesian: cartesian_peak(run, from),
        time: (rest.saturating_sub(from)) as f64 * dt,
        distance,
        deviation: line.map(|_| deviation),
        clearance: run.body.nearest(),
        note: entered(run, inside),
    }
}

/// The note on what was entered: the tool point the box across the way, a link a contact.
fn entered(run: &Run, tool_in_box: bool) -> String {
    let mut note = Vec::new();
    if tool_in_box {
        note.push("entered box".to_string());
    }
    if let Some(entry) = &run.entered {
        note.push(format!("entered {}", entry.hit));
    }
    note.join(", ")
}

/// The peak change of a Cartesian axis's set-point velocity over a period, from tick `from` on,
/// over that axis's `max_acceleration` (the worst axis); `None` without three set-points in a
/// row.
fn cartesian_peak(run: &Run, from: usize) -> Option<f64> {
    let dt = run.config.control_period;
    let limit = run.config.config().cartesian.max_acceleration;
    let sp = &run.setpoints;
    let mut peak = None;
    for k in from.max(2)..sp.len() {
        let (Some(a), Some(b), Some(c)) = (sp[k - 2], sp[k - 1], sp[k]) else {
            continue;
        };
        let (v0, v1) = (math::diff(&a, &b), math::diff(&b, &c));
        let worst = (0..6)
            .map(|i| (v1[i] - v0[i]).abs() / (dt * dt) / limit[i])
            .fold(0.0, f64::max);
        peak = Some(worst.max(peak.unwrap_or(0.0)));
    }
    peak
}

/// The figures of a motion refused up front.
pub fn refused() -> Figures {
    Figures {
        accel: 0.0,
        jerk: None,
        cartesian: None,
        time: 0.0,
        distance: 0.0,
        deviation: None,
        clearance: None,
        note: "refused".to_string(),
    }
}

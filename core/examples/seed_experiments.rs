//! The seed thesis's simulation experiments (spec §8.2 E7–E9), printed next to the seed's
//! numbers.
//!
//! `cargo run --release -p armgate-core --example seed_experiments [-- --plots DIR]`
//!
//! With `--plots DIR`, also writes `e7-approach.svg` (distance to the unreachable goal and the
//! tool path, WN22 marked) and `e8-e9-rectangle.svg` (the paths and the errors over time).
#![allow(missing_docs, clippy::unwrap_used)]

#[path = "../tests/common/mod.rs"]
mod common;

use std::path::Path;

use armgate_plot::{Figure, Marker, MarkerKind, Panel, Series, write_svg};
use common::experiments::{
    DivergenceRun, RECTANGLE, RectangleRun, TraceTick, UNREACHABLE, blended, corner_passes,
    jerk_limited, off_rectangle, rectangle_config, run_divergence, run_rectangle,
};

fn main() {
    let plots = armgate_plot::plots_dir_from_args().unwrap();
    let d = run_divergence(&common::robot("ranger-mk1"));
    println!("E7: ranger-mk1 sequence ending at the unreachable {UNREACHABLE:?} m");
    println!(
        "  seed without guard: chaotic motion near full extension; with guard: stops near the closest reachable pose, WN22 sent"
    );
    println!(
        "  ours: final tool {:.4?} m, {:.4} m from the goal; shoulder→tool {:.4} m of {:.4} m reach",
        d.final_position.as_slice(),
        d.final_distance,
        d.extension.0,
        d.extension.1
    );
    println!(
        "        moved away from the goal by {:.2e} m in all (largest single tick {:.2e} m); largest joint step {:.4} rad/tick; WN22 raised on {} ticks",
        d.total_retreat, d.worst_retreat, d.max_joint_step, d.divergence_ticks
    );
    println!();
    println!("E8/E9: rectangle (0.5,0.2,0.1)→(0.5,0.2,0.4)→(0.5,−0.2,0.4)→(0.5,−0.2,0.1)→back,");
    println!("v_max 0.05 m/s, a_max 0.10 m/s², constant tool orientation, ideal arm.\n");
    println!(
        "| exp | robot      | seed mean | seed max        | ours mean  | ours max   | at (s) | max joint step/tick | duration (s) |"
    );
    println!(
        "|-----|------------|-----------|-----------------|------------|------------|--------|---------------------|--------------|"
    );
    let mut rectangles = Vec::new();
    for (exp, robot, seed_mean, seed_max) in [
        ("E8", "hybrid", "0.18 mm", "2.02 mm (23 s)"),
        ("E9", "ranger-mk2", "≈ 1 µm", "8 µm (23 s)"),
    ] {
        let r = run_rectangle(&rectangle_config(common::robot(robot)));
        println!(
            "| {exp}  | {robot:<10} | {seed_mean:<9} | {seed_max:<15} | {:>8.2e} m | {:>8.2e} m | {:>6.2} | {:>19.5} | {:>12.2} |",
            r.mean_error, r.max_error, r.max_error_time, r.max_joint_step, r.duration
        );
        println!(
            "|     | tool rpy {:?}; joints start {:.4?} end {:.4?}; WN22 ticks {} |",
            r.rpy,
            &r.first_joints[..],
            &r.last_joints[..],
            r.divergence_ticks
        );
        rectangles.push((exp, robot, r));
    }
    let blends = print_blends();
    if let Some(dir) = plots {
        plot_approach(&dir, &d);
        plot_rectangles(&dir, &rectangles);
        plot_blends(&dir, &blends);
    }
}

/// E8 with blended via points (docs/motion.md, "Blended via points"): each profile with a
/// range of blend tolerances, against the same profile stopping at every corner. Returns the
/// runs (profile, tolerance, run).
fn print_blends() -> Vec<(&'static str, f64, RectangleRun)> {
    let mut runs = Vec::new();
    println!();
    println!("E8 blended: the same rectangle on hybrid, passing corners within a tolerance.");
    println!("closest pass = the largest over the three inner corners of the path's closest");
    println!("approach to that corner; off the edges = the largest distance of the path from the");
    println!("rectangle (how deep the corner is cut).\n");
    println!(
        "| profile       | tolerance (mm) | duration (s) | saved (s, %)   | closest pass (mm) | off the edges (mm) |"
    );
    println!(
        "|---------------|----------------|--------------|----------------|-------------------|--------------------|"
    );
    let trapezoid = rectangle_config(common::robot("hybrid"));
    for (profile, config) in [
        ("trapezoid", trapezoid.clone()),
        ("jerk-limited", jerk_limited(trapezoid)),
    ] {
        let stopping = run_rectangle(&config).duration;
        for tolerance in [0.0, 0.002, 0.005, 0.01, 0.02, 0.05] {
            let run = run_rectangle(&blended(config.clone(), tolerance));
            let pass = corner_passes(&run).into_iter().fold(0.0, f64::max);
            let off = run
                .trace
                .iter()
                .map(|t| off_rectangle(&t.tool))
                .fold(0.0, f64::max);
            let saved = stopping - run.duration;
            println!(
                "| {profile:<13} | {:>14.1} | {:>12.2} | {saved:>5.2} ({:>4.1} %) | {:>17.3} | {:>18.3} |",
                tolerance * 1e3,
                run.duration,
                saved / stopping * 100.0,
                pass * 1e3,
                off * 1e3
            );
            runs.push((profile, tolerance, run));
        }
    }
    runs
}

/// `e8-blended.svg`: the first corner up close for a few tolerances, and the set-point's speed
/// over the run, stopping and blended, for both profiles.
fn plot_blends(dir: &Path, runs: &[(&str, f64, RectangleRun)]) {
    let [_, corner @ .., _, _, _] = RECTANGLE;
    let [c, ..] = corner;
    let near = |t: &TraceTick| (t.tool.y - c[1]).abs() <= 0.07 && (t.tool.z - c[2]).abs() <= 0.07;
    let mut path = Panel::new(
        "the first corner (0.5, 0.2, 0.4) up close, y–z view",
        "y (m)",
        "z (m)",
    )
    .equal_aspect();
    let mut speed = Panel::new("set-point speed", "t (s)", "speed (m/s)");
    let shown = [0.0, 0.01, 0.02, 0.05];
    for (k, (profile, tolerance, run)) in runs
        .iter()
        .filter(|(_, t, _)| shown.contains(t))
        .enumerate()
    {
        let name = format!("{profile}, {:.0} mm", tolerance * 1e3);
        if *profile == "trapezoid" {
            path = path.series(
                Series::line(
                    name.clone(),
                    xy(run
                        .trace
                        .iter()
                        .filter(|t| near(t))
                        .map(|t| (t.tool.y, t.tool.z))),
                )
                .color(k + 1),
            );
        }
        if *tolerance == 0.0 || *tolerance == 0.05 {
            let speeds = run.trace.windows(2).filter_map(|w| match w {
                [a, b] => Some((b.t, (b.setpoint - a.setpoint).norm() / (b.t - a.t))),
                _ => None,
            });
            speed = speed.series(Series::line(name, xy(speeds)).color(k + 1));
        }
    }
    let figure = Figure::new(
        "E8 with blended via points: corners cut within the tolerance, no stop",
        vec![path, speed],
    )
    .columns(2)
    .panel_size(640, 480);
    write(dir, "e8-blended.svg", &figure);
}

fn xy(points: impl IntoIterator<Item = (f64, f64)>) -> Vec<(f64, f64)> {
    points.into_iter().collect()
}

/// The start of each run of WN22 ticks.
fn divergence_markers(trace: &[TraceTick]) -> Vec<Marker> {
    let mut before = false;
    let mut markers = Vec::new();
    for tick in trace {
        if tick.diverging && !before {
            markers.push(Marker::new(tick.t, "WN22", MarkerKind::Warning));
        }
        before = tick.diverging;
    }
    markers
}

fn plot_approach(dir: &Path, d: &DivergenceRun) {
    let distance = Panel::new(
        "distance from the unreachable goal (guard on: no chaotic motion)",
        "t (s)",
        "distance (m)",
    )
    .series(Series::line(
        "tool",
        xy(d.trace.iter().map(|k| (k.t, k.error))),
    ))
    .markers(divergence_markers(&d.trace));
    let [a, b, _] = d.waypoints;
    let path = Panel::new(
        format!("tool path, top view (goal {UNREACHABLE:?} m is off the chart)"),
        "x (m)",
        "y (m)",
    )
    .series(Series::line(
        "tool",
        xy(d.trace.iter().map(|k| (k.tool.x, k.tool.y))),
    ))
    .series(Series::points("via points 1, 2", [(a.x, a.y), (b.x, b.y)]))
    .series(Series::points(
        "where it stops",
        [(d.final_position.x, d.final_position.y)],
    ))
    .equal_aspect();
    let figure = Figure::new(
        "E7: ranger-mk1 sent towards an unreachable point, divergence guard on",
        vec![distance, path],
    )
    .columns(2)
    .panel_size(640, 480);
    write(dir, "e7-approach.svg", &figure);
}

fn plot_rectangles(dir: &Path, runs: &[(&str, &str, RectangleRun)]) {
    let mut path = Panel::new("tool path, y–z view (x = 0.5 m)", "y (m)", "z (m)").equal_aspect();
    let mut panels = Vec::new();
    for (k, (exp, robot, r)) in runs.iter().enumerate() {
        path = path.series(
            Series::line(
                format!("{exp} {robot}"),
                xy(r.trace.iter().map(|t| (t.tool.y, t.tool.z))),
            )
            .color(k + 1),
        );
        // The seed's errors were millimetres (E8) and micrometres (E9); ours are far smaller:
        // each on a scale of its own.
        let (scale, unit) = match r.max_error {
            e if e > 1e-4 => (1e3, "mm"),
            e if e > 1e-7 => (1e6, "µm"),
            _ => (1e9, "nm"),
        };
        panels.push(
            Panel::new(
                format!(
                    "{exp} {robot}: distance from the leg's line (mean {:.3} {unit}, max {:.3} {unit})",
                    r.mean_error * scale,
                    r.max_error * scale
                ),
                "t (s)",
                format!("error ({unit})"),
            )
            .series(
                Series::line(
                    "tool",
                    xy(r.trace.iter().map(|t| (t.t, t.error * scale))),
                )
                .color(k + 1),
            )
            .markers(divergence_markers(&r.trace)),
        );
    }
    path = path.series(
        Series::reference("ideal rectangle", RECTANGLE.iter().map(|p| (p[1], p[2]))).color(0),
    );
    panels.insert(0, path);
    let figure = Figure::new(
        "E8/E9: the rectangle at v_max 0.05 m/s, a_max 0.10 m/s², ideal arm",
        panels,
    )
    .panel_size(900, 340);
    write(dir, "e8-e9-rectangle.svg", &figure);
}

fn write(dir: &Path, name: &str, figure: &Figure) {
    let path = dir.join(name);
    write_svg(&path, figure).unwrap();
    println!("wrote {}", path.display());
}

//! The figures of `armgate plot`, from the logs.

use armgate_plot::{Figure, Marker, MarkerKind, Panel, Series};

use super::logs::{Logs, StateLog};

/// Colours (palette indices), the same in every panel.
const MEASURED: usize = 0;
const COMMANDED: usize = 1;
const AXES: [usize; 3] = [2, 4, 3];
const START: usize = 2;
const END: usize = 6;

/// The tool path in three views (top x–y, front x–z, side y–z, each to scale) and the tool's
/// x, y, z over time with the markers.
pub fn tool_path(logs: &Logs, title: &str) -> Figure {
    let s = &logs.state;
    let view = |name: &str, a: usize, b: usize| {
        let axis = ["x", "y", "z"];
        let label = |k: usize| format!("{} (m)", axis.get(k).copied().unwrap_or("?"));
        let pairs = |values: &[Vec<f64>; 3]| -> Vec<(f64, f64)> {
            match (values.get(a), values.get(b)) {
                (Some(u), Some(v)) => u.iter().copied().zip(v.iter().copied()).collect(),
                _ => Vec::new(),
            }
        };
        let measured = pairs(&s.tool);
        let (start, end) = (measured.first().copied(), measured.last().copied());
        let mut panel = Panel::new(name, label(a), label(b))
            .series(Series::line("measured", measured).color(MEASURED))
            .series(Series::points("start", start).color(START))
            .series(Series::points("end", end).color(END))
            .equal_aspect();
        let setpoint = pairs(&s.setpoint);
        if setpoint.iter().any(|(u, v)| u.is_finite() && v.is_finite()) {
            panel =
                panel.series(Series::reference("Cartesian set-point", setpoint).color(COMMANDED));
        }
        panel
    };
    let mut over_time =
        Panel::new("tool position over time", "t (s)", "position (m)").markers(markers(logs));
    for ((name, values), color) in ["x", "y", "z"].iter().zip(&s.tool).zip(AXES) {
        over_time = over_time.series(Series::line(*name, timed(&s.t, values)).color(color));
    }
    Figure::new(
        format!("{title}: tool path"),
        vec![
            view("top view, x–y", 0, 1),
            view("front view, x–z", 0, 2),
            view("side view, y–z", 1, 2),
            over_time,
        ],
    )
    .columns(2)
    .panel_size(640, 480)
}

/// One panel per joint: measured position and command over time, with the markers.
pub fn joints(logs: &Logs, title: &str) -> Figure {
    let s = &logs.state;
    let markers = markers(logs);
    let panels: Vec<Panel> =
        s.q.iter()
            .zip(&s.cmd)
            .enumerate()
            .map(|(k, (q, cmd))| {
                Panel::new(
                    format!("joint {}", k + 1),
                    "t (s)",
                    format!("q{} (rad; m if prismatic)", k + 1),
                )
                .series(Series::line("measured", timed(&s.t, q)).color(MEASURED))
                .series(Series::line("command", timed(&s.t, cmd)).color(COMMANDED))
                .markers(markers.iter().cloned())
            })
            .collect();
    let columns = if panels.len() > 3 { 2 } else { 1 };
    Figure::new(format!("{title}: joints"), panels)
        .columns(columns)
        .panel_size(640, 340)
}

fn timed(t: &[f64], values: &[f64]) -> Vec<(f64, f64)> {
    t.iter().copied().zip(values.iter().copied()).collect()
}

/// The mode at the start and at each change, and the warnings and ER replies (labelled with
/// their code; one marker for a run of the same code within 1 % of the log's time span).
pub fn markers(logs: &Logs) -> Vec<Marker> {
    let mut markers = mode_changes(&logs.state);
    let span = match (logs.state.t.first(), logs.state.t.last()) {
        (Some(a), Some(b)) => b - a,
        _ => 0.0,
    };
    let mut last: Option<(f64, &str)> = None;
    for notice in &logs.notices {
        let code = notice.text.split_whitespace().next().unwrap_or("?");
        if let Some((t, c)) = last
            && c == code
            && notice.t - t <= span * 0.01
        {
            continue;
        }
        markers.push(Marker::new(notice.t, code, MarkerKind::Warning));
        last = Some((notice.t, code));
    }
    markers
}

fn mode_changes(s: &StateLog) -> Vec<Marker> {
    let mut markers: Vec<Marker> = Vec::new();
    let mut previous: Option<&str> = None;
    for (t, mode) in s.t.iter().zip(&s.mode) {
        if previous != Some(mode.as_str()) {
            markers.push(Marker::new(*t, mode.as_str(), MarkerKind::Event));
            previous = Some(mode);
        }
    }
    markers
}

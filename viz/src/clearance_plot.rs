//! `armgate-viz clearance`: the minimum distances of a recorded run over time, as an SVG: the
//! least gap to the exclusion boxes, to the bounds and between links, from the recording's
//! `/clearance` channel (what the recorder measured with core's own distance functions at
//! every recorded pose), with the margin drawn and the warnings and errors of `/log` as
//! markers.

use std::path::Path;

use armgate_plot::{Figure, Marker, MarkerKind, Panel, Series};
use serde_json::Value;

use crate::foxglove::{Level, Topic};

/// The gaps of one recorded pose (m; NaN where nothing of the kind is checked).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// The log time (s).
    pub t: f64,
    /// The least gap to a box.
    pub boxes: f64,
    /// The least room inside the bounds.
    pub bounds: f64,
    /// The least gap between two links.
    pub links: f64,
    /// The margin.
    pub margin: f64,
}

/// What a recording holds for the plot.
#[derive(Clone, Debug, Default)]
pub struct Run {
    /// One row per recorded pose, in time order.
    pub rows: Vec<Row>,
    /// The warnings and errors of `/log`: time (s) and the text's first word (`ER21`).
    pub notices: Vec<(f64, String)>,
}

/// Reads the `/clearance` and `/log` messages of an MCAP recording (the whole file is read
/// into memory: about 1 MB a simulated second for ur5).
pub fn read(path: &Path) -> Result<Run, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let stream =
        mcap::MessageStream::new(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut run = Run::default();
    for message in stream {
        let message = message.map_err(|e| format!("{}: {e}", path.display()))?;
        let topic = message.channel.topic.as_str();
        if topic != Topic::Clearance.name() && topic != Topic::Log.name() {
            continue;
        }
        let Ok(value) = serde_json::from_slice::<Value>(&message.data) else {
            continue;
        };
        let t = message.log_time as f64 * 1e-9;
        if topic == Topic::Log.name() {
            if value.get("level").and_then(Value::as_u64) >= Some(Level::Warning as u64) {
                let text = value.get("message").and_then(Value::as_str);
                let text = text.unwrap_or_default();
                let word = text.split_whitespace().next().unwrap_or_default();
                run.notices.push((t, word.to_owned()));
            }
            continue;
        }
        let get = |key: &str| value.get(key).and_then(Value::as_f64).unwrap_or(f64::NAN);
        run.rows.push(Row {
            t,
            boxes: get("boxes"),
            bounds: get("bounds"),
            links: get("links"),
            margin: get("margin"),
        });
    }
    if run.rows.is_empty() {
        return Err(format!(
            "{}: no /clearance messages (a recording of a robot without a body, or made \
             before armgate recorded the body)",
            path.display()
        ));
    }
    run.rows.sort_by(|a, b| a.t.total_cmp(&b.t));
    Ok(run)
}

/// Which gap a line shows.
type Pick = fn(&Row) -> f64;

/// Palette indices, as the other plots use them.
const BOXES: usize = 0;
const BOUNDS: usize = 2;
const LINKS: usize = 4;
const MARGIN: usize = 6;

/// The figure: one panel, the three least gaps over time, the margin, the notices.
pub fn figure(run: &Run, title: &str) -> Figure {
    let series =
        |pick: Pick| -> Vec<(f64, f64)> { run.rows.iter().map(|r| (r.t, pick(r))).collect() };
    let mut panel = Panel::new(
        "minimum distance at the measured joints",
        "t (s)",
        "distance (m)",
    );
    let kinds: [(&str, Pick, usize); 3] = [
        ("to the boxes", |r| r.boxes, BOXES),
        ("inside the bounds", |r| r.bounds, BOUNDS),
        ("between links", |r| r.links, LINKS),
    ];
    for (name, pick, color) in kinds {
        let points = series(pick);
        if points.iter().any(|(_, v)| v.is_finite()) {
            panel = panel.series(Series::line(name, points).color(color));
        }
    }
    let margin = series(|r| r.margin);
    panel = panel
        .series(Series::reference("margin", margin).color(MARGIN))
        .include_y(0.0)
        .markers(
            run.notices
                .iter()
                .map(|(t, word)| Marker::new(*t, word.clone(), MarkerKind::Warning)),
        );
    Figure::new(format!("{title}: clearance"), vec![panel])
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;
    use armgate_plot::inspect::SvgSummary;

    #[test]
    fn the_figure_has_each_kind_the_margin_and_the_notices() {
        let rows: Vec<Row> = (0..200)
            .map(|k| {
                let t = f64::from(k) * 0.02;
                Row {
                    t,
                    boxes: 0.3 - 0.05 * t,
                    bounds: 0.8,
                    links: f64::NAN,
                    margin: 0.01,
                }
            })
            .collect();
        let run = Run {
            rows,
            notices: vec![(2.0, "ER21".to_owned())],
        };
        let dir = std::env::temp_dir().join(format!("armgate-clearance-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("clearance.svg");
        armgate_plot::write_svg(&path, &figure(&run, "run")).unwrap();
        let svg = SvgSummary::parse(&std::fs::read_to_string(&path).unwrap()).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        for text in [
            "run: clearance",
            "to the boxes",
            "inside the bounds",
            "margin",
            "ER21",
        ] {
            assert!(svg.has_text(text), "{text}: {:?}", svg.texts);
        }
        // No link pair is checked: no such line.
        assert!(!svg.has_text("between links"));
        assert!(svg.lines_with_points(50) >= 2, "{:?}", svg.polylines);
    }
}

//! `armgate plot` on a small log fixture (tests/fixtures/log: 6 joints, off → joint →
//! cartesian, a circle in x–z, an ER20 reply and two WN22 warnings): the SVGs hold the
//! expected series, axis labels and markers.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

use std::path::{Path, PathBuf};
use std::process::Command;

use armgate_plot::inspect::SvgSummary;

fn fixture() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/log")
}

fn svg(path: &Path) -> SvgSummary {
    SvgSummary::parse(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// How many texts are exactly `label` (marker labels are drawn with a leading space).
fn count(svg: &SvgSummary, label: &str) -> usize {
    svg.texts.iter().filter(|t| t.trim() == label).count()
}

#[test]
fn plot_writes_the_tool_path_and_the_joints() {
    let out = std::env::temp_dir().join(format!("armgate-plot-cli-{}", std::process::id()));
    let run = Command::new(env!("CARGO_BIN_EXE_armgate"))
        .arg("plot")
        .arg(fixture())
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(run.status.success(), "{run:?}");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert_eq!(stdout.lines().count(), 2, "{stdout}");

    let path = svg(&out.join("tool-path.svg"));
    for text in [
        "tool path",
        "top view, x–y",
        "front view, x–z",
        "side view, y–z",
        "tool position over time",
        "x (m)",
        "z (m)",
        "t (s)",
        "position (m)",
        "measured",
        "Cartesian set-point",
        "start",
        "end",
        "mode change",
        "warning / error",
    ] {
        assert!(path.has_text(text), "{text:?} not in {:?}", path.texts);
    }
    // Measured path and set-point (cartesian rows only) in the x–y and x–z views, x, y, z
    // over time: long lines. In the y–z view y is constant: one pixel column, thinned to its
    // ends and extremes.
    assert_eq!(path.lines_with_points(20), 7, "{:?}", path.polylines);
    assert_eq!(path.polylines.iter().filter(|p| p.points == 4).count(), 2);
    // Markers on the time panel: the modes in order, ER20 and one WN22 for two warnings
    // 40 ms apart.
    for label in ["off", "joint", "cartesian", "ER20", "WN22"] {
        assert_eq!(count(&path, label), 1, "{label}: {:?}", path.texts);
    }

    let joints = svg(&out.join("joints.svg"));
    for k in 1..=6 {
        assert!(joints.has_text(&format!("joint {k}")));
        assert!(joints.has_text(&format!("q{k} (rad; m if prismatic)")));
    }
    // Six measured lines and six commands (none while off).
    assert_eq!(joints.lines_with_points(20), 12, "{:?}", joints.polylines);
    assert_eq!(count(&joints, "WN22"), 6);
    assert_eq!(count(&joints, "cartesian"), 6);
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn plot_without_a_state_log_exits_2_and_names_the_file() {
    let empty = std::env::temp_dir().join(format!("armgate-plot-empty-{}", std::process::id()));
    std::fs::create_dir_all(&empty).unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_armgate"))
        .arg("plot")
        .arg(&empty)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("state.csv"), "{stderr}");
    std::fs::remove_dir_all(&empty).unwrap();
}

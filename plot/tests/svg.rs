//! A figure written to disk holds what was asked for: titles, axis labels, one line per
//! series segment, markers with their labels; long series are thinned.
#![allow(missing_docs, clippy::unwrap_used)]

use armgate_plot::inspect::SvgSummary;
use armgate_plot::{Figure, Marker, MarkerKind, Panel, Series, write_svg};

fn temp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("armgate-plot-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn a_figure_holds_its_series_labels_and_markers() {
    let t: Vec<f64> = (0..20_000).map(|k| k as f64 * 1e-3).collect();
    let mut broken: Vec<(f64, f64)> = t.iter().map(|t| (*t, t.cos())).collect();
    broken[10_000].1 = f64::NAN; // two segments
    let joints = Panel::new("joint 1", "t (s)", "q1 (rad)")
        .series(Series::line("measured", t.iter().map(|t| (*t, t.sin()))))
        .series(Series::line("command", broken))
        .markers([
            Marker::new(2.0, "cartesian", MarkerKind::Event),
            Marker::new(12.5, "WN22", MarkerKind::Warning),
        ]);
    let path = Panel::new("tool path, x–z", "x (m)", "z (m)")
        .series(Series::reference(
            "ideal",
            (0..=360).map(|d| {
                let a = f64::from(d).to_radians();
                (a.cos() * 0.2, 0.5 + a.sin() * 0.2)
            }),
        ))
        .equal_aspect();
    let file = temp("figure.svg");
    write_svg(&file, &Figure::new("A <test> & more", vec![joints, path])).unwrap();

    let svg = SvgSummary::parse(&std::fs::read_to_string(&file).unwrap()).unwrap();
    for text in [
        "A <test> & more",
        "joint 1",
        "t (s)",
        "q1 (rad)",
        "x (m)",
        "z (m)",
        "measured",
        "command",
        "ideal",
        "cartesian",
        "WN22",
        "mode change",
        "warning / error",
    ] {
        assert!(svg.has_text(text), "no text {text:?} in {:?}", svg.texts);
    }
    // measured, two command segments, the circle: long lines; 20 000 samples thinned to at
    // most 4 per pixel column.
    assert_eq!(svg.lines_with_points(50), 4, "{:?}", svg.polylines);
    assert!(svg.polylines.iter().all(|p| p.points <= 4 * 900));
    assert!(svg.polylines.iter().any(|p| p.stroke == "#0072B2"));
}

#[test]
fn not_an_svg_is_refused() {
    assert!(SvgSummary::parse("").is_none());
    assert!(SvgSummary::parse("<html></html>").is_none());
    assert!(SvgSummary::parse("<svg width=\"1\"><text>a</text>").is_none());
}

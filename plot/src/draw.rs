//! Drawing a [`Figure`] with plotters' SVG backend.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::thin::{Grid, thin};
use crate::{Figure, Marker, MarkerKind, Panel, Series, Style};

/// Drawing or writing the SVG failed.
#[derive(Debug)]
pub struct PlotError(String);

impl std::fmt::Display for PlotError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PlotError {}

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for PlotError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        Self(e.to_string())
    }
}

/// Colour-blind-safe colours (Okabe and Ito), then darker greys.
const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(120, 120, 120),
];
const EVENT: RGBColor = RGBColor(110, 110, 110);
const WARNING: RGBColor = RGBColor(200, 0, 0);

const FONT: &str = "sans-serif";
/// Layout (pixels): around each panel, the axis label areas, the panel and figure titles.
const MARGIN: u32 = 12;
const X_LABEL_AREA: u32 = 42;
const Y_LABEL_AREA: u32 = 70;
const CAPTION: u32 = 16;
const TITLE: u32 = 22;
/// Rows of marker labels, and the height of one (pixels).
const MARKER_ROWS: u32 = 3;
const MARKER_ROW: u32 = 13;
/// Height of one legend entry (pixels).
const LEGEND_ROW: u32 = 19;

/// Draws `figure` into an SVG file at `path`.
pub fn write_svg(path: &Path, figure: &Figure) -> Result<(), PlotError> {
    let columns = figure.columns.max(1);
    let rows = figure.panels.len().div_ceil(columns).max(1);
    let (w, h) = figure.panel_size;
    let size = (
        w.saturating_mul(u32::try_from(columns).unwrap_or(1)),
        h.saturating_mul(u32::try_from(rows).unwrap_or(1))
            .saturating_add(TITLE * 2),
    );
    let root = SVGBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(&figure.title, (FONT, TITLE))?;
    let areas = root.split_evenly((rows, columns));
    for (area, panel) in areas.iter().zip(&figure.panels) {
        draw_panel(area, panel)?;
    }
    root.present()?;
    Ok(())
}

fn draw_panel(area: &DrawingArea<SVGBackend<'_>, Shift>, panel: &Panel) -> Result<(), PlotError> {
    let (w, h) = area.dim_in_pixel();
    let pixels = (
        w.saturating_sub(2 * MARGIN + Y_LABEL_AREA).max(1),
        h.saturating_sub(2 * MARGIN + X_LABEL_AREA + CAPTION * 2)
            .max(1),
    );
    let grid = ranges(panel, pixels);
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (FONT, CAPTION))
        .margin(MARGIN)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(grid.x.0..grid.x.1, grid.y.0..grid.y.1)?;
    chart
        .configure_mesh()
        .max_light_lines(0)
        .bold_line_style(BLACK.mix(0.12))
        .x_desc(&panel.x_label)
        .y_desc(&panel.y_label)
        .x_label_formatter(&|v| tick_label(*v, grid.x))
        .y_label_formatter(&|v| tick_label(*v, grid.y))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        .draw()?;

    // In order: a thin reference drawn after a thick line shows on top of it.
    let mut labelled = false;
    for (k, series) in panel.series.iter().enumerate() {
        let color = PALETTE
            .get(series.color.unwrap_or(k) % PALETTE.len())
            .copied()
            .unwrap_or(BLACK);
        labelled |= draw_series(&mut chart, series, color, &grid)?;
    }
    labelled |= draw_markers(&mut chart, panel, &grid)?;
    if labelled {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()?;
    }
    Ok(())
}

type Chart<'a, 'b> = ChartContext<
    'a,
    SVGBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// Draws one series; true if it has a legend entry.
fn draw_series(
    chart: &mut Chart<'_, '_>,
    series: &Series,
    color: RGBColor,
    grid: &Grid,
) -> Result<bool, PlotError> {
    let style = match series.style {
        Style::Line | Style::Points => color.stroke_width(2),
        Style::Reference => color.stroke_width(1),
    };
    let mut first = true;
    for segment in series
        .points
        .split(|(x, y)| !x.is_finite() || !y.is_finite())
        .filter(|s| !s.is_empty())
    {
        let points = thin(segment, grid);
        let drawn = match series.style {
            Style::Points => chart.draw_series(
                points
                    .into_iter()
                    .map(|p| Circle::new(p, 2, style.filled())),
            )?,
            Style::Line | Style::Reference => chart.draw_series(LineSeries::new(points, style))?,
        };
        if first && !series.name.is_empty() {
            let legend = style.stroke_width(2);
            let drawn = drawn.label(&series.name);
            if series.style == Style::Points {
                drawn.legend(move |(x, y)| Circle::new((x + 10, y), 3, legend.filled()));
            } else {
                drawn.legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], legend));
            }
        }
        first = false;
    }
    Ok(!first && !series.name.is_empty())
}

/// Draws the panel's markers: a vertical line each, the label at the foot in the headroom
/// kept free for it (staggered over three rows, by x); true if there were any (each kind
/// present then has a legend entry).
fn draw_markers(chart: &mut Chart<'_, '_>, panel: &Panel, grid: &Grid) -> Result<bool, PlotError> {
    let mut markers: Vec<&Marker> = panel.markers.iter().filter(|m| m.x.is_finite()).collect();
    markers.sort_by(|a, b| a.x.total_cmp(&b.x));
    let (y0, y1) = grid.y;
    let row = (y1 - y0) / f64::from(grid.pixels.1.max(1)) * f64::from(MARKER_ROW);
    for kind in [MarkerKind::Event, MarkerKind::Warning] {
        let (color, name) = match kind {
            MarkerKind::Event => (EVENT, "mode change"),
            MarkerKind::Warning => (WARNING, "warning / error"),
        };
        let of_kind = || markers.iter().enumerate().filter(|(_, m)| m.kind == kind);
        if of_kind().next().is_none() {
            continue;
        }
        let line = color.mix(0.6).stroke_width(1);
        chart
            .draw_series(
                of_kind().map(|(_, m)| PathElement::new(vec![(m.x, y0), (m.x, y1)], line)),
            )?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x + 10, y - 6), (x + 10, y + 6)], line));
        let font = (FONT, 11).into_font().color(&color);
        chart.draw_series(of_kind().map(|(k, m)| {
            // The text hangs from this height: rows counted up from the foot of the panel.
            let level = 2.8 - f64::from(u32::try_from(k).unwrap_or(0) % MARKER_ROWS);
            Text::new(
                format!(" {}", m.label),
                (m.x, y0 + row * level),
                font.clone(),
            )
        }))?;
    }
    Ok(!markers.is_empty())
}

/// The axis ranges: the data (and markers) with a 4 % margin, or the panel's fixed y range;
/// widened to the same scale on both axes for `equal_aspect`.
fn ranges(panel: &Panel, pixels: (u32, u32)) -> Grid {
    let finite = || {
        panel
            .series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|(x, y)| x.is_finite() && y.is_finite())
    };
    let bounds = |values: &mut dyn Iterator<Item = f64>| {
        values.fold(None, |b: Option<(f64, f64)>, v| {
            Some(b.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))))
        })
    };
    let markers = panel.markers.iter().map(|m| m.x).filter(|x| x.is_finite());
    let x = pad(bounds(&mut finite().map(|p| p.0).chain(markers)));
    // A fixed range is kept as it is: its owner left room for the legend.
    let y = panel.y_range.unwrap_or_else(|| {
        let values = finite()
            .map(|p| p.1)
            .chain(panel.y_includes.iter().copied());
        headroom(
            pad(bounds(&mut values.filter(|v| v.is_finite()))),
            pixels.1,
            panel,
        )
    });
    let (x, y) = if panel.equal_aspect {
        equal_scale(x, y, pixels)
    } else {
        (x, y)
    };
    Grid { x, y, pixels }
}

/// Widens the y range so that the legend (at the top) and the marker labels (at the foot)
/// have room of their own and cover no data.
fn headroom((lo, hi): (f64, f64), height: u32, panel: &Panel) -> (f64, f64) {
    let named = panel.series.iter().filter(|s| !s.name.is_empty()).count();
    let kinds = [MarkerKind::Event, MarkerKind::Warning]
        .iter()
        .filter(|k| panel.markers.iter().any(|m| m.kind == **k))
        .count();
    let entries = u32::try_from(named + kinds).unwrap_or(u32::MAX);
    let top = if entries > 0 {
        entries.saturating_mul(LEGEND_ROW).saturating_add(16)
    } else {
        0
    };
    let bottom = if panel.markers.is_empty() {
        0
    } else {
        MARKER_ROW * MARKER_ROWS + 6
    };
    let free = f64::from(height.saturating_sub(top + bottom).max(height / 3).max(1));
    let per_px = (hi - lo) / free;
    (
        lo - per_px * f64::from(bottom),
        hi + per_px * f64::from(top),
    )
}

/// A tick value with as many decimals as the range needs (a tenth of it shows), and no "-0".
fn tick_label(v: f64, (lo, hi): (f64, f64)) -> String {
    let step = (hi - lo).abs() / 10.0;
    let decimals = if step > 0.0 && step.is_finite() {
        (-step.log10().floor()).clamp(0.0, 12.0) as usize
    } else {
        3
    };
    let text = format!("{v:.decimals$}");
    if text
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        text.trim_start_matches('-').to_owned()
    } else {
        text
    }
}

fn pad(bounds: Option<(f64, f64)>) -> (f64, f64) {
    match bounds {
        None => (0.0, 1.0),
        Some((lo, hi)) if hi - lo <= f64::EPSILON * hi.abs().max(1.0) => {
            let d = (lo.abs() * 0.1).max(1e-3);
            (lo - d, hi + d)
        }
        Some((lo, hi)) => {
            let d = (hi - lo) * 0.04;
            (lo - d, hi + d)
        }
    }
}

/// Widens the narrower range about its centre so that a unit has the same length on both axes.
fn equal_scale(x: (f64, f64), y: (f64, f64), (w, h): (u32, u32)) -> ((f64, f64), (f64, f64)) {
    let per_px = ((x.1 - x.0) / f64::from(w)).max((y.1 - y.0) / f64::from(h));
    let widen = |(lo, hi): (f64, f64), px: u32| {
        let c = 0.5 * (lo + hi);
        let half = 0.5 * per_px * f64::from(px);
        (c - half, c + half)
    };
    (widen(x, w), widen(y, h))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Marker;

    #[test]
    fn equal_aspect_gives_both_axes_the_same_scale() {
        let panel = Panel::new("p", "x (m)", "z (m)")
            .series(Series::line("a", [(0.0, 0.0), (1.0, 0.1)]))
            .equal_aspect();
        let g = ranges(&panel, (400, 200));
        let sx = (g.x.1 - g.x.0) / 400.0;
        let sy = (g.y.1 - g.y.0) / 200.0;
        assert!((sx - sy).abs() < 1e-12, "{sx} {sy}");
        assert!(g.x.0 < 0.0 && g.x.1 > 1.0 && g.y.0 < 0.0 && g.y.1 > 0.1);
    }

    #[test]
    fn tick_labels_have_the_decimals_the_range_needs() {
        assert_eq!(tick_label(-0.0001, (-1.0, 1.0)), "0.0");
        assert_eq!(tick_label(0.26, (0.0, 1.0)), "0.3");
        assert_eq!(tick_label(0.0126, (0.0, 0.05)), "0.013");
        assert_eq!(tick_label(120.0, (0.0, 300.0)), "120");
    }

    #[test]
    fn ranges_cover_markers_and_survive_empty_and_flat_data() {
        let panel = Panel::new("p", "t (s)", "v")
            .series(Series::line(
                "flat",
                [(0.0, 2.0), (1.0, 2.0), (f64::NAN, 5.0)],
            ))
            .markers([Marker::new(3.0, "WN22", MarkerKind::Warning)]);
        let g = ranges(&panel, (100, 100));
        assert!(g.x.0 < 0.0 && g.x.1 > 3.0, "{:?}", g.x);
        assert!(g.y.0 < 2.0 && g.y.1 > 2.0 && g.y.1 < 5.0, "{:?}", g.y);
        let empty = ranges(&Panel::new("p", "x", "y"), (100, 100));
        assert_eq!((empty.x, empty.y), ((0.0, 1.0), (0.0, 1.0)));
    }
}

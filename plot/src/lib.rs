//! SVG charts for armgate's tools and examples: the `armgate plot` command and the experiment
//! and bench examples describe what to draw ([`Figure`], [`Panel`], [`Series`], [`Marker`]);
//! [`write_svg`] draws it with plotters' SVG backend.
//!
//! ```no_run
//! use armgate_plot::{Figure, Panel, Series, write_svg};
//!
//! let t: Vec<f64> = (0..100).map(|k| k as f64 * 0.01).collect();
//! let panel = Panel::new("joint 1", "t (s)", "q (rad)")
//!     .series(Series::line("measured", t.iter().map(|t| (*t, t.sin()))));
//! write_svg("joint1.svg".as_ref(), &Figure::new("A move", vec![panel]))
//!     .expect("written");
//! ```
//!
//! The SVG backend writes text as `<text>` elements that the viewer renders, so no font files,
//! fontconfig or freetype are needed to draw. Long series are thinned to what the picture can
//! show (see [`thin`]), so a 30 s run at 2 ms per sample stays a small file.

mod args;
mod draw;
pub mod inspect;
pub mod thin;

pub use args::plots_dir_from_args;
pub use draw::{PlotError, write_svg};

/// A picture: a title over panels laid out in a grid, row by row.
#[derive(Clone, Debug)]
pub struct Figure {
    /// Drawn across the top.
    pub title: String,
    /// The charts.
    pub panels: Vec<Panel>,
    /// Panels per row.
    pub columns: usize,
    /// Size of one panel (pixels).
    pub panel_size: (u32, u32),
}

impl Figure {
    /// One column of 900 × 360 px panels.
    pub fn new(title: impl Into<String>, panels: Vec<Panel>) -> Self {
        Self {
            title: title.into(),
            panels,
            columns: 1,
            panel_size: (900, 360),
        }
    }

    /// Lays the panels out `columns` to a row.
    pub fn columns(mut self, columns: usize) -> Self {
        self.columns = columns.max(1);
        self
    }

    /// Sets the size of each panel (pixels).
    pub fn panel_size(mut self, width: u32, height: u32) -> Self {
        self.panel_size = (width, height);
        self
    }
}

/// One chart: axes with their labels (units in brackets), series and markers. The legend
/// goes top right and the marker labels at the foot, each in room of its own above and below
/// the data.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Drawn above the chart.
    pub title: String,
    /// The x axis label, e.g. "t (s)".
    pub x_label: String,
    /// The y axis label, e.g. "q (rad)".
    pub y_label: String,
    /// The data.
    pub series: Vec<Series>,
    /// Vertical lines at events (mode changes, warnings).
    pub markers: Vec<Marker>,
    /// The y range; from the data, with room for the legend and marker labels, if none.
    pub y_range: Option<(f64, f64)>,
    /// Values the y range reaches, with the data (such as 0 for a load).
    pub y_includes: Vec<f64>,
    /// One metre (or unit) is as long along x as along y: for paths in a plane.
    pub equal_aspect: bool,
}

impl Panel {
    /// An empty chart.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            markers: Vec::new(),
            y_range: None,
            y_includes: Vec::new(),
            equal_aspect: false,
        }
    }

    /// Adds a series.
    pub fn series(mut self, series: Series) -> Self {
        self.series.push(series);
        self
    }

    /// Adds markers.
    pub fn markers(mut self, markers: impl IntoIterator<Item = Marker>) -> Self {
        self.markers.extend(markers);
        self
    }

    /// Fixes the y range, with no room added for the legend and the marker labels.
    pub fn y_range(mut self, min: f64, max: f64) -> Self {
        self.y_range = Some((min, max));
        self
    }

    /// Makes the y range reach `value` (from the data, with room for the legend).
    pub fn include_y(mut self, value: f64) -> Self {
        self.y_includes.push(value);
        self
    }

    /// Draws x and y to the same scale.
    pub fn equal_aspect(mut self) -> Self {
        self.equal_aspect = true;
        self
    }
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// A line through the points; a non-finite point breaks it.
    Line,
    /// A thin line, for references such as an ideal path or a limit; added after the data,
    /// it shows on top of a thick line that follows it closely.
    Reference,
    /// A dot at each point.
    Points,
}

/// Named data of one colour.
#[derive(Clone, Debug)]
pub struct Series {
    /// In the legend; none if empty.
    pub name: String,
    /// (x, y) in axis units; a non-finite point breaks a line.
    pub points: Vec<(f64, f64)>,
    /// Line or dots.
    pub style: Style,
    /// Index into the palette; by position in the panel if none.
    pub color: Option<usize>,
}

impl Series {
    /// A line.
    pub fn line(name: impl Into<String>, points: impl IntoIterator<Item = (f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points: points.into_iter().collect(),
            style: Style::Line,
            color: None,
        }
    }

    /// A thin reference line (ideal path, limit).
    pub fn reference(
        name: impl Into<String>,
        points: impl IntoIterator<Item = (f64, f64)>,
    ) -> Self {
        Self {
            style: Style::Reference,
            ..Self::line(name, points)
        }
    }

    /// Dots.
    pub fn points(name: impl Into<String>, points: impl IntoIterator<Item = (f64, f64)>) -> Self {
        Self {
            style: Style::Points,
            ..Self::line(name, points)
        }
    }

    /// Picks the colour (an index into the palette), so that the same quantity has the same
    /// colour in every panel.
    pub fn color(mut self, index: usize) -> Self {
        self.color = Some(index);
        self
    }
}

/// What a marker shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MarkerKind {
    /// A change of state, such as the control mode (grey).
    Event,
    /// A warning or error (red).
    Warning,
}

/// A labelled vertical line at `x`.
#[derive(Clone, Debug)]
pub struct Marker {
    /// Where (x axis units).
    pub x: f64,
    /// Short text drawn beside the line at the top, e.g. "cartesian" or "WN22".
    pub label: String,
    /// Its colour and legend entry.
    pub kind: MarkerKind,
}

impl Marker {
    /// A marker.
    pub fn new(x: f64, label: impl Into<String>, kind: MarkerKind) -> Self {
        Self {
            x,
            label: label.into(),
            kind,
        }
    }
}

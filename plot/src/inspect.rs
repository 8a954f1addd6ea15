//! What an SVG written by [`write_svg`](crate::write_svg) holds: its texts and lines, for the
//! tests and CI checks of the tools that write plots.

/// The parts of an SVG file that tell what was drawn.
#[derive(Clone, Debug, Default)]
pub struct SvgSummary {
    /// Every `<text>` element's content (titles, axis labels, tick labels, legend, markers),
    /// with the XML escapes undone.
    pub texts: Vec<String>,
    /// Every `<polyline>`: its stroke colour and its number of points.
    pub polylines: Vec<Polyline>,
}

/// One `<polyline>` element.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Polyline {
    /// The `stroke` attribute, e.g. `#0072B2`.
    pub stroke: String,
    /// How many points it has.
    pub points: usize,
}

impl SvgSummary {
    /// Reads the SVG text; `None` if it is not one (no `<svg` root or no closing tag).
    pub fn parse(svg: &str) -> Option<Self> {
        let body = svg.trim_start();
        if !body.starts_with("<svg") || !body.trim_end().ends_with("</svg>") {
            return None;
        }
        let mut summary = Self::default();
        for element in body.split('<').skip(1) {
            if let Some(rest) = element.strip_prefix("text") {
                let content = rest.split_once('>').map_or("", |(_, c)| c);
                summary.texts.push(unescape(content.trim()));
            } else if let Some(attributes) = element.strip_prefix("polyline") {
                summary.polylines.push(Polyline {
                    stroke: attribute(attributes, "stroke")
                        .unwrap_or_default()
                        .to_owned(),
                    points: attribute(attributes, "points")
                        .map_or(0, |p| p.split_whitespace().count()),
                });
            }
        }
        Some(summary)
    }

    /// True if some text contains `needle`.
    pub fn has_text(&self, needle: &str) -> bool {
        self.texts.iter().any(|t| t.contains(needle))
    }

    /// Polylines with at least `min_points` points.
    pub fn lines_with_points(&self, min_points: usize) -> usize {
        self.polylines
            .iter()
            .filter(|p| p.points >= min_points)
            .count()
    }
}

fn attribute<'a>(attributes: &'a str, name: &str) -> Option<&'a str> {
    let start = attributes.find(&format!(" {name}=\""))? + name.len() + 3;
    let rest = attributes.get(start..)?;
    rest.split_once('"').map(|(value, _)| value)
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

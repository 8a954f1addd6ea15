//! The measurement file: one pose per line, comma-separated.
//!
//! `q1, …, qn, x, y, z[, weight]`: the joint values (rad, or m for a prismatic joint) the
//! controller reported and the tool position the instrument measured (m, in the instrument's
//! frame). Blank lines, lines starting with `#` and a header line that is not numbers are
//! skipped. The optional weight is relative (default 1). Every line of a file has the same
//! fields (all a weight, or none) — those the header names if it names x, y, z, else those of
//! most lines — so a line missing a value is refused with its number, not read with its weight
//! as z.

use std::fmt::Write as _;

use nalgebra::Vector3;

use crate::fit::Measurement;

/// Why a measurement file could not be read.
#[derive(Clone, Debug, PartialEq)]
pub struct ParseError {
    /// Line number (1-based).
    pub line: usize,
    /// What is wrong with it.
    pub reason: String,
}

impl std::fmt::Display for ParseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "line {}: {}", self.line, self.reason)
    }
}

impl std::error::Error for ParseError {}

/// The data lines of a file.
struct Rows {
    /// The number of fields of the header line, if there is one.
    header: Option<usize>,
    /// The numbers of each data line, with its line number.
    data: Vec<(usize, Vec<f64>)>,
}

/// The numbers of each data line, with its line number.
fn rows(text: &str) -> Result<Rows, ParseError> {
    let mut rows = Vec::new();
    let mut header = None;
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Result<Vec<f64>, _> = line.split(',').map(|f| f.trim().parse()).collect();
        match fields {
            Ok(v) if v.iter().all(|x| x.is_finite()) => rows.push((k + 1, v)),
            Ok(_) => {
                return Err(ParseError {
                    line: k + 1,
                    reason: "a value is not finite".into(),
                });
            }
            // A header: only before the first data line.
            Err(_) if rows.is_empty() => header = Some(line.split(',').count()),
            Err(e) => {
                return Err(ParseError {
                    line: k + 1,
                    reason: format!("not a number: {e}"),
                });
            }
        }
    }
    Ok(Rows { header, data: rows })
}

/// The number of fields every measurement line of a robot with `dof` joints must have: the
/// header's if it names the measurement columns (a plan's header names only the joints), else
/// the most common (the larger on a tie); and whether the header gave it.
fn field_count(rows: &Rows, dof: usize) -> (usize, bool) {
    if let Some(n) = rows.header.filter(|n| *n == dof + 3 || *n == dof + 4) {
        return (n, true);
    }
    let mut counts: Vec<(usize, usize)> = Vec::new();
    for (_, v) in &rows.data {
        match counts.iter_mut().find(|(len, _)| *len == v.len()) {
            Some((_, c)) => *c += 1,
            None => counts.push((v.len(), 1)),
        }
    }
    counts
        .into_iter()
        .max_by_key(|(len, c)| (*c, *len))
        .map_or((0, false), |(len, _)| (len, false))
}

/// Parses measurements of a robot with `dof` joints.
pub fn parse(text: &str, dof: usize) -> Result<Vec<Measurement>, ParseError> {
    let rows = rows(text)?;
    let (fields, from_header) = field_count(&rows, dof);
    let expected = format!("{dof} joints, x, y, z and an optional weight");
    rows.data
        .into_iter()
        .map(|(line, v)| {
            if fields != dof + 3 && fields != dof + 4 {
                let source = if from_header {
                    "the header has"
                } else {
                    "most lines have"
                };
                return Err(ParseError {
                    line,
                    reason: format!("{source} {fields} fields; expected {expected}"),
                });
            }
            if v.len() != fields {
                return Err(ParseError {
                    line,
                    reason: format!(
                        "{} values where {} has {fields} ({dof} joints, x, y, z{}): a value is \
                         missing or extra",
                        v.len(),
                        if from_header {
                            "the header"
                        } else {
                            "every other line"
                        },
                        if fields == dof + 4 { ", weight" } else { "" }
                    ),
                });
            }
            let (q, rest) = v.split_at(dof.min(v.len()));
            let (position, weight) = match *rest {
                [x, y, z] => (Vector3::new(x, y, z), 1.0),
                [x, y, z, w] if w > 0.0 => (Vector3::new(x, y, z), w),
                [_, _, _, _] => {
                    return Err(ParseError {
                        line,
                        reason: "the weight must be positive".into(),
                    });
                }
                _ => {
                    return Err(ParseError {
                        line,
                        reason: format!("{} values; expected {expected}", v.len()),
                    });
                }
            };
            Ok(Measurement {
                q: q.to_vec(),
                position,
                weight,
                line,
            })
        })
        .collect()
}

/// Parses a list of joint configurations (`q1, …, qn` per line; extra columns ignored).
pub fn parse_poses(text: &str, dof: usize) -> Result<Vec<Vec<f64>>, ParseError> {
    rows(text)?
        .data
        .into_iter()
        .map(|(line, v)| {
            v.get(..dof).map(<[f64]>::to_vec).ok_or(ParseError {
                line,
                reason: format!("{} values; expected {dof} joint values", v.len()),
            })
        })
        .collect()
}

/// The header line of a file with `dof` joints, with or without the measurement columns.
fn header(dof: usize, measured: bool) -> String {
    let mut h: Vec<String> = (1..=dof).map(|i| format!("q{i}")).collect();
    if measured {
        h.extend(["x", "y", "z", "weight"].map(String::from));
    }
    h.join(",")
}

/// Writes measurements in the format [`parse`] reads.
pub fn format(measurements: &[Measurement], dof: usize) -> String {
    let mut out = header(dof, true) + "\n";
    for m in measurements {
        for v in m.q.iter().chain(m.position.iter()) {
            let _ = write!(out, "{v:.12},");
        }
        let _ = writeln!(out, "{}", m.weight);
    }
    out
}

/// Writes joint configurations, one per line, in the format [`parse_poses`] reads.
pub fn format_poses(poses: &[Vec<f64>], dof: usize) -> String {
    let mut out = header(dof, false) + "\n";
    for q in poses {
        let row: Vec<String> = q.iter().map(|v| format!("{v:.9}")).collect();
        out += &row.join(",");
        out.push('\n');
    }
    out
}

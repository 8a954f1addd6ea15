//! The measurement file: one pose per line, comma-separated.
//!
//! `q1, …, qn, x, y, z[, weight]`: the joint values (rad, or m for a prismatic joint) the
//! controller reported and the tool position the instrument measured (m, in the instrument's
//! frame). Blank lines, lines starting with `#` and a header line that is not numbers are
//! skipped. The optional weight is relative (default 1).

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

/// The numbers of each data line, with its line number.
fn rows(text: &str) -> Result<Vec<(usize, Vec<f64>)>, ParseError> {
    let mut rows = Vec::new();
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
            Err(_) if rows.is_empty() => {}
            Err(e) => {
                return Err(ParseError {
                    line: k + 1,
                    reason: format!("not a number: {e}"),
                });
            }
        }
    }
    Ok(rows)
}

/// Parses measurements of a robot with `dof` joints.
pub fn parse(text: &str, dof: usize) -> Result<Vec<Measurement>, ParseError> {
    rows(text)?
        .into_iter()
        .map(|(line, v)| {
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
                        reason: format!(
                            "{} values; expected {dof} joints, x, y, z and an optional weight",
                            v.len()
                        ),
                    });
                }
            };
            Ok(Measurement {
                q: q.to_vec(),
                position,
                weight,
            })
        })
        .collect()
}

/// Parses a list of joint configurations (`q1, …, qn` per line; extra columns ignored).
pub fn parse_poses(text: &str, dof: usize) -> Result<Vec<Vec<f64>>, ParseError> {
    rows(text)?
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

//! Run files: a via-point sequence in TOML, for `armgate run`.
//!
//! A file has either Cartesian entries or joint entries, at most 20 (the controller's via slots
//! 0..19, filled in file order):
//!
//! ```toml
//! [[cartesian]]
//! xyz = [0.5, 0.2, 0.1]   # m
//! rpy = [0.0, 0.0, 0.0]   # roll, pitch, yaw (rad), R = Rz(yaw)·Ry(pitch)·Rx(roll)
//! time = 5.0              # minimum duration of the leg to this point (s); default 0
//!
//! [[joint]]
//! q = [0.0, 0.5, 1.0, 0.0, 0.3, 0.0]   # one value per joint (rad, or m if prismatic)
//! time = 3.0
//! blend = 0.05            # optional: pass this point within 0.05 without stopping
//! ```
//!
//! Running it sends `VC`, `VP` 0..n−1, `VE` (or `jC`, `jV` 0..n−1, `jE`), and a `VT` (`jT`)
//! for every point with a `blend`.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::banks::MAX_JOINTS;
use crate::{Client, ClientError, Pose};
use armgate_protocol::client::ViaKind;

/// The controller's via slots per sequence.
pub const VIA_SLOTS: usize = 20;

/// One Cartesian via point.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CartesianPoint {
    /// Position (m).
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw (rad).
    pub rpy: [f64; 3],
    /// Minimum duration of the leg to this point (s); 0: as fast as the limits allow.
    #[serde(default)]
    pub time: f64,
    /// Blend tolerance at this point (m + rad): passed within it without stopping (`VT`);
    /// none: the robot file's default.
    #[serde(default)]
    pub blend: Option<f64>,
}

/// One joint via point.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointPoint {
    /// The joint values (rad, or m for prismatic joints).
    pub q: Vec<f64>,
    /// Minimum duration of the leg to this point (s); 0: as fast as the limits allow.
    #[serde(default)]
    pub time: f64,
    /// Blend tolerance at this point (rad, Euclidean over the joints): passed within it
    /// without stopping (`jT`); none: the robot file's default.
    #[serde(default)]
    pub blend: Option<f64>,
}

/// A parsed run file.
#[derive(Clone, Debug, PartialEq)]
pub enum RunFile {
    /// `[[cartesian]]` entries.
    Cartesian(Vec<CartesianPoint>),
    /// `[[joint]]` entries.
    Joint(Vec<JointPoint>),
}

/// Why a run file was refused.
#[derive(Debug, thiserror::Error)]
pub enum RunFileError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Not valid TOML, or a top-level key other than `cartesian` and `joint`.
    #[error("{0}")]
    Syntax(String),
    /// Both kinds of entries.
    #[error("a run file has [[cartesian]] entries or [[joint]] entries, not both")]
    Mixed,
    /// No entries.
    #[error("no [[cartesian]] or [[joint]] entries")]
    Empty,
    /// More entries than via slots.
    #[error("{count} [[{kind}]] entries, but the controller has {VIA_SLOTS} via slots")]
    TooMany {
        /// `cartesian` or `joint`.
        kind: &'static str,
        /// How many.
        count: usize,
    },
    /// An entry is malformed.
    #[error("[[{kind}]] entry {number} (via slot {slot}): {message}", slot = number - 1)]
    Entry {
        /// `cartesian` or `joint`.
        kind: &'static str,
        /// The entry's 1-based number in the file.
        number: usize,
        /// What is wrong.
        message: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    #[serde(default)]
    cartesian: Vec<toml::Value>,
    #[serde(default)]
    joint: Vec<toml::Value>,
}

impl RunFile {
    /// Reads and parses a run file for an arm with `joints` joints.
    pub fn load(path: &Path, joints: usize) -> Result<Self, RunFileError> {
        let text = std::fs::read_to_string(path).map_err(|source| RunFileError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(&text, joints)
    }

    /// Parses a run file for an arm with `joints` joints (every `q` must have that many values).
    pub fn parse(text: &str, joints: usize) -> Result<Self, RunFileError> {
        let raw: RawFile = toml::from_str(text).map_err(|e| RunFileError::Syntax(e.to_string()))?;
        match (raw.cartesian.is_empty(), raw.joint.is_empty()) {
            (false, false) => Err(RunFileError::Mixed),
            (true, true) => Err(RunFileError::Empty),
            (false, true) => entries("cartesian", raw.cartesian, |p: &CartesianPoint| {
                check_finite(p.xyz.iter().chain(&p.rpy), "xyz and rpy")?;
                check_time(p.time)?;
                check_blend(p.blend)
            })
            .map(Self::Cartesian),
            (true, false) => entries("joint", raw.joint, |p: &JointPoint| {
                if p.q.len() != joints {
                    return Err(format!(
                        "q has {} values, but the arm has {joints} joints (--joints)",
                        p.q.len()
                    ));
                }
                if joints > MAX_JOINTS {
                    return Err(format!("at most {MAX_JOINTS} joints"));
                }
                check_finite(p.q.iter(), "q")?;
                check_time(p.time)?;
                check_blend(p.blend)
            })
            .map(Self::Joint),
        }
    }

    /// How many via points.
    pub fn len(&self) -> usize {
        match self {
            Self::Cartesian(p) => p.len(),
            Self::Joint(p) => p.len(),
        }
    }

    /// Whether there are no via points (never true for a parsed file).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Gives every point without its own `blend` this one (`armgate run --blend`).
    pub fn set_default_blend(&mut self, tolerance: f64) {
        let blends: Vec<&mut Option<f64>> = match self {
            Self::Cartesian(p) => p.iter_mut().map(|p| &mut p.blend).collect(),
            Self::Joint(p) => p.iter_mut().map(|p| &mut p.blend).collect(),
        };
        for blend in blends {
            blend.get_or_insert(tolerance);
        }
    }

    /// The largest blend tolerance of the points (0 if none).
    pub fn largest_blend(&self) -> f64 {
        let blends: Vec<Option<f64>> = match self {
            Self::Cartesian(p) => p.iter().map(|p| p.blend).collect(),
            Self::Joint(p) => p.iter().map(|p| p.blend).collect(),
        };
        blends.into_iter().flatten().fold(0.0, f64::max)
    }

    /// The Cartesian points as poses.
    pub fn poses(points: &[CartesianPoint]) -> Vec<Pose> {
        points
            .iter()
            .map(|p| Pose::from_xyz_rpy(p.xyz, p.rpy))
            .collect()
    }
}

fn entries<T: for<'de> Deserialize<'de>>(
    kind: &'static str,
    raw: Vec<toml::Value>,
    check: impl Fn(&T) -> Result<(), String>,
) -> Result<Vec<T>, RunFileError> {
    if raw.len() > VIA_SLOTS {
        return Err(RunFileError::TooMany {
            kind,
            count: raw.len(),
        });
    }
    raw.into_iter()
        .enumerate()
        .map(|(i, value)| {
            let entry_error = |message: String| RunFileError::Entry {
                kind,
                number: i + 1,
                message,
            };
            let point: T = value
                .try_into()
                .map_err(|e: toml::de::Error| entry_error(e.message().trim().to_owned()))?;
            check(&point).map_err(entry_error)?;
            Ok(point)
        })
        .collect()
}

fn check_finite<'a>(mut values: impl Iterator<Item = &'a f64>, what: &str) -> Result<(), String> {
    if values.all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(format!("{what} must be finite numbers"))
    }
}

fn check_blend(blend: Option<f64>) -> Result<(), String> {
    match blend {
        Some(b) if !(b.is_finite() && b >= 0.0) => {
            Err(format!("blend {b} must be a finite number ≥ 0"))
        }
        _ => Ok(()),
    }
}

fn check_time(time: f64) -> Result<(), String> {
    if time.is_finite() && time >= 0.0 {
        Ok(())
    } else {
        Err(format!("time {time} must be a number of seconds ≥ 0"))
    }
}

impl Client {
    /// Loads a run file into the controller and starts it: `VC`, `VP` 0.., `VE` for Cartesian
    /// points (Cartesian mode), `jC`, `jV` 0.., `jE` for joint points (joint mode).
    pub fn start_run(&mut self, run: &RunFile) -> Result<(), ClientError> {
        match run {
            RunFile::Cartesian(points) => {
                self.via_clear()?;
                for (slot, p) in (0u8..).zip(points) {
                    self.via_cartesian(slot, p.xyz, p.rpy, p.time)?;
                    if let Some(blend) = p.blend {
                        self.via_tolerance(ViaKind::Cartesian, slot, Some(blend))?;
                    }
                }
                self.run_sequence()
            }
            RunFile::Joint(points) => {
                self.joint_via_clear()?;
                for (slot, p) in (0u8..).zip(points) {
                    self.via_joint(slot, &p.q, p.time)?;
                    if let Some(blend) = p.blend {
                        self.via_tolerance(ViaKind::Joint, slot, Some(blend))?;
                    }
                }
                self.run_joint_sequence()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cartesian_file() {
        let run = RunFile::parse(
            "[[cartesian]]\nxyz = [0.5, 0.2, 0.1]\nrpy = [0, 0, 0]\ntime = 2\n\
             [[cartesian]]\nxyz = [0.5, 0.2, 0.4]\nrpy = [0.0, 1.0, 0.0]\n",
            6,
        )
        .unwrap();
        let RunFile::Cartesian(points) = run else {
            panic!("{run:?}")
        };
        assert_eq!(points.len(), 2);
        assert_eq!(points[0].time, 2.0);
        assert_eq!(points[1].time, 0.0);
        assert_eq!(points[1].rpy, [0.0, 1.0, 0.0]);
    }

    #[test]
    fn joint_file() {
        let run = RunFile::parse(
            "[[joint]]\nq = [0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7]\ntime = 1.5\n",
            8,
        )
        .unwrap();
        assert_eq!(
            run,
            RunFile::Joint(vec![JointPoint {
                q: vec![0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7],
                time: 1.5,
                blend: None,
            }])
        );
    }

    #[test]
    fn the_example_rectangles_parse() {
        let run = RunFile::parse(include_str!("../examples/rectangle.toml"), 6).unwrap();
        let RunFile::Cartesian(points) = run else {
            panic!("{run:?}")
        };
        let corners: Vec<[f64; 3]> = points.iter().map(|p| p.xyz).collect();
        assert_eq!(
            corners,
            [
                [0.0, 0.2, 0.8],
                [0.1, 0.2, 0.8],
                [0.1, 0.2, 0.7],
                [-0.1, 0.2, 0.7],
                [-0.1, 0.2, 0.8],
                [0.0, 0.2, 0.8]
            ]
        );
        let run = RunFile::parse(include_str!("../examples/rectangle-e8.toml"), 6).unwrap();
        let RunFile::Cartesian(points) = run else {
            panic!("{run:?}")
        };
        let corners: Vec<[f64; 3]> = points.iter().map(|p| p.xyz).collect();
        assert_eq!(
            corners,
            [
                [0.5, 0.2, 0.1],
                [0.5, 0.2, 0.4],
                [0.5, -0.2, 0.4],
                [0.5, -0.2, 0.1],
                [0.5, 0.2, 0.1]
            ]
        );
        assert!(points.windows(2).all(|w| w[0].rpy == w[1].rpy));
    }

    #[test]
    fn blends_parse_and_the_default_fills_the_rest() {
        let mut run = RunFile::parse(
            "[[joint]]\nq = [0, 0, 0, 0, 0, 0]\nblend = 0.05\n[[joint]]\nq = [1, 0, 0, 0, 0, 0]\n",
            6,
        )
        .unwrap();
        assert_eq!(run.largest_blend(), 0.05);
        run.set_default_blend(0.2);
        let RunFile::Joint(points) = &run else {
            panic!("{run:?}")
        };
        assert_eq!(
            points.iter().map(|p| p.blend).collect::<Vec<_>>(),
            [Some(0.05), Some(0.2)]
        );
        assert_eq!(run.largest_blend(), 0.2);
        let e = error("[[cartesian]]\nxyz = [0, 0, 0]\nrpy = [0, 0, 0]\nblend = -1\n");
        assert!(e.ends_with("blend -1 must be a finite number ≥ 0"), "{e}");
    }

    fn error(text: &str) -> String {
        RunFile::parse(text, 6).unwrap_err().to_string()
    }

    #[test]
    fn errors_name_the_entry() {
        let two = "[[cartesian]]\nxyz = [0, 0, 0]\nrpy = [0, 0, 0]\n[[cartesian]]\n";
        assert_eq!(
            error(&format!("{two}xyz = [1, 2, 3]\n")),
            "[[cartesian]] entry 2 (via slot 1): missing field `rpy`"
        );
        let e = error(&format!("{two}xyz = [1, 2]\nrpy = [0, 0, 0]\n"));
        assert!(e.starts_with("[[cartesian]] entry 2 (via slot 1): "), "{e}");
        let e = error(&format!(
            "{two}xyz = [1, 2, 3]\nrpy = [0, 0, 0]\ntime = -1\n"
        ));
        assert!(
            e.starts_with("[[cartesian]] entry 2 (via slot 1): time -1"),
            "{e}"
        );
        let e = error(&format!(
            "{two}xyz = [1, 2, 3]\nrpy = [0, 0, 0]\nspeed = 1\n"
        ));
        assert!(e.contains("entry 2") && e.contains("speed"), "{e}");
        assert_eq!(
            error("[[joint]]\nq = [0, 0, 0, 0, 0, 0]\n[[joint]]\nq = [0, 0, 0]\n"),
            "[[joint]] entry 2 (via slot 1): q has 3 values, but the arm has 6 joints (--joints)"
        );
    }

    #[test]
    fn file_level_errors() {
        assert_eq!(error(""), RunFileError::Empty.to_string());
        assert_eq!(
            error(
                "[[joint]]\nq = [0, 0, 0, 0, 0, 0]\n[[cartesian]]\nxyz = [0, 0, 0]\nrpy = [0, 0, 0]\n"
            ),
            RunFileError::Mixed.to_string()
        );
        let many = "[[joint]]\nq = [0, 0, 0, 0, 0, 0]\n".repeat(21);
        assert_eq!(
            error(&many),
            "21 [[joint]] entries, but the controller has 20 via slots"
        );
        assert!(error("[[cartesian]\n").contains("TOML"));
        assert!(error("points = 3\n").contains("points"));
    }
}

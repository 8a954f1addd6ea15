//! The instrument's frame: where the measuring instrument stands relative to the robot.
//!
//! A laser tracker or measuring arm reports positions in its own frame, metres away from the
//! robot and turned. Calibration first registers that frame — a closed-form rigid fit
//! (Kabsch/Horn, by SVD) of the nominal model's tool positions to the measured ones, trimmed of
//! gross errors — and then refines it with the robot's constants ([`crate::model::Param::Instrument`]). The
//! result is reported and written on its own (a small TOML file, [`to_toml`]); the robot file
//! keeps its own base frame.

use std::fmt::Write as _;

use nalgebra::{DMatrix, Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use toml_edit::{DocumentMut, Item, Value};

use crate::fit::{Fit, Measurement};
use crate::model::Geometry;

/// A pose whose distance after the registration exceeds this many times the median distance
/// is left out of the next registration pass, and out of the first fit (the nominal model errs
/// by millimetres everywhere; a mistyped coordinate by far more).
const GROSS_FACTOR: f64 = 5.0;
/// ... but never below this distance (m): a nearly exact nominal model rejects nothing.
const GROSS_FLOOR: f64 = 1e-3;
/// Trimming passes of the registration.
const PASSES: usize = 3;

/// The rigid transform `T` minimising `Σ wₖ ‖T·fromₖ − toₖ‖²` (Kabsch/Horn: the SVD of the
/// weighted cross-covariance). `None` if the points do not fix a rotation (fewer than three,
/// or all on one line) or the weights are not positive.
pub fn rigid_fit(
    from: &[Vector3<f64>],
    to: &[Vector3<f64>],
    weights: &[f64],
) -> Option<Isometry3<f64>> {
    let total: f64 = weights.iter().sum();
    if from.len() < 3
        || from.len() != to.len()
        || total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return None;
    }
    let centroid = |points: &[Vector3<f64>]| {
        points
            .iter()
            .zip(weights)
            .fold(Vector3::zeros(), |sum, (p, w)| sum + p * *w)
            / total
    };
    let (from_c, to_c) = (centroid(from), centroid(to));
    let h: Matrix3<f64> = from
        .iter()
        .zip(to)
        .zip(weights)
        .fold(Matrix3::zeros(), |h, ((p, q), w)| {
            h + (p - from_c) * (q - to_c).transpose() * *w
        });
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let mut s: Vec<f64> = svd.singular_values.iter().copied().collect();
    s.sort_by(|a, b| b.total_cmp(a));
    if s.get(1).copied().unwrap_or(0.0) <= 1e-12 * s.first().copied().unwrap_or(0.0) {
        return None;
    }
    let v = v_t.transpose();
    let flip = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, flip)) * u.transpose();
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let translation = to_c - rotation * from_c;
    Some(Isometry3::from_parts(
        Translation3::from(translation),
        rotation,
    ))
}

/// The instrument's first estimate: the registration of the nominal model to the measurements.
#[derive(Clone, Debug)]
pub struct Registration {
    /// The robot's world frame in the instrument's frame.
    pub transform: Isometry3<f64>,
    /// Measurements (indices) too far from the registered nominal model to be anything but
    /// gross errors; left out of the registration and of the first fit.
    pub gross: Vec<usize>,
}

/// Registers `geometry`'s world frame to the instrument's: a weighted rigid fit of its tool
/// positions to the measured ones, repeated without the poses beyond [`GROSS_FACTOR`] times
/// the median distance. `None` if the poses do not fix a rotation.
pub fn register(geometry: &Geometry, measurements: &[Measurement]) -> Option<Registration> {
    let model: Vec<Vector3<f64>> = measurements
        .iter()
        .map(|m| geometry.robot_position(&m.q))
        .collect();
    let measured: Vec<Vector3<f64>> = measurements.iter().map(|m| m.position).collect();
    let mut keep = vec![true; measurements.len()];
    let mut transform = Isometry3::identity();
    for _ in 0..PASSES {
        let weights: Vec<f64> = measurements
            .iter()
            .zip(&keep)
            .map(|(m, k)| if *k { m.weight } else { 0.0 })
            .collect();
        transform = rigid_fit(&model, &measured, &weights)?;
        let distances: Vec<f64> = model
            .iter()
            .zip(&measured)
            .map(|(p, q)| (transform * nalgebra::Point3::from(*p) - q).coords.norm())
            .collect();
        let limit = (GROSS_FACTOR * median(&distances)).max(GROSS_FLOOR);
        let next: Vec<bool> = distances.iter().map(|d| *d <= limit).collect();
        if next == keep {
            break;
        }
        keep = next;
    }
    let gross = keep
        .iter()
        .enumerate()
        .filter(|(_, k)| !**k)
        .map(|(i, _)| i)
        .collect();
    Some(Registration { transform, gross })
}

/// The median of `values` (0 for none).
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match (v.get(n.saturating_sub(1) / 2), v.get(n / 2)) {
        (Some(a), Some(b)) => 0.5 * (a + b),
        _ => 0.0,
    }
}

/// Where the instrument is: its frame in the robot's base frame {0}.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Base coordinates = `pose` · instrument coordinates.
    pub pose: Isometry3<f64>,
    /// One standard deviation of x, y, z (m) and roll, pitch, yaw (rad), if fitted.
    pub sigma: Option<[f64; 6]>,
}

impl Placement {
    /// The instrument's frame in `geometry`'s base frame {0}.
    pub fn of(geometry: &Geometry) -> Self {
        Self {
            pose: (geometry.instrument() * geometry.base()).inverse(),
            sigma: None,
        }
    }

    /// The fitted placement with its uncertainty: the covariance of the fit's instrument
    /// parameters carried to x, y, z, roll, pitch, yaw (first-order, numerical derivatives).
    pub fn fitted(fit: &Fit) -> Self {
        let mut placement = Self::of(&fit.geometry);
        let columns: Vec<usize> = (0..fit.params.len())
            .filter(|k| fit.params.get(*k).is_some_and(|p| p.is_instrument()))
            .collect();
        if columns.is_empty() {
            return placement;
        }
        const STEP: f64 = 1e-7;
        let mut g = DMatrix::zeros(6, columns.len());
        for (c, &k) in columns.iter().enumerate() {
            let Some(&p) = fit.params.get(k) else {
                continue;
            };
            let value = fit.geometry.get(p);
            let at = |v: f64| xyz_rpy(&Self::of(&fit.geometry.with(&[p], &[v])).pose);
            let (plus, minus) = (at(value + STEP), at(value - STEP));
            for (row, (p, m)) in plus.iter().zip(&minus).enumerate() {
                let mut d = p - m;
                if row >= 3 {
                    d = (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                        - std::f64::consts::PI;
                }
                if let Some(slot) = g.get_mut((row, c)) {
                    *slot = d / (2.0 * STEP);
                }
            }
        }
        let block = fit
            .covariance
            .select_rows(&columns)
            .select_columns(&columns);
        let out = &g * block * g.transpose();
        let diagonal = out.diagonal();
        placement.sigma = Some(std::array::from_fn(|k| {
            diagonal.get(k).map_or(0.0, |v| v.max(0.0).sqrt())
        }));
        placement
    }

    /// The report's lines about the instrument.
    pub fn report(&self) -> String {
        let [x, y, z, roll, pitch, yaw] = xyz_rpy(&self.pose);
        let deg = 180.0 / std::f64::consts::PI;
        let mut out = format!(
            "instrument frame in the robot's base frame: {:.1} mm from it\n  xyz (mm)  \
             {:>11.4} {:>11.4} {:>11.4}\n  rpy (deg) {:>11.5} {:>11.5} {:>11.5}\n",
            self.pose.translation.vector.norm() * 1e3,
            x * 1e3,
            y * 1e3,
            z * 1e3,
            roll * deg,
            pitch * deg,
            yaw * deg
        );
        if let Some([sx, sy, sz, sr, sp, sw]) = self.sigma {
            let _ = writeln!(
                out,
                "  ± σ (mm)  {:>11.4} {:>11.4} {:>11.4}\n  ± σ (deg) {:>11.5} {:>11.5} {:>11.5}",
                sx * 1e3,
                sy * 1e3,
                sz * 1e3,
                sr * deg,
                sp * deg,
                sw * deg
            );
        }
        out
    }

    /// The instrument file (`--instrument-out`, read back by `simulate --instrument`).
    pub fn to_toml(&self) -> String {
        let [x, y, z, roll, pitch, yaw] = xyz_rpy(&self.pose);
        let mut out = String::from(
            "# The instrument's frame in the robot's base frame {0} (armgate-calibrate):\n\
             # base coordinates = Trans(xyz) · Rz(yaw)·Ry(pitch)·Rx(roll) · instrument coordinates,\n\
             # the convention of a robot file's [base]. docs/calibration.md, \"Frames\".\n\
             [instrument]\n",
        );
        let _ = writeln!(out, "xyz = [{x:.9}, {y:.9}, {z:.9}] # m");
        let _ = writeln!(out, "rpy = [{roll:.9}, {pitch:.9}, {yaw:.9}] # rad");
        if let Some([sx, sy, sz, sr, sp, sw]) = self.sigma {
            let _ = writeln!(out, "xyz_sigma = [{sx:.3e}, {sy:.3e}, {sz:.3e}] # m, 1σ");
            let _ = writeln!(out, "rpy_sigma = [{sr:.3e}, {sp:.3e}, {sw:.3e}] # rad, 1σ");
        }
        out
    }

    /// Reads an instrument file: `[instrument]` with `xyz` (m) and `rpy` (rad), each
    /// defaulting to zero; `xyz_sigma`, `rpy_sigma` optional; nothing else.
    pub fn parse(text: &str) -> Result<Self, String> {
        let doc: DocumentMut = text.parse().map_err(|e| format!("{e}"))?;
        let table = doc
            .get("instrument")
            .and_then(Item::as_table_like)
            .ok_or("no [instrument] table")?;
        let mut values: [Option<[f64; 3]>; 4] = [None; 4];
        for (key, item) in table.iter() {
            const KEYS: [&str; 4] = ["xyz", "rpy", "xyz_sigma", "rpy_sigma"];
            let slot = KEYS
                .iter()
                .zip(values.iter_mut())
                .find(|(known, _)| **known == key)
                .map(|(_, slot)| slot)
                .ok_or_else(|| format!("instrument.{key}: unknown key"))?;
            let triple: [f64; 3] = item
                .as_array()
                .map(|a| a.iter().filter_map(number).collect::<Vec<f64>>())
                .filter(|v| v.iter().all(|x| x.is_finite()))
                .and_then(|v| v.try_into().ok())
                .ok_or_else(|| format!("instrument.{key}: expected three finite numbers"))?;
            *slot = Some(triple);
        }
        let [xyz, rpy, sxyz, srpy] = values;
        let (xyz, [roll, pitch, yaw]) = (xyz.unwrap_or_default(), rpy.unwrap_or_default());
        Ok(Self {
            pose: Isometry3::from_parts(
                Translation3::from(Vector3::from(xyz)),
                UnitQuaternion::from_euler_angles(roll, pitch, yaw),
            ),
            sigma: sxyz
                .zip(srpy)
                .map(|([a, b, c], [d, e, f])| [a, b, c, d, e, f]),
        })
    }
}

/// A TOML number (an integer is one too).
fn number(v: &Value) -> Option<f64> {
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
}

/// x, y, z (m) and roll, pitch, yaw (rad, `Rz·Ry·Rx`) of a pose.
pub fn xyz_rpy(pose: &Isometry3<f64>) -> [f64; 6] {
    let t = pose.translation.vector;
    let (roll, pitch, yaw) = pose.rotation.euler_angles();
    [t.x, t.y, t.z, roll, pitch, yaw]
}

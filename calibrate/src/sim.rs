//! Simulated metrology: a "true" robot that differs from its file by known errors, measured by
//! a noisy instrument. The measurements use `armgate_core`'s forward kinematics, independent of
//! the calibration model.

use armgate_core::config::{ConfigError, ValidRobot};
use armgate_core::kinematics::Chain;
use armgate_core::rng::SplitMix64;
use nalgebra::{Isometry3, Vector3};

use crate::fit::Measurement;
use crate::model::{FitSet, Geometry, Param};

/// A standard normal draw (Box–Muller).
pub fn gaussian(rng: &mut SplitMix64) -> f64 {
    let u = 1.0 - rng.next_f64(); // (0, 1]: the logarithm stays finite
    let v = rng.next_f64();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// Bounds of the uniformly drawn errors of a simulated arm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Errors {
    /// Joint offsets (rad).
    pub offset: f64,
    /// DH lengths a and d (m).
    pub length: f64,
    /// DH twists α and Hayati angles β (rad).
    pub twist: f64,
    /// Base and tool positions (m).
    pub frame: f64,
    /// Base orientation (rad).
    pub frame_angle: f64,
}

impl Errors {
    /// The errors of issue 15's test: offsets ±0.5°, lengths ±1 mm, base and tool ±1 mm, and
    /// small twists (±0.05°) so that α and β are exercised too.
    pub const TYPICAL: Self = Self {
        offset: 0.5 * std::f64::consts::PI / 180.0,
        length: 1e-3,
        twist: 0.05 * std::f64::consts::PI / 180.0,
        frame: 1e-3,
        frame_angle: 0.05 * std::f64::consts::PI / 180.0,
    };
}

/// `config` with every calibratable constant off by a uniform draw within `errors` (an error
/// only if the errors are not finite).
pub fn perturb(config: &ValidRobot, errors: &Errors, seed: u64) -> Result<ValidRobot, ConfigError> {
    let mut rng = SplitMix64::new(seed);
    let mut geometry = Geometry::new(config);
    for p in geometry.constants(FitSet::All) {
        let bound = match p {
            Param::Theta(_) => errors.offset,
            Param::D(_) | Param::A(_) => errors.length,
            Param::Alpha(_) | Param::Beta(_) => errors.twist,
            Param::BaseXyz(_) | Param::ToolXyz(_) => errors.frame,
            Param::BaseRpy(_) => errors.frame_angle,
            Param::Instrument(_) => 0.0,
        };
        let value = geometry.get(p) + rng.uniform(-bound, bound);
        geometry.set(p, value);
    }
    config.clone().edit(|truth| geometry.apply_to(truth))
}

/// Measures the tool position of `truth` at each pose, in its world frame, with Gaussian noise
/// of standard deviation `noise` (m) per coordinate.
pub fn measure(truth: &ValidRobot, poses: &[Vec<f64>], noise: f64, seed: u64) -> Vec<Measurement> {
    // An instrument whose frame is the world frame lies at the base's inverse in {0}.
    let world = Geometry::new(truth).base().inverse();
    measure_from(truth, &world, poses, noise, seed)
}

/// [`measure`] by an instrument whose frame lies at `instrument` in `truth`'s base frame {0}
/// (as `--instrument-out` states it): the positions are in the instrument's frame.
pub fn measure_from(
    truth: &ValidRobot,
    instrument: &Isometry3<f64>,
    poses: &[Vec<f64>],
    noise: f64,
    seed: u64,
) -> Vec<Measurement> {
    let world_to_instrument = (Geometry::new(truth).base() * instrument).inverse();
    let chain = Chain::new(truth);
    let mut rng = SplitMix64::new(seed);
    poses
        .iter()
        .filter_map(|q| {
            let world = chain.forward(q).ok()?.translation.vector;
            let p = world_to_instrument.transform_point(&world.into()).coords;
            let n = Vector3::from_fn(|_, _| noise * gaussian(&mut rng));
            Some(Measurement {
                q: q.clone(),
                position: p + n,
                weight: 1.0,
                line: 0,
            })
        })
        .collect()
}

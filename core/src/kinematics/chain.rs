//! The kinematic chain: forward kinematics, link frames, Jacobian, manipulability.

use nalgebra::{Matrix3, Matrix6, Rotation3, SMatrix, SVector, Vector3};

use super::family::ClosedForm;
use super::jacobian::Jacobian;
use super::subproblems::Angle;
use crate::MAX_JOINTS;
use crate::config::{JointType, ValidRobot};
use crate::math::Frame;
use crate::math::Joints;
use crate::rng::SplitMix64;

/// Why a kinematics call was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KinematicsError {
    /// The joint vector's length differs from the chain's number of joints.
    WrongJointCount,
    /// A joint value is NaN or infinite.
    NonFiniteJoints,
}

impl core::fmt::Display for KinematicsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::WrongJointCount => "joint vector length differs from the number of joints",
            Self::NonFiniteJoints => "joint value is NaN or infinite",
        })
    }
}

/// One link: the constant part of its modified-DH transform, with the sines and cosines of
/// the twist precomputed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Link {
    prismatic: bool,
    cos_alpha: f64,
    sin_alpha: f64,
    tilted: bool,
    cos_beta: f64,
    sin_beta: f64,
    a: f64,
    d: f64,
    theta: f64,
    cos_theta: f64,
    sin_theta: f64,
}

/// A serial chain of up to [`MAX_JOINTS`] revolute or prismatic joints with a tool frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    links: [Link; MAX_JOINTS],
    n: usize,
    base: Frame,
    tool: Frame,
    min: [f64; MAX_JOINTS],
    max: [f64; MAX_JOINTS],
    /// The closed-form family, if the geometry has one.
    closed_form: Option<ClosedForm>,
}

/// The joint axes (z of each joint frame) and their origins from one evaluation, base
/// coordinates: all the Jacobian needs. Kept by the solver across iterations, not rebuilt.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Axes {
    pub(super) z: [Vector3<f64>; MAX_JOINTS],
    pub(super) origin: [Vector3<f64>; MAX_JOINTS],
}

impl Chain {
    /// Builds the chain of a validated robot description.
    pub fn new(config: &ValidRobot) -> Self {
        let mut chain = Self {
            links: [Link::default(); MAX_JOINTS],
            n: config.joints.len().min(MAX_JOINTS),
            base: config.base_frame(),
            tool: config.tool.frame(),
            min: [0.0; MAX_JOINTS],
            max: [0.0; MAX_JOINTS],
            closed_form: None,
        };
        let slots = chain
            .links
            .iter_mut()
            .zip(chain.min.iter_mut().zip(chain.max.iter_mut()));
        for (joint, (link, (min, max))) in config.joints.iter().zip(slots) {
            let (sin_alpha, cos_alpha) = libm::sincos(joint.alpha);
            let (sin_beta, cos_beta) = libm::sincos(joint.beta);
            let (sin_theta, cos_theta) = libm::sincos(joint.theta);
            *link = Link {
                prismatic: joint.kind == JointType::Prismatic,
                cos_alpha,
                sin_alpha,
                tilted: joint.beta != 0.0,
                cos_beta,
                sin_beta,
                a: joint.a,
                d: joint.d,
                theta: joint.theta,
                cos_theta,
                sin_theta,
            };
            *min = joint.min;
            *max = joint.max;
        }
        chain.closed_form = ClosedForm::detect(&chain);
        chain
    }

    /// The closed-form family detected when the chain was built.
    pub(super) fn closed_form(&self) -> Option<&ClosedForm> {
        self.closed_form.as_ref()
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.n
    }

    /// Lower joint limits (one per joint).
    pub fn min(&self) -> &[f64] {
        self.min.get(..self.n).unwrap_or(&[])
    }

    /// Upper joint limits (one per joint).
    pub fn max(&self) -> &[f64] {
        self.max.get(..self.n).unwrap_or(&[])
    }

    /// The length of the tool frame's offset from the last link frame (m).
    pub(super) fn tool_offset(&self) -> f64 {
        self.tool.translation.vector.norm()
    }

    /// The most link `i` (0-based) can translate what lies beyond the joint before it: its
    /// `|a|` plus its `|d|`, for a prismatic joint at the larger end of its range (m; 0 past
    /// the last joint).
    pub(super) fn link_reach(&self, i: usize) -> f64 {
        let Some(link) = self.links.get(i).filter(|_| i < self.n) else {
            return 0.0;
        };
        let d = if link.prismatic {
            let (lo, hi) = (
                self.min.get(i).copied().unwrap_or(0.0),
                self.max.get(i).copied().unwrap_or(0.0),
            );
            libm::fabs(link.d + lo).max(libm::fabs(link.d + hi))
        } else {
            libm::fabs(link.d)
        };
        libm::fabs(link.a) + d
    }

    /// True if joint `i` is prismatic.
    pub fn is_prismatic(&self, i: usize) -> bool {
        self.links.get(i).is_some_and(|l| l.prismatic)
    }

    /// A configuration drawn uniformly within the joint limits: test poses, benchmarks and
    /// calibration plans.
    pub fn random_joints(&self, rng: &mut SplitMix64) -> Joints {
        let mut q = Joints::zeros(self.n);
        for (v, (lo, hi)) in q.iter_mut().zip(self.min().iter().zip(self.max())) {
            *v = rng.uniform(*lo, *hi);
        }
        q
    }

    /// The middle of every joint range.
    pub fn mid_range(&self) -> Joints {
        let mut q = Joints::zeros(self.n);
        for (v, (lo, hi)) in q.iter_mut().zip(self.min.iter().zip(&self.max)) {
            *v = 0.5 * (lo + hi);
        }
        q
    }

    /// True if every joint lies within its limits.
    pub fn within_limits(&self, q: &[f64]) -> bool {
        q.len() == self.n
            && q.iter()
                .zip(self.min.iter().zip(&self.max))
                .all(|(v, (lo, hi))| *lo <= *v && *v <= *hi)
    }

    /// Checks a joint vector's length and values.
    pub fn check(&self, q: &[f64]) -> Result<Joints, KinematicsError> {
        let values = self.checked(q)?;
        let mut joints = Joints::zeros(self.n);
        for (j, v) in joints.iter_mut().zip(values) {
            *j = v;
        }
        Ok(joints)
    }

    /// [`check`](Self::check) into the fixed array the walk reads (entries past `n` zero).
    /// Returning the bare array, not a `Joints` through `Option` and `Result`, spares the
    /// Cortex-M7 several unaligned 72-byte copies per call.
    pub(super) fn checked(&self, q: &[f64]) -> Result<[f64; MAX_JOINTS], KinematicsError> {
        if q.len() != self.n {
            return Err(KinematicsError::WrongJointCount);
        }
        let mut values = [0.0; MAX_JOINTS];
        for (x, v) in values.iter_mut().zip(q) {
            if !v.is_finite() {
                return Err(KinematicsError::NonFiniteJoints);
            }
            *x = *v;
        }
        Ok(values)
    }

    /// The tool frame in the base frame.
    pub fn forward(&self, q: &[f64]) -> Result<Frame, KinematicsError> {
        let q = self.checked(q)?;
        Ok(self.walk(&q, |_, _, _| {}))
    }

    /// The tool frame for joints that [`check`](Self::check) returned (not checked again).
    pub(crate) fn pose(&self, q: &Joints) -> Frame {
        self.walk(q.as_array(), |_, _, _| {})
    }

    /// The frames {1}..{n} of every joint (written to `links[..n]`) and the tool frame.
    pub fn link_frames(
        &self,
        q: &[f64],
        links: &mut [Frame; MAX_JOINTS],
    ) -> Result<Frame, KinematicsError> {
        let q = self.checked(q)?;
        Ok(self.walk(&q, |i, rot, pos| {
            if let Some(link) = links.get_mut(i) {
                let rot = Matrix3::from_columns(&rot.map(|c| *c));
                *link = Frame::from_parts(pos.into(), Rotation3::from_matrix_unchecked(rot));
            }
        }))
    }

    /// The geometric Jacobian at the tool origin, base coordinates.
    pub fn jacobian(&self, q: &[f64]) -> Result<Jacobian, KinematicsError> {
        let q = self.checked(q)?;
        let mut axes = Axes::default();
        let tool = self.tool_and_axes(&q, &mut axes);
        let mut j = Jacobian::zeros();
        self.jacobian_into(&axes, &tool.translation.vector, &mut j);
        Ok(j)
    }

    /// Yoshikawa's manipulability `√det(J Jᵀ)` (`√det(Jᵀ J)` for fewer than six joints); zero at
    /// a singularity.
    pub fn manipulability(&self, q: &[f64]) -> Result<f64, KinematicsError> {
        let j = self.jacobian(q)?;
        let det = if self.n >= 6 {
            let outer: Matrix6<f64> = j * j.transpose();
            outer.determinant()
        } else {
            // JᵀJ with ones on the diagonal of the unused (zero) columns: the determinant of
            // its leading n×n block.
            let unused =
                SVector::<f64, MAX_JOINTS>::from_fn(|i, _| f64::from(u8::from(i >= self.n)));
            (j.tr_mul(&j) + SMatrix::from_diagonal(&unused)).determinant()
        };
        // NaN-safe by construction: only a positive determinant has a root (`det.max(0.0)`
        // relied on `max` dropping NaN).
        Ok(if det > 0.0 {
            crate::math::sqrt(det)
        } else {
            0.0
        })
    }

    /// Forward kinematics: walks the chain, showing each joint frame's rotation and origin to
    /// `visit`, and returns the tool frame. `q` must hold valid values in its first `n` entries.
    /// One walk serves FK, link frames and the solvers, which differ only in what they keep.
    #[inline(always)]
    fn walk(
        &self,
        q: &[f64; MAX_JOINTS],
        visit: impl FnMut(usize, [&Vector3<f64>; 3], Vector3<f64>),
    ) -> Frame {
        self.walk_by(
            |_, link, qi| {
                let (theta, d) = if link.prismatic {
                    (link.theta, link.d + qi)
                } else {
                    (link.theta + qi, link.d)
                };
                let (st, ct) = libm::sincos(theta);
                (st, ct, d)
            },
            q,
            visit,
        )
    }

    /// The tool frame of a revolute chain from each joint value's angle (cosine and sine)
    /// (prismatic joints keep their offset): FK without recomputing the sines and cosines a
    /// closed-form solver already has.
    pub(super) fn pose_by_trig(&self, angles: &[Angle; MAX_JOINTS]) -> Frame {
        self.walk_by(by_trig(angles), &[0.0; MAX_JOINTS], |_, _, _| {})
    }

    /// How far [`pose_by_trig`](Self::pose_by_trig) misses a target whose rotation, less the
    /// tool's, is `flange` (`R_target R_toolᵀ`: turning both by `R_tool` keeps their distance)
    /// and whose position is `position`: the squared position error and the squared Frobenius
    /// distance of the rotations, without the product with the tool's rotation. Out of line on
    /// the microcontroller: fewer instructions there (qemu-bench, about 20 a check) and 0.4 KB
    /// less flash.
    #[cfg_attr(target_os = "none", inline(never))]
    pub(super) fn misses_by_trig(
        &self,
        angles: &[Angle; MAX_JOINTS],
        (flange, position): (&Matrix3<f64>, &Vector3<f64>),
    ) -> (f64, f64) {
        let reached = self.flange_by(by_trig(angles), &[0.0; MAX_JOINTS], |_, _, _| {});
        let rotation = reached.rotation.matrix();
        let tip = reached.translation.vector + rotation * self.tool.translation.vector;
        (
            (tip - position).norm_squared(),
            (rotation - flange).norm_squared(),
        )
    }

    /// The base frame {0} in the world.
    pub fn base(&self) -> &Frame {
        &self.base
    }

    /// The tool frame's rotation relative to the flange.
    pub(super) fn tool_rotation(&self) -> &Matrix3<f64> {
        self.tool.rotation.matrix()
    }

    /// The walk, with `joint(i, link, q_i)` giving each joint's `sin θ`, `cos θ` and `d`.
    #[inline(always)]
    fn walk_by(
        &self,
        joint: impl Fn(usize, &Link, f64) -> (f64, f64, f64),
        q: &[f64; MAX_JOINTS],
        visit: impl FnMut(usize, [&Vector3<f64>; 3], Vector3<f64>),
    ) -> Frame {
        self.flange_by(joint, q, visit) * self.tool
    }

    /// [`walk_by`](Self::walk_by) to the flange, before the tool frame.
    #[inline(always)]
    fn flange_by(
        &self,
        joint: impl Fn(usize, &Link, f64) -> (f64, f64, f64),
        q: &[f64; MAX_JOINTS],
        mut visit: impl FnMut(usize, [&Vector3<f64>; 3], Vector3<f64>),
    ) -> Frame {
        // The rotation is kept as its three columns (the joint frame's axes), starting from the
        // base frame's (the identity unless the file places the base).
        let b = self.base.rotation.matrix();
        let [mut x, mut y, mut z] = [
            Vector3::new(b.m11, b.m21, b.m31),
            Vector3::new(b.m12, b.m22, b.m32),
            Vector3::new(b.m13, b.m23, b.m33),
        ];
        let mut pos = self.base.translation.vector;
        for (i, (link, &qi)) in self.links.iter().zip(q).enumerate().take(self.n) {
            let (st, ct, d) = joint(i, link, qi);
            // RotX(α) · TransX(a): origin moves along the old x; y, z turn about x.
            pos += x * link.a;
            let y1 = y * link.cos_alpha + z * link.sin_alpha;
            z = z * link.cos_alpha - y * link.sin_alpha;
            // RotY(β), Hayati's calibration angle: x, z turn about y (skipped when β = 0, as in
            // every uncalibrated file, to keep the tick's cost).
            if link.tilted {
                (x, z) = (
                    x * link.cos_beta - z * link.sin_beta,
                    x * link.sin_beta + z * link.cos_beta,
                );
            }
            // RotZ(θ) · TransZ(d)
            pos += z * d;
            (x, y) = (x * ct + y1 * st, y1 * ct - x * st);
            visit(i, [&x, &y, &z], pos);
        }
        let rot = Matrix3::from_columns(&[x, y, z]);
        Frame::from_parts(pos.into(), Rotation3::from_matrix_unchecked(rot))
    }

    /// The tool frame, with every joint's axis and origin written to `axes`.
    pub(super) fn tool_and_axes(&self, q: &[f64; MAX_JOINTS], axes: &mut Axes) -> Frame {
        self.walk(q, |i, [_, _, axis], pos| {
            if let (Some(z), Some(o)) = (axes.z.get_mut(i), axes.origin.get_mut(i)) {
                *z = *axis;
                *o = pos;
            }
        })
    }

    /// The Jacobian at tool position `tip` from the joint axes, written into `j`.
    pub(super) fn jacobian_into(&self, axes: &Axes, tip: &Vector3<f64>, j: &mut Jacobian) {
        let joints = axes.z.iter().zip(&axes.origin).zip(&self.links);
        // Column-major storage: each chunk of six is one column.
        let columns = j.as_mut_slice().chunks_exact_mut(6);
        for (col, ((axis, origin), link)) in columns.zip(joints).take(self.n) {
            let (linear, angular) = if link.prismatic {
                (*axis, Vector3::zeros())
            } else {
                (axis.cross(&(tip - origin)), *axis)
            };
            for (c, v) in col.iter_mut().zip(linear.iter().chain(angular.iter())) {
                *c = *v;
            }
        }
    }

    /// Joint limits as fixed arrays, for the solvers.
    pub(super) fn limits(&self) -> (&[f64; MAX_JOINTS], &[f64; MAX_JOINTS]) {
        (&self.min, &self.max)
    }
}

/// A walk's joints from each joint value's angle, its link's θ offset added by the sum
/// formulas.
#[inline(always)]
fn by_trig(angles: &[Angle; MAX_JOINTS]) -> impl Fn(usize, &Link, f64) -> (f64, f64, f64) + '_ {
    |i, link, _| {
        let (sq, cq) = angles.get(i).map_or((0.0, 1.0), |a| (a.sin, a.cos));
        let st = link.sin_theta * cq + link.cos_theta * sq;
        let ct = link.cos_theta * cq - link.sin_theta * sq;
        (st, ct, link.d)
    }
}

//! The geometric subproblems that the closed-form solvers are built from (Paden–Kahan 1–4,
//! in the general form that does not need perpendicular axes).
//!
//! Every vector is in base coordinates and every axis `k` is a unit vector. An angle is kept
//! as its cosine and sine ([`Angle`]): the solvers chain rotations, and the angle's value (an
//! `atan2`) is only needed for the answer. Only exact solutions are returned: a problem whose
//! data admit none within [`TANGENT`] has no roots (the caller's FK check is the final word).

use nalgebra::Vector3;

/// How far beyond a tangency (|cos| > 1, a negative square) the data of an exact model may be
/// and still count as touching: the rounding of a stretched elbow or a wrist at the edge of its
/// range. (The ideal model of a calibrated arm allows more: its roots are polished anyway.)
pub(super) const TANGENT: f64 = 1e-9;
/// Below this a projection onto the plane of an axis counts as zero: the angle is free.
const DEGENERATE: f64 = 1e-12;

/// A joint angle as its cosine and sine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Angle {
    pub cos: f64,
    pub sin: f64,
}

impl Angle {
    /// The angle of value `theta`.
    pub fn of(theta: f64) -> Self {
        let (sin, cos) = libm::sincos(theta);
        Self { cos, sin }
    }

    /// Its value in [−π, π]: `atan(|sin/cos|)` taken to the quadrant, as `libm::atan2(sin,
    /// cos)` computes it but without its tests for zeros, infinities and NaN (about a third of
    /// its cost on the Cortex-M7), which a cosine and sine never are both. The same to the bit
    /// but where the sine is beyond about 2⁶⁴ times a negative cosine: one ulp above π/2 there.
    pub fn value(&self) -> f64 {
        use core::f64::consts::PI;
        /// π − `PI`, the part of π below `PI`'s last bit.
        const PI_LO: f64 = 1.224_646_799_147_353_2e-16;
        let z = libm::atan((self.sin / self.cos).abs());
        let z = if self.cos < 0.0 { PI - (z - PI_LO) } else { z };
        z.copysign(self.sin)
    }

    /// The cosine of the difference to `other`: 1 when equal, −1 half a turn apart.
    pub fn closeness(&self, other: &Angle) -> f64 {
        self.cos * other.cos + self.sin * other.sin
    }

    /// The opposite angle.
    pub fn negated(&self) -> Self {
        Self {
            cos: self.cos,
            sin: -self.sin,
        }
    }

    /// The sum of the two angles.
    pub fn plus(&self, other: &Angle) -> Self {
        Self {
            cos: self.cos * other.cos - self.sin * other.sin,
            sin: self.sin * other.cos + self.cos * other.sin,
        }
    }

    /// This angle plus half a turn.
    pub fn half_turned(&self) -> Self {
        Self {
            cos: -self.cos,
            sin: -self.sin,
        }
    }

    /// This angle about an axis of sense `sign` (+1 or −1) relative to the reference axis.
    pub fn signed(&self, sign: f64) -> Self {
        if sign < 0.0 { self.negated() } else { *self }
    }
}

/// How far from perpendicular (cosine) two unit axes may be for [`Mirror`]: rounding only, so
/// that the mirrored root is as exact as a solved one.
const PERPENDICULAR: f64 = 1e-14;

/// The second solution of three rotations about axes `a`, `b`, `c` with `b` perpendicular to
/// both others, from the first: `R(a, α) R(b, β) R(c, γ) = R(a, α + π) R(b, −β − 2φ) R(c, γ +
/// π)`, where `c = R(b, φ) a`. (With `R(c, γ) = R(b, φ) R(a, γ) R(b, −φ)`, this is the
/// half-turn identity `R(a, α) R(b, β') R(a, γ) = R(a, α + π) R(b, −β') R(a, γ + π)` for `a ⊥
/// b`.) It spares a wrist's second root its subproblems and its three `atan2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Mirror {
    /// 2φ.
    twice: Angle,
    /// Its value.
    twice_value: f64,
}

impl Mirror {
    /// The mirror of the unit axes `a`, `b`, `c` (in their zero configuration), if `b` is
    /// perpendicular to both others.
    pub fn of(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> Option<Self> {
        if a.dot(b).abs() > PERPENDICULAR || b.dot(c).abs() > PERPENDICULAR {
            return None;
        }
        let phi = Angle {
            cos: a.dot(c),
            sin: b.dot(&a.cross(c)),
        };
        let twice = phi.plus(&phi);
        Some(Self {
            twice,
            twice_value: 2.0 * phi.value(),
        })
    }

    /// The other solution of the angles `[α, β, γ]` with values `values`.
    pub fn other(&self, [a, b, c]: [Angle; 3], [va, vb, vc]: [f64; 3]) -> ([Angle; 3], [f64; 3]) {
        use core::f64::consts::PI;
        (
            [
                a.half_turned(),
                b.plus(&self.twice).negated(),
                c.half_turned(),
            ],
            [va + PI, self.other_middle(vb), vc + PI],
        )
    }

    /// The other solution's β from the value of the first's.
    pub fn other_middle(&self, value: f64) -> f64 {
        -value - self.twice_value
    }
}

/// The roots of a subproblem with at most two.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Roots {
    /// The data admit no exact solution.
    None,
    /// A tangency: one root.
    One(Angle),
    /// Two roots: the `+` and the `−` branch.
    Two(Angle, Angle),
    /// Every angle solves it (a singular configuration): the caller picks one.
    Any,
}

impl Roots {
    /// The roots as an array of up to two, each with its branch index (0 = `+`, 1 = `−`);
    /// `Any` gives `reference` as branch 0. With `nearest`, only the root nearest
    /// `reference` (the tracking case, which follows one branch), compared with its angle
    /// `known` if the caller has it (a `sincos` spared).
    pub fn list(
        self,
        reference: f64,
        known: Option<&Angle>,
        nearest: bool,
    ) -> ([(Angle, u8); 2], usize) {
        let none = Angle { cos: 1.0, sin: 0.0 };
        match self {
            Self::None => ([(none, 0); 2], 0),
            Self::One(a) => ([(a, 0), (none, 0)], 1),
            Self::Two(a, b) if nearest => {
                let r = known.copied().unwrap_or_else(|| Angle::of(reference));
                if a.closeness(&r) >= b.closeness(&r) {
                    ([(a, 0), (none, 0)], 1)
                } else {
                    ([(b, 1), (none, 0)], 1)
                }
            }
            Self::Two(a, b) => ([(a, 0), (b, 1)], 2),
            Self::Any => ([(Angle::of(reference), 0), (none, 0)], 1),
        }
    }
}

/// `v` turned about the unit axis `k` by `a` (Rodrigues, without building the matrix). Out of
/// line on the microcontroller: the solvers call it about fifteen times, and inlined copies
/// cost the firmware 2.3 KB of its flash budget (on the host, inlined, the solves are 20 %
/// faster).
#[cfg_attr(target_os = "none", inline(never))]
pub(super) fn rotate(k: &Vector3<f64>, a: &Angle, v: &Vector3<f64>) -> Vector3<f64> {
    v * a.cos + k.cross(v) * a.sin + k * (k.dot(v) * (1.0 - a.cos))
}

/// The circle a fixed point `v` describes about a fixed unit axis `k`: `R(k, θ) v = centre +
/// cos θ · radial + sin θ · tangent`. For a point turned by several angles in one solve, each
/// turn is then six products and three sums, not a call of [`rotate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Circle {
    centre: Vector3<f64>,
    radial: Vector3<f64>,
    tangent: Vector3<f64>,
}

impl Circle {
    /// The circle of `v` about `k`.
    pub fn new(k: &Vector3<f64>, v: &Vector3<f64>) -> Self {
        let centre = k * k.dot(v);
        Self {
            centre,
            radial: v - centre,
            tangent: k.cross(v),
        }
    }

    /// `v` turned by `a`.
    #[inline(always)]
    pub fn at(&self, a: &Angle) -> Vector3<f64> {
        self.centre + self.radial * a.cos + self.tangent * a.sin
    }
}

/// Subproblem 1: the angle that turns `p` about `k` onto `q` (`R(k, θ) p = q`). `None` if `p`
/// or `q` lies on the axis (every angle, or none, does).
pub(super) fn sp1(k: &Vector3<f64>, p: &Vector3<f64>, q: &Vector3<f64>) -> Option<Angle> {
    let (x, y) = sp1_scaled(k, p, q);
    unit(x, y, crate::math::sqrt(x * x + y * y), DEGENERATE)
}

/// Subproblem 1's cosine and sine times `‖p⊥‖·‖q⊥‖` (the lengths of the projections onto the
/// plane of `k`), which several solutions of one problem may share.
fn sp1_scaled(k: &Vector3<f64>, p: &Vector3<f64>, q: &Vector3<f64>) -> (f64, f64) {
    let pp = p - k * k.dot(p);
    let qp = q - k * k.dot(q);
    (pp.dot(&qp), k.dot(&p.cross(q)))
}

/// The angle of cosine and sine `(x, y) / r`; `None` if `r` is too small to tell, i.e. not
/// above `floor`.
fn unit(x: f64, y: f64, r: f64, floor: f64) -> Option<Angle> {
    (r > floor).then(|| Angle {
        cos: x / r,
        sin: y / r,
    })
}

/// Subproblem 4: the angles with `hᵀ R(k, θ) p = d`; data up to `slack` beyond a tangency
/// give the tangent root.
pub(super) fn sp4(
    h: &Vector3<f64>,
    k: &Vector3<f64>,
    p: &Vector3<f64>,
    d: f64,
    slack: f64,
) -> Roots {
    Sinusoid::new(h, k, p).roots(d, slack)
}

/// Subproblem 4 of fixed `h`, `k` and `p`, `hᵀ R(k, θ) p = a cos θ + b sin θ + offset`, solved
/// for several `d`: its coefficients are taken once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Sinusoid {
    a: f64,
    b: f64,
    offset: f64,
    /// a² + b².
    r2: f64,
}

impl Sinusoid {
    /// The sinusoid of `h`, `k` and `p`.
    pub fn new(h: &Vector3<f64>, k: &Vector3<f64>, p: &Vector3<f64>) -> Self {
        let along = k.dot(p);
        let pp = p - k * along;
        // hᵀR(k,θ)p = (hᵀk)(kᵀp) + cos θ · hᵀp⊥ + sin θ · hᵀ(k × p)
        let (a, b) = (h.dot(&pp), h.dot(&k.cross(p)));
        Self {
            a,
            b,
            offset: h.dot(k) * along,
            r2: a * a + b * b,
        }
    }

    /// The angle at which it peaks, doubled: its roots lie either side of that angle.
    pub fn twice_peak(&self) -> f64 {
        2.0 * libm::atan2(self.b, self.a)
    }

    /// The angles at which it equals `d`.
    pub fn roots(&self, d: f64, slack: f64) -> Roots {
        let Self { a, b, r2, .. } = *self;
        let c = d - self.offset;
        // a cos θ + b sin θ = c. With r² = a² + b², cos φ = a/r, sin φ = b/r: θ = φ ± δ with
        // cos δ = c/r and sin δ = √(r² − c²)/r. Written over r², one square root is enough.
        if r2 <= DEGENERATE * DEGENERATE {
            return if c.abs() <= slack {
                Roots::Any
            } else {
                Roots::None
            };
        }
        let c2 = c * c;
        if c2 > r2 * (1.0 + slack) * (1.0 + slack) {
            return Roots::None;
        }
        let past = c2 > r2;
        // Beyond a tangency on an ideal model (slack above rounding), the true arm's two roots
        // straddle the tangent one about as far as the data overshoot: both are seeded.
        let half = if !past || slack > TANGENT {
            crate::math::sqrt((r2 - c2).abs())
        } else {
            0.0
        };
        // Beyond a tangency, cos δ is 1: c becomes ±r.
        let c = match (past, c < 0.0) {
            (false, _) => c,
            (true, false) => crate::math::sqrt(r2),
            (true, true) => -crate::math::sqrt(r2),
        };
        let plus = Angle {
            cos: (a * c - b * half) / r2,
            sin: (b * c + a * half) / r2,
        };
        if half == 0.0 {
            return Roots::One(plus);
        }
        let minus = Angle {
            cos: (a * c + b * half) / r2,
            sin: (b * c - a * half) / r2,
        };
        Roots::Two(plus, minus)
    }
}

/// Subproblem 3: the angles with `‖R(k, θ) p1 − p2‖² = d2` (as subproblem 4 on the dot
/// product; the distance is given squared, as the callers have it, so no square root is taken).
pub(super) fn sp3(
    k: &Vector3<f64>,
    p1: &Vector3<f64>,
    p2: &Vector3<f64>,
    d2: f64,
    slack: f64,
) -> Roots {
    let dot = 0.5 * (p1.norm_squared() + p2.norm_squared() - d2);
    sp4(p2, k, p1, dot, slack)
}

/// Subproblem 3 for an elbow, `‖R(k, θ) p1 − p2‖² = d2` with `k`, `p1` and `p2` fixed by the
/// chain, solved for several distances. Its roots are `φ ± δ` where only δ depends on the
/// distance: 2φ is taken once, and each second root's value is `2φ − θ` (no `atan2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Elbow {
    p2: Vector3<f64>,
    /// `p2ᵀ R(k, θ) p1`, which gives the distance: ‖R p1 − p2‖² = ‖p1‖² + ‖p2‖² − 2 p2ᵀ R p1.
    dot: Sinusoid,
    /// (‖p1‖² + ‖p2‖²) / 2.
    half_sum: f64,
    /// The circle of `p1` about `k`, where every root takes it.
    turned: Circle,
    /// 2φ.
    twice_mid: f64,
}

impl Elbow {
    /// The elbow of `k`, `p1`, `p2`.
    pub fn new(k: &Vector3<f64>, p1: Vector3<f64>, p2: Vector3<f64>) -> Self {
        let dot = Sinusoid::new(&p2, k, &p1);
        Self {
            p2,
            dot,
            half_sum: 0.5 * (p1.norm_squared() + p2.norm_squared()),
            turned: Circle::new(k, &p1),
            twice_mid: dot.twice_peak(),
        }
    }

    /// The roots for `d2` as [`Roots::list`] lists them (`reference`, `known`, `nearest`), each
    /// with its value. Inlined: out of line, its roots went through memory (qemu-bench: about
    /// 40 instructions per solve on puma560, 240 on ur5).
    #[inline(always)]
    pub fn roots(
        &self,
        d2: f64,
        slack: f64,
        (reference, known, nearest): (f64, Option<&Angle>, bool),
    ) -> ([(Angle, f64, u8); 2], usize) {
        let roots = self.dot.roots(self.half_sum - 0.5 * d2, slack);
        let (roots, n) = roots.list(reference, known, nearest);
        let mut out = [(Angle { cos: 1.0, sin: 0.0 }, 0.0, 0); 2];
        let mut first = None;
        for (slot, (angle, branch)) in out.iter_mut().zip(roots).take(n) {
            let value = match first {
                Some(first) => self.twice_mid - first,
                None => angle.value(),
            };
            first = Some(value);
            *slot = (angle, value, branch);
        }
        (out, n)
    }

    /// `R(k, θ) p1 − p2` at the root `angle`.
    #[inline(always)]
    pub fn reach(&self, angle: &Angle) -> Vector3<f64> {
        self.turned.at(angle) - self.p2
    }
}

/// Both angles of subproblem 2's answer, `R(k1, θ1) p1 = R(k2, θ2) p2`.
pub(super) type AnglePair = (Angle, Angle);

/// The roots of subproblem 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum PairRoots {
    /// No exact solution.
    None,
    /// One (tangent) or two solutions; the count is the second field.
    Some([AnglePair; 2], usize),
    /// `p1` lies on `k1`: θ1 is free.
    FreeFirst,
}

/// Subproblem 2: the angles with `R(k1, θ1) p1 = R(k2, θ2) p2` for non-parallel `k1`, `k2`
/// and `‖p1‖ = ‖p2‖`.
pub(super) fn sp2(
    k1: &Vector3<f64>,
    p1: &Vector3<f64>,
    k2: &Vector3<f64>,
    p2: &Vector3<f64>,
    slack: f64,
) -> PairRoots {
    sp2_solving(k1, p1, k2, p2, (slack, 2))
}

/// [`sp2`] solving at most `most` roots (the count still says how many there are; any other is
/// left at zero): for a caller that has the second root from the first.
pub(super) fn sp2_solving(
    k1: &Vector3<f64>,
    p1: &Vector3<f64>,
    k2: &Vector3<f64>,
    p2: &Vector3<f64>,
    (slack, most): (f64, usize),
) -> PairRoots {
    let (a1, a2) = (k1.dot(p1), k2.dot(p2));
    // ‖p1⊥‖², the square of p1's distance from k1, taken directly: near the free case it is
    // far below the rounding of ‖p1‖² − a1².
    let off1 = (p1 - k1 * a1).norm_squared();
    if off1 <= DEGENERATE * DEGENERATE {
        return PairRoots::FreeFirst;
    }
    let c = k1.dot(k2);
    let s2 = 1.0 - c * c;
    let (n1, n2) = (p1.norm_squared(), p2.norm_squared());
    if s2 <= DEGENERATE || (n1 - n2).abs() > slack * (n1 + n2) {
        return PairRoots::None;
    }
    // The common point z = αk1 + βk2 + γ(k1 × k2) keeps both axial components and the norm:
    // its distance from k1 is p1's, ‖z⊥‖² = β²s² + γ²s² = ‖p1⊥‖². (Written as ‖p1‖² − ‖αk1 +
    // βk2‖², γ² lost everything below 1e-16 to rounding: a wrist within 1e-8 rad of its
    // singularity got no roots.)
    let alpha = (a1 - c * a2) / s2;
    let beta = (a2 - c * a1) / s2;
    let gamma2 = off1 / s2 - beta * beta;
    if gamma2 < -slack {
        return PairRoots::None;
    }
    let gamma = crate::math::sqrt(gamma2.max(0.0));
    let n = k1.cross(k2);
    let base = k1 * alpha + k2 * beta;
    let count = if gamma == 0.0 { 1 } else { 2 };
    let zero = Angle { cos: 1.0, sin: 0.0 };
    let mut pairs = [(zero, zero); 2];
    // Both points z keep the axial components and the norm, so their projections onto either
    // axis's plane are as long as each other: the first root's lengths serve the second.
    let mut lengths = None;
    for (pair, sign) in pairs.iter_mut().zip([1.0, -1.0]).take(count.min(most)) {
        let z = base + n * (sign * gamma);
        let ((x1, y1), (x2, y2)) = (sp1_scaled(k1, p1, &z), sp1_scaled(k2, p2, &z));
        let (r1, r2) = *lengths.get_or_insert_with(|| {
            (
                crate::math::sqrt(x1 * x1 + y1 * y1),
                crate::math::sqrt(x2 * x2 + y2 * y2),
            )
        });
        // Each length is a squared distance from an axis (‖p⊥‖·‖z⊥‖ with ‖z⊥‖ = ‖p⊥‖), so
        // the floor is the square of the free case's: compared with DEGENERATE itself, every
        // wrist 1e-12 to 1e-6 rad from its singularity lost its roots.
        let floor = DEGENERATE * DEGENERATE;
        match (unit(x1, y1, r1, floor), unit(x2, y2, r2, floor)) {
            (Some(t1), Some(t2)) => *pair = (t1, t2),
            _ => return PairRoots::None,
        }
    }
    PairRoots::Some(pairs, count)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::panic)]

    use super::*;
    use crate::rng::SplitMix64;

    fn unit(rng: &mut SplitMix64) -> Vector3<f64> {
        Vector3::new(
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        )
        .normalize()
    }

    fn close(a: &Angle, theta: f64) -> bool {
        let d = a.value() - theta;
        libm::sin(d).abs() < 1e-9 && libm::cos(d) > 0.0
    }

    #[test]
    fn value_is_libm_atan2() {
        let mut rng = SplitMix64::new(0xA7A2);
        for _ in 0..200_000 {
            let a = Angle::of(rng.uniform(-7.0, 7.0));
            assert_eq!(
                a.value().to_bits(),
                libm::atan2(a.sin, a.cos).to_bits(),
                "{a:?}"
            );
        }
        // The axes with both signs of zero, components far apart in size, and unnormalised
        // pairs (as a solver's roots may be, to rounding): to the bit, but one ulp off π/2
        // where the sine dwarfs a negative cosine.
        let parts = [
            0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, 1e-20, -1e-20, 3e19, -0.7, 0.5,
        ];
        for sin in parts {
            for cos in parts {
                if sin == 0.0 && cos == 0.0 {
                    continue;
                }
                let (ours, libm) = (Angle { cos, sin }.value(), libm::atan2(sin, cos));
                let ulps = ours.to_bits().abs_diff(libm.to_bits());
                let dwarfed = cos <= 0.0 && sin.abs() > 1e18 * cos.abs();
                assert!(
                    ulps == 0 || (dwarfed && ulps == 1),
                    "{sin} {cos}: {ours} {libm}"
                );
            }
        }
    }

    #[test]
    fn sinusoid_and_circle_agree_with_rotation() {
        let mut rng = SplitMix64::new(0x51_7E);
        for _ in 0..2_000 {
            let (h, k) = (unit(&mut rng), unit(&mut rng));
            let p = unit(&mut rng) * rng.uniform(0.1, 2.0);
            let angle = Angle::of(rng.uniform(-3.0, 3.0));
            let turned = rotate(&k, &angle, &p);
            assert!((Circle::new(&k, &p).at(&angle) - turned).norm() < 1e-14);
            let d = h.dot(&turned);
            assert!(contains(
                Sinusoid::new(&h, &k, &p).roots(d, TANGENT),
                angle.value()
            ));
        }
    }

    fn contains(roots: Roots, theta: f64) -> bool {
        match roots {
            Roots::One(a) => close(&a, theta),
            Roots::Two(a, b) => close(&a, theta) || close(&b, theta),
            _ => false,
        }
    }

    #[test]
    fn each_subproblem_recovers_a_random_angle() {
        let mut rng = SplitMix64::new(26);
        for _ in 0..1000 {
            let (k, k2, p, h) = (
                unit(&mut rng),
                unit(&mut rng),
                unit(&mut rng) * 0.7,
                unit(&mut rng),
            );
            let (t1, t2) = (rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0));
            let q = rotate(&k, &Angle::of(t1), &p);
            assert!(close(&sp1(&k, &p, &q).unwrap(), t1));
            assert!(contains(sp4(&h, &k, &p, h.dot(&q), TANGENT), t1));
            let p2 = unit(&mut rng) * 0.3;
            assert!(contains(
                sp3(&k, &p, &p2, (q - p2).norm_squared(), TANGENT),
                t1
            ));
            // R(k, t1) p = R(k2, t2) p2'
            let p2 = rotate(&k2, &Angle::of(t2).negated(), &q);
            let PairRoots::Some(pairs, count) = sp2(&k, &p, &k2, &p2, TANGENT) else {
                panic!("no roots");
            };
            assert!(
                pairs
                    .iter()
                    .take(count)
                    .any(|(a, b)| close(a, t1) && close(b, t2))
            );
        }
    }

    #[test]
    fn a_mirrored_root_turns_as_the_first_and_an_elbow_root_has_its_value() {
        let mut rng = SplitMix64::new(44);
        for _ in 0..1000 {
            // Wrist axes a ⊥ b, c = R(b, φ) a.
            let b = unit(&mut rng);
            let a = b.cross(&unit(&mut rng)).normalize();
            let c = rotate(&b, &Angle::of(rng.uniform(-3.0, 3.0)), &a);
            let mirror = Mirror::of(&a, &b, &c).unwrap();
            let values = [0; 3].map(|_| rng.uniform(-3.0, 3.0));
            let angles = values.map(Angle::of);
            let (other, other_values) = mirror.other(angles, values);
            for (angle, value) in other.iter().zip(other_values) {
                assert!(close(angle, value));
            }
            let turn = |[x, y, z]: [Angle; 3], p: &Vector3<f64>| {
                rotate(&a, &x, &rotate(&b, &y, &rotate(&c, &z, p)))
            };
            let p = unit(&mut rng);
            assert!((turn(angles, &p) - turn(other, &p)).norm() < 1e-12);
            // An elbow's second root's value is 2φ less the first's.
            let (k, p1, p2) = (unit(&mut rng), unit(&mut rng) * 0.7, unit(&mut rng) * 0.3);
            let q = rotate(&k, &Angle::of(values[0]), &p1);
            let elbow = Elbow::new(&k, p1, p2);
            let (roots, n) = elbow.roots((q - p2).norm_squared(), TANGENT, (0.0, None, false));
            for (angle, value, _) in roots.iter().take(n) {
                assert!(close(angle, *value));
                assert!(
                    (elbow.reach(angle).norm_squared() - (q - p2).norm_squared()).abs() < 1e-12
                );
            }
        }
        let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
        assert!(Mirror::of(&x, &(x + y).normalize(), &z).is_none());
    }

    #[test]
    fn degenerate_and_unreachable_data_are_told_apart() {
        let z = Vector3::z();
        let x = Vector3::x();
        assert_eq!(sp1(&z, &z, &x), None);
        assert_eq!(sp4(&z, &z, &x, 0.0, TANGENT), Roots::Any);
        assert_eq!(sp4(&z, &z, &x, 0.5, TANGENT), Roots::None);
        assert_eq!(sp4(&x, &z, &x, 2.0, TANGENT), Roots::None);
        // Tangent: the one angle that points x at x.
        assert!(matches!(sp4(&x, &z, &x, 1.0, TANGENT), Roots::One(a) if close(&a, 0.0)));
        assert_eq!(sp3(&z, &x, &(x * 3.0), 0.25, TANGENT), Roots::None);
        assert_eq!(sp2(&z, &z, &x, &z, TANGENT), PairRoots::FreeFirst);
        assert_eq!(
            sp2(&z, &x, &x, &(Vector3::y() * 2.0), TANGENT),
            PairRoots::None
        );
    }
}

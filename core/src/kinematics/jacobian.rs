//! The geometric Jacobian.

use crate::MAX_JOINTS;
use crate::math::Twist;

/// A 6×n geometric Jacobian in base coordinates, reference point at the tool origin.
/// Column j maps joint j's rate to the tool twist `[vx, vy, vz, wx, wy, wz]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jacobian {
    pub(super) cols: [[f64; 6]; MAX_JOINTS],
    pub(super) n: usize,
}

impl Jacobian {
    /// An all-zero Jacobian of `n` columns.
    pub(super) fn zero(n: usize) -> Self {
        Self {
            cols: [[0.0; 6]; MAX_JOINTS],
            n: n.min(MAX_JOINTS),
        }
    }

    /// Number of columns (joints).
    pub fn dof(&self) -> usize {
        self.n
    }

    /// Column `j`, or `None` past the last joint.
    pub fn column(&self, j: usize) -> Option<&[f64; 6]> {
        self.cols.get(..self.n)?.get(j)
    }

    /// The twist produced by joint rates `qd` (extra entries ignored): `J · q̇`.
    pub fn twist(&self, qd: &[f64]) -> Twist {
        let mut t = [0.0; 6];
        for (col, rate) in self.cols.iter().take(self.n).zip(qd) {
            for (ti, ci) in t.iter_mut().zip(col) {
                *ti += ci * rate;
            }
        }
        Twist::from_array(t)
    }

    /// `Jᵀ · e` for a 6-vector `e`.
    pub(super) fn transpose_mul(&self, e: &[f64; 6]) -> [f64; MAX_JOINTS] {
        let mut g = [0.0; MAX_JOINTS];
        for (gi, col) in g.iter_mut().zip(self.cols.iter().take(self.n)) {
            *gi = dot6(col, e);
        }
        g
    }

    /// The full n×n Gram matrix `Jᵀ · J`.
    pub(super) fn gram(&self) -> [[f64; MAX_JOINTS]; MAX_JOINTS] {
        let mut a = [[0.0; MAX_JOINTS]; MAX_JOINTS];
        self.damped_gram_into(0.0, &[false; MAX_JOINTS], &mut a);
        for i in 0..self.n {
            for j in 0..i {
                let v = a.get(i).and_then(|row| row.get(j)).copied().unwrap_or(0.0);
                if let Some(x) = a.get_mut(j).and_then(|row| row.get_mut(i)) {
                    *x = v;
                }
            }
        }
        a
    }

    /// The lower triangle of `JᵀJ + λI` with the rows and columns of `locked` joints removed
    /// (only their λ stays on the diagonal), written into the leading n×n block of `a`.
    pub(super) fn damped_gram_into(
        &self,
        lambda: f64,
        locked: &[bool; MAX_JOINTS],
        a: &mut [[f64; MAX_JOINTS]; MAX_JOINTS],
    ) {
        let columns = self.cols.iter().zip(locked).take(self.n);
        for ((row, (ci, li)), i) in a.iter_mut().zip(columns).zip(0..) {
            let others = self.cols.iter().zip(locked).take(i + 1);
            for ((x, (cj, lj)), j) in row.iter_mut().zip(others).zip(0..) {
                let product = if *li || *lj { 0.0 } else { dot6(ci, cj) };
                *x = if i == j { product + lambda } else { product };
            }
        }
    }
}

impl Jacobian {
    /// The 6×6 matrix `J · Jᵀ`.
    pub(super) fn outer_gram(&self) -> [[f64; 6]; 6] {
        let mut a = [[0.0; 6]; 6];
        for col in self.cols.iter().take(self.n) {
            for (row, ci) in a.iter_mut().zip(col) {
                for (x, cj) in row.iter_mut().zip(col) {
                    *x += ci * cj;
                }
            }
        }
        a
    }
}

fn dot6(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5]
}

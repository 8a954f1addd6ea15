//! Dense solves for the small symmetric systems of the IK (n ≤ 8).
//!
//! Index loops are bounded by `n ≤ N` over `[_; N]` arrays, checked once on entry, so the
//! indexing below cannot go out of bounds.
#![allow(clippy::indexing_slicing)]

/// Solves `A x = b` in place for symmetric positive definite `A` (the lower triangle of the
/// leading n×n block is read) by Cholesky factorisation: `a` is overwritten with the factor,
/// `b` with the solution. Returns false if `A` is not positive definite (or `n > N`). In place
/// because on the Cortex-M7 copying these arrays costs as much as the arithmetic.
pub(super) fn cholesky_solve<const N: usize>(
    a: &mut [[f64; N]; N],
    b: &mut [f64; N],
    n: usize,
) -> bool {
    if n > N {
        return false;
    }
    for j in 0..n {
        let d = a[j][j] - a[j][..j].iter().map(|x| x * x).sum::<f64>();
        if d <= 0.0 || !d.is_finite() {
            return false;
        }
        let d = libm::sqrt(d);
        a[j][j] = d;
        for i in j + 1..n {
            let (upper, lower) = a.split_at_mut(i);
            let dot: f64 = lower[0][..j]
                .iter()
                .zip(&upper[j][..j])
                .map(|(x, y)| x * y)
                .sum();
            lower[0][j] = (lower[0][j] - dot) / d;
        }
    }
    // L y = b, then Lᵀ x = y.
    for i in 0..n {
        let dot: f64 = a[i][..i].iter().zip(&b[..i]).map(|(l, y)| l * y).sum();
        b[i] = (b[i] - dot) / a[i][i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= a[k][i] * b[k];
        }
        b[i] = s / a[i][i];
    }
    true
}

/// Determinant of the leading `n × n` block by Gaussian elimination with partial pivoting.
pub(super) fn determinant<const N: usize>(a: &[[f64; N]; N], n: usize) -> f64 {
    if n > N {
        return 0.0;
    }
    let mut m = *a;
    let mut det = 1.0;
    for c in 0..n {
        let mut p = c;
        for r in c + 1..n {
            if libm::fabs(m[r][c]) > libm::fabs(m[p][c]) {
                p = r;
            }
        }
        if m[p][c] == 0.0 {
            return 0.0;
        }
        if p != c {
            m.swap(p, c);
            det = -det;
        }
        det *= m[c][c];
        for r in c + 1..n {
            let f = m[r][c] / m[c][c];
            let pivot = m[c];
            for (x, p) in m[r].iter_mut().zip(&pivot).take(n).skip(c) {
                *x -= f * p;
            }
        }
    }
    det
}

/// Determinant of a 6×6 matrix.
pub(super) fn determinant6(a: &[[f64; 6]; 6]) -> f64 {
    determinant(a, 6)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_spd_system() {
        let a = [[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]];
        let x_true = [1.0, -2.0, 0.5];
        let mut b = [0.0; 3];
        for (bi, row) in b.iter_mut().zip(&a) {
            *bi = row.iter().zip(&x_true).map(|(r, x)| r * x).sum();
        }
        let mut a = a;
        assert!(cholesky_solve(&mut a, &mut b, 3));
        for (xi, ti) in b.iter().zip(&x_true) {
            assert!((xi - ti).abs() < 1e-14);
        }
    }

    #[test]
    fn rejects_indefinite_matrix() {
        let mut a = [[1.0, 2.0], [2.0, 1.0]];
        assert!(!cholesky_solve(&mut a, &mut [1.0, 1.0], 2));
    }

    #[test]
    fn determinant_matches_hand_value() {
        let a = [[2.0, 0.0, 1.0], [1.0, 3.0, 0.0], [0.0, 1.0, 4.0]];
        // 2·(12 − 0) − 0 + 1·(1 − 0) = 25
        assert!((determinant(&a, 3) - 25.0).abs() < 1e-12);
        assert_eq!(determinant(&[[0.0; 2]; 2], 2), 0.0);
    }
}

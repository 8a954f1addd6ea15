//! Dense solves for the small symmetric systems of the IK (n ≤ 8).
//!
//! Index loops are bounded by `n ≤ N` over `[_; N]` arrays, checked once on entry, so the
//! indexing below cannot go out of bounds.
#![allow(clippy::indexing_slicing)]

/// Solves `A x = b` for symmetric positive definite `A` (first `n` rows/columns) by Cholesky
/// factorisation. Returns `None` if `A` is not positive definite (or `n > N`).
pub(super) fn cholesky_solve<const N: usize>(
    a: &[[f64; N]; N],
    b: &[f64; N],
    n: usize,
) -> Option<[f64; N]> {
    if n > N {
        return None;
    }
    // L in the lower triangle of l.
    let mut l = [[0.0; N]; N];
    for i in 0..n {
        for j in 0..=i {
            let dot: f64 = l[i].iter().zip(&l[j]).take(j).map(|(x, y)| x * y).sum();
            let s = a[i][j] - dot;
            if i == j {
                if s <= 0.0 || !s.is_finite() {
                    return None;
                }
                l[i][i] = libm::sqrt(s);
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    // L y = b, then Lᵀ x = y.
    let mut x = [0.0; N];
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i][k] * x[k];
        }
        x[i] = s / l[i][i];
    }
    for i in (0..n).rev() {
        let mut s = x[i];
        for k in i + 1..n {
            s -= l[k][i] * x[k];
        }
        x[i] = s / l[i][i];
    }
    Some(x)
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
        let x = cholesky_solve(&a, &b, 3).unwrap();
        for (xi, ti) in x.iter().zip(&x_true) {
            assert!((xi - ti).abs() < 1e-14);
        }
    }

    #[test]
    fn rejects_indefinite_matrix() {
        let a = [[1.0, 2.0], [2.0, 1.0]];
        assert!(cholesky_solve(&a, &[1.0, 1.0], 2).is_none());
    }

    #[test]
    fn determinant_matches_hand_value() {
        let a = [[2.0, 0.0, 1.0], [1.0, 3.0, 0.0], [0.0, 1.0, 4.0]];
        // 2·(12 − 0) − 0 + 1·(1 − 0) = 25
        assert!((determinant(&a, 3) - 25.0).abs() < 1e-12);
        assert_eq!(determinant(&[[0.0; 2]; 2], 2), 0.0);
    }
}

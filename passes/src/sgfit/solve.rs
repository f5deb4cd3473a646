//! The damped step of Levenberg–Marquardt, mirrored by the `solve` kernel
//! of `shaders/sgfit/fit.wgsl`: Marquardt's (A + η diag A) δ = −b solved as
//! its Jacobi-scaled form (Â + η I) y = −b̂ with Â = D^{-1/2} A D^{-1/2},
//! δ = D^{-1/2} y, by Cholesky. D_i = max(A_ii, 1e-12 · max A_jj, 1e-30)
//! keeps parameters with no influence (dead lobes) at δ = 0.

/// Relative floor of the scaling diagonal.
pub const RELATIVE_DIAGONAL_FLOOR: f64 = 1e-12;
/// Absolute floor of the scaling diagonal.
pub const ABSOLUTE_DIAGONAL_FLOOR: f64 = 1e-30;

/// The step δ for the normal matrix `a` (n × n, row-major, symmetric),
/// gradient `b` = Jᵀr and damping `eta`; `None` when the damped matrix is
/// not positive definite in floating point (the step is then rejected).
pub fn damped_step(a: &[f64], b: &[f64], n: usize, eta: f64) -> Option<Vec<f64>> {
    let max_diag = (0..n).map(|i| a[i * n + i]).fold(0.0f64, f64::max);
    let d: Vec<f64> = (0..n)
        .map(|i| {
            a[i * n + i]
                .max(RELATIVE_DIAGONAL_FLOOR * max_diag)
                .max(ABSOLUTE_DIAGONAL_FLOOR)
                .sqrt()
        })
        .collect();
    // Lower triangle of the scaled, damped matrix.
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            l[i * n + j] = a[i * n + j] / (d[i] * d[j]) + if i == j { eta } else { 0.0 };
        }
    }
    // Right-looking Cholesky with L's columns kept unscaled (C_ij = L_ij
    // L_jj, the diagonal holding L_jj²), the order the GPU kernel uses (one
    // barrier a column there), the right-hand side updated along as an
    // extra row: A_ik −= C_ij C_kj / L_jj², y_k −= C_kj y_j / L_jj².
    let mut y: Vec<f64> = (0..n).map(|i| -b[i] / d[i]).collect();
    for j in 0..n {
        let pivot = l[j * n + j];
        if !(pivot > 0.0 && pivot.is_finite()) {
            return None;
        }
        for i in j + 1..n {
            let f = l[i * n + j] / pivot;
            for k in j + 1..=i {
                l[i * n + k] -= f * l[k * n + j];
            }
        }
        let f = y[j] / pivot;
        for k in j + 1..n {
            y[k] -= f * l[k * n + j];
        }
    }
    // Lᵀ x = z with z_j = y_j / L_jj: x_j = y_j / L_jj², then y_i −= C_ji x_j.
    let mut x = vec![0.0; n];
    for j in (0..n).rev() {
        x[j] = y[j] / l[j * n + j];
        for i in 0..j {
            y[i] -= l[j * n + i] * x[j];
        }
    }
    let y = x;
    let delta: Vec<f64> = y.iter().zip(&d).map(|(y, d)| y / d).collect();
    delta.iter().all(|x| x.is_finite()).then_some(delta)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undamped_step_solves_the_normal_equations() {
        // A = MᵀM for a well-conditioned M, scales 1e-3..1e3 apart.
        let n = 5;
        let m: Vec<f64> = (0..n * n)
            .map(|i| ((i * 7 + 3) % 11) as f64 - 5.0 + if i % (n + 1) == 0 { 9.0 } else { 0.0 })
            .collect();
        let scale = [1e-3, 1.0, 10.0, 1e3, 0.5];
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] =
                    (0..n).map(|k| m[k * n + i] * m[k * n + j]).sum::<f64>() * scale[i] * scale[j];
            }
        }
        let b = [1.0, -2.0, 0.5, 3.0, -1.0];
        let delta = damped_step(&a, &b, n, 0.0).unwrap();
        for i in 0..n {
            let ad: f64 = (0..n).map(|j| a[i * n + j] * delta[j]).sum();
            assert!(
                (ad + b[i]).abs() < 1e-9 * (1.0 + b[i].abs()),
                "row {i}: {ad} vs {}",
                -b[i]
            );
        }
        // Damping shrinks the step; a zero row gives a zero step.
        let damped = damped_step(&a, &b, n, 1e6).unwrap();
        assert!(damped
            .iter()
            .zip(&delta)
            .all(|(x, y)| x.abs() <= y.abs() + 1e-12));
        let mut z = a.clone();
        for k in 0..n {
            z[2 * n + k] = 0.0;
            z[k * n + 2] = 0.0;
        }
        // (A zero column of J also zeroes its gradient entry.)
        let mut bz = b;
        bz[2] = 0.0;
        assert_eq!(damped_step(&z, &bz, n, 1e-3).unwrap()[2], 0.0);
    }
}

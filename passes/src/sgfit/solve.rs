//! The damped step of Levenberg–Marquardt, mirrored by the `solve_*`
//! kernels of `shaders/sgfit/fit.wgsl`: Marquardt's (A + η diag A) δ = −b
//! solved as its Jacobi-scaled form (Â + η I) y = −b̂ with
//! Â = D^{-1/2} A D^{-1/2}, δ = D^{-1/2} y. D_i = max(A_ii, 1e-12 · max
//! A_jj, 1e-30) keeps parameters with no influence (dead lobes) at δ = 0.
//!
//! The fit's normal matrix has a structure the solve exploits: a residual
//! row holds one colour channel, so the amplitudes of different channels
//! do not couple (their entries are exact zeros,
//! [`super::model::normal_from_gram`]). Ordered as the three channels'
//! amplitudes, then the 3M nonlinear parameters (sharpness and axis),
//! Cholesky's factor keeps those zeros, and the factorisation splits in
//! three stages ([`damped_step`]):
//!
//! 1. each channel's M × M amplitude block is factored on its own, the
//!    nonlinear rows and the right-hand side riding along (on the GPU one
//!    workgroup per channel, concurrently);
//! 2. the Schur complement S of those blocks in the 3M × 3M nonlinear block
//!    (each entry a sum over the three channels' columns, independent of
//!    the others: on the GPU spread over every core);
//! 3. S factored, then back substitution through S and each channel.
//!
//! It is the same step as one Cholesky of the whole 6M × 6M system (checked
//! against one in f64), at about a quarter of its sequential work: at
//! M = 32, 1.2 M multiply-adds in one workgroup before, 0.3 M now.

/// Relative floor of the scaling diagonal.
pub const RELATIVE_DIAGONAL_FLOOR: f64 = 1e-12;
/// Absolute floor of the scaling diagonal.
pub const ABSOLUTE_DIAGONAL_FLOOR: f64 = 1e-30;

/// Parameters per lobe: the amplitudes of the three channels, then the
/// nonlinear three (as [`super::model::PARAMS_PER_LOBE`] orders them).
const PER_LOBE: usize = 6;

/// Index of amplitude `c` of lobe `k` in the fit's parameter order.
fn amplitude_index(c: usize, k: usize) -> usize {
    PER_LOBE * k + c
}

/// Index of nonlinear parameter `r` (lobe r / 3, its (r mod 3)-th of
/// sharpness and the two axis offsets) in the fit's parameter order.
fn nonlinear_index(r: usize) -> usize {
    PER_LOBE * (r / 3) + 3 + r % 3
}

/// Right-looking Cholesky of the `m` × `m` block at the head of `rows`
/// (row-major, `m` wide, lower triangle) with L's columns kept unscaled
/// (C_ij = L_ij L_jj, the diagonal holding L_jj²), the rows past `m` riding
/// along: each is reduced as a row of the matrix below the block would be
/// (A_ik −= C_ij C_kj / L_jj², k < m). False where a pivot is not positive.
fn factor_unscaled(rows: &mut [f64], m: usize) -> bool {
    let count = rows.len() / m;
    for j in 0..m {
        let pivot = rows[j * m + j];
        if !(pivot > 0.0 && pivot.is_finite()) {
            return false;
        }
        for i in j + 1..count {
            let f = rows[i * m + j] / pivot;
            for k in j + 1..=i.min(m - 1) {
                rows[i * m + k] -= f * rows[k * m + j];
            }
        }
    }
    true
}

/// Back substitution through a factor of [`factor_unscaled`]: Lᵀ x = z with
/// z_j = y_j / L_jj, so x_j = y_j / L_jj², then y_i −= C_ji x_j (i < j).
fn back_substitute(rows: &[f64], m: usize, mut y: Vec<f64>) -> Vec<f64> {
    let mut x = vec![0.0; m];
    for j in (0..m).rev() {
        x[j] = y[j] / rows[j * m + j];
        for i in 0..j {
            y[i] -= rows[j * m + i] * x[j];
        }
    }
    x
}

/// √D: the Jacobi scaling of the `n` × `n` matrix `a`, its diagonal floored
/// at [`RELATIVE_DIAGONAL_FLOOR`] × its largest and at
/// [`ABSOLUTE_DIAGONAL_FLOOR`].
fn jacobi_scale(a: &[f64], n: usize) -> Vec<f64> {
    let max_diag = (0..n).map(|i| a[i * n + i]).fold(0.0f64, f64::max);
    (0..n)
        .map(|i| {
            a[i * n + i]
                .max(RELATIVE_DIAGONAL_FLOOR * max_diag)
                .max(ABSOLUTE_DIAGONAL_FLOOR)
                .sqrt()
        })
        .collect()
}

/// The step δ for the fit's normal matrix `a` (6M × 6M for `lobes` = M,
/// row-major, symmetric, amplitudes of different channels uncoupled),
/// gradient `b` = Jᵀr and damping `eta`, by the three stages of the
/// module's doc; `None` when the damped matrix is not positive definite in
/// floating point (the step is then rejected).
pub fn damped_step(a: &[f64], b: &[f64], lobes: usize, eta: f64) -> Option<Vec<f64>> {
    let (m, n, q) = (lobes, PER_LOBE * lobes, 3 * lobes);
    let d = jacobi_scale(a, n);
    let scaled = |i: usize, j: usize| a[i * n + j] / (d[i] * d[j]) + if i == j { eta } else { 0.0 };
    let rhs = |i: usize| -b[i] / d[i];
    // 1. Per channel: its block (rows 0..m), the nonlinear rows in its
    // columns (m..m + q) and the right-hand side (m + q), reduced.
    let mut channels = Vec::with_capacity(3);
    for c in 0..3 {
        let mut rows = vec![0.0; (m + q + 1) * m];
        for i in 0..m {
            for j in 0..=i {
                rows[i * m + j] = scaled(amplitude_index(c, i), amplitude_index(c, j));
            }
        }
        for r in 0..q {
            for j in 0..m {
                rows[(m + r) * m + j] = scaled(nonlinear_index(r), amplitude_index(c, j));
            }
        }
        for j in 0..m {
            rows[(m + q) * m + j] = rhs(amplitude_index(c, j));
        }
        if !factor_unscaled(&mut rows, m) {
            return None;
        }
        channels.push(rows);
    }
    // 2. The Schur complement in the nonlinear block, its right-hand side
    // as row q: S_rt = Â_rt − Σ_c Σ_j C_rj C_tj / L_jj².
    let reduced = |r: usize, t: usize| -> f64 {
        channels
            .iter()
            .map(|rows| {
                (0..m)
                    .map(|j| rows[(m + r) * m + j] * rows[(m + t) * m + j] / rows[j * m + j])
                    .sum::<f64>()
            })
            .sum()
    };
    let mut schur = vec![0.0; (q + 1) * q];
    for r in 0..q {
        for t in 0..=r {
            schur[r * q + t] = scaled(nonlinear_index(r), nonlinear_index(t)) - reduced(r, t);
        }
    }
    for t in 0..q {
        schur[q * q + t] = rhs(nonlinear_index(t)) - reduced(q, t);
    }
    // 3. S factored, the nonlinear step, then each channel's amplitudes
    // from the right-hand side less the nonlinear step's share.
    if !factor_unscaled(&mut schur, q) {
        return None;
    }
    let x_nonlinear = back_substitute(&schur, q, schur[q * q..].to_vec());
    let mut delta = vec![0.0; n];
    for (r, x) in x_nonlinear.iter().enumerate() {
        delta[nonlinear_index(r)] = *x;
    }
    for (c, rows) in channels.iter().enumerate() {
        let y: Vec<f64> = (0..m)
            .map(|j| {
                rows[(m + q) * m + j]
                    - (0..q)
                        .map(|r| rows[(m + r) * m + j] * x_nonlinear[r])
                        .sum::<f64>()
            })
            .collect();
        for (k, x) in back_substitute(rows, m, y).into_iter().enumerate() {
            delta[amplitude_index(c, k)] = x;
        }
    }
    for (x, d) in delta.iter_mut().zip(&d) {
        *x /= d;
    }
    delta.iter().all(|x| x.is_finite()).then_some(delta)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One Cholesky of the whole scaled, damped system: the oracle the
    /// staged solve is checked against.
    fn whole_cholesky_step(a: &[f64], b: &[f64], n: usize, eta: f64) -> Option<Vec<f64>> {
        let d = jacobi_scale(a, n);
        let mut rows = vec![0.0; (n + 1) * n];
        for i in 0..n {
            for j in 0..=i {
                rows[i * n + j] = a[i * n + j] / (d[i] * d[j]) + if i == j { eta } else { 0.0 };
            }
            rows[n * n + i] = -b[i] / d[i];
        }
        if !factor_unscaled(&mut rows, n) {
            return None;
        }
        let x = back_substitute(&rows, n, rows[n * n..].to_vec());
        Some(x.iter().zip(&d).map(|(x, d)| x / d).collect())
    }

    /// A normal matrix of the fit's shape: JᵀJ of a random J whose rows
    /// each touch one channel's amplitudes and every nonlinear parameter,
    /// columns scaled 1e-3..1e3 apart; and Jᵀr.
    fn fit_shaped(lobes: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
        let n = PER_LOBE * lobes;
        let mut state = seed;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let scale: Vec<f64> = (0..n).map(|i| 10f64.powi((i % 7) as i32 - 3)).collect();
        let rows = 3 * n;
        let mut j = vec![0.0; rows * n];
        let mut r = vec![0.0; rows];
        for t in 0..rows {
            let c = t % 3;
            for k in 0..lobes {
                j[t * n + amplitude_index(c, k)] = next() * scale[amplitude_index(c, k)];
            }
            for q in 0..3 * lobes {
                j[t * n + nonlinear_index(q)] = next() * scale[nonlinear_index(q)];
            }
            r[t] = next();
        }
        let mut a = vec![0.0; n * n];
        let mut b = vec![0.0; n];
        for t in 0..rows {
            for p in 0..n {
                b[p] += j[t * n + p] * r[t];
                for s in 0..n {
                    a[p * n + s] += j[t * n + p] * j[t * n + s];
                }
            }
        }
        (a, b)
    }

    /// The staged solve takes the step one Cholesky of the whole system
    /// takes, damped or not, and that step solves the normal equations.
    #[test]
    fn the_staged_step_is_the_whole_systems() {
        for (lobes, seed) in [(1, 1), (3, 2), (8, 3)] {
            let (a, b) = fit_shaped(lobes, seed);
            let n = PER_LOBE * lobes;
            for eta in [0.0, 1e-3, 10.0] {
                let staged = damped_step(&a, &b, lobes, eta).unwrap();
                let whole = whole_cholesky_step(&a, &b, n, eta).unwrap();
                let size = whole.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                for (s, w) in staged.iter().zip(&whole) {
                    assert!(
                        (s - w).abs() <= 1e-9 * size,
                        "M = {lobes}, η = {eta}: {s} vs {w}"
                    );
                }
            }
            let delta = damped_step(&a, &b, lobes, 0.0).unwrap();
            for i in 0..n {
                let ad: f64 = (0..n).map(|j| a[i * n + j] * delta[j]).sum();
                let row: f64 = (0..n).map(|j| (a[i * n + j] * delta[j]).abs()).sum();
                assert!(
                    (ad + b[i]).abs() <= 1e-8 * (row + b[i].abs()),
                    "row {i}: {ad} vs {}",
                    -b[i]
                );
            }
        }
    }

    /// Damping shrinks the step; a parameter with no influence (a zero row
    /// and column, and so a zero gradient) gets a zero step; a matrix that
    /// is not positive definite is refused.
    #[test]
    fn damping_dead_parameters_and_indefinite_matrices() {
        let lobes = 2;
        let n = PER_LOBE * lobes;
        let (a, b) = fit_shaped(lobes, 7);
        let free = damped_step(&a, &b, lobes, 0.0).unwrap();
        let damped = damped_step(&a, &b, lobes, 1e6).unwrap();
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(norm(&damped) < 1e-3 * norm(&free));
        for dead in [amplitude_index(1, 1), nonlinear_index(4)] {
            let mut z = a.clone();
            for k in 0..n {
                z[dead * n + k] = 0.0;
                z[k * n + dead] = 0.0;
            }
            let mut bz = b.clone();
            bz[dead] = 0.0;
            assert_eq!(damped_step(&z, &bz, lobes, 1e-3).unwrap()[dead], 0.0);
        }
        let mut bad = a.clone();
        let i = nonlinear_index(2);
        bad[i * n + i] = -bad[i * n + i];
        assert!(damped_step(&bad, &b, lobes, 0.0).is_none());
    }
}

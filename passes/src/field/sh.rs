//! View-dependent colour as real spherical harmonics of degree 0–2.
//!
//! A node holds its colour averaged over directions (the base, what a
//! degree-0 field holds) and, for degree ℓ ≥ 1, (ℓ + 1)² − 1 further RGB
//! coefficients. Along direction `d` (the ray's, from the eye into the
//! field) the colour is max(0, base + Σ_k coefficient_k · Y_k(d)), with
//! Y_k the real spherical harmonics of band 1 (k = 1..3) and band 2
//! (k = 4..8) in the usual order and normalisation (Plenoxels' and
//! 3D Gaussian splatting's). Each Y_k integrates to zero over the sphere,
//! so the base stays the colour's mean over directions. Mirrored in
//! `shaders/field/sh.wgsl`.

use glam::DVec3;

/// The highest degree a field may carry.
pub const MAX_SH_DEGREE: u32 = 2;

/// Coefficients beyond the base for `degree`: 0, 3 or 8.
pub const fn sh_extra_coefficients(degree: u32) -> usize {
    ((degree + 1) * (degree + 1) - 1) as usize
}

const C1: f64 = 0.488_602_511_902_919_9;
const C2: [f64; 5] = [
    1.092_548_430_592_079_2,
    -1.092_548_430_592_079_2,
    0.315_391_565_252_520_05,
    -1.092_548_430_592_079_2,
    0.546_274_215_296_039_6,
];

/// Y_1 … Y_8 at unit direction `d` (the first 3 are band 1).
pub fn sh_basis(d: DVec3) -> [f64; 8] {
    let (x, y, z) = (d.x, d.y, d.z);
    [
        -C1 * y,
        C1 * z,
        -C1 * x,
        C2[0] * x * y,
        C2[1] * y * z,
        C2[2] * (2.0 * z * z - x * x - y * y),
        C2[3] * x * z,
        C2[4] * (x * x - y * y),
    ]
}

/// The colour along `d` of a base colour and its `extra` coefficients
/// (before the clamp at zero).
pub fn sh_colour_unclamped(base: DVec3, extra: &[DVec3], d: DVec3) -> DVec3 {
    let y = sh_basis(d);
    extra.iter().zip(y).fold(base, |acc, (c, yk)| acc + *c * yk)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each basis function integrates to zero over the sphere and the
    /// eight are orthonormal (checked by quadrature on a fine grid in θ, φ).
    #[test]
    fn the_basis_is_orthonormal_with_zero_mean() {
        let (nt, np) = (400, 800);
        let mut gram = [[0.0f64; 8]; 8];
        let mut mean = [0.0f64; 8];
        for i in 0..nt {
            let theta = (i as f64 + 0.5) / nt as f64 * std::f64::consts::PI;
            for j in 0..np {
                let phi = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                let d = DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                let w = theta.sin()
                    * (std::f64::consts::PI / nt as f64)
                    * (std::f64::consts::TAU / np as f64);
                let y = sh_basis(d);
                for (a, row) in gram.iter_mut().enumerate() {
                    mean[a] += w * y[a];
                    for (g, yb) in row.iter_mut().zip(y) {
                        *g += w * y[a] * yb;
                    }
                }
            }
        }
        for (a, row) in gram.iter().enumerate() {
            assert!(mean[a].abs() < 1e-4, "Y_{} mean {}", a + 1, mean[a]);
            for (b, g) in row.iter().enumerate() {
                let want = if a == b { 1.0 } else { 0.0 };
                assert!((g - want).abs() < 1e-4, "⟨Y_{}, Y_{}⟩ = {g}", a + 1, b + 1);
            }
        }
    }

    #[test]
    fn coefficient_counts() {
        assert_eq!(sh_extra_coefficients(0), 0);
        assert_eq!(sh_extra_coefficients(1), 3);
        assert_eq!(sh_extra_coefficients(2), 8);
    }
}

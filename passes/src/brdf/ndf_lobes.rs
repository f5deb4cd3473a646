//! GGX's distribution of normals as a mixture of N SGs around the normal.
//! For small α, D(h) ≈ 1/(πα²) · 1/(1 + t)² with t = (2/α²)(1 − h·n), and
//! 1/(1 + t)² = ∫₀^∞ e^{−s} · s e^{−s t} ds. N-point Gauss–Laguerre
//! quadrature of that integral gives a mixture of N exponentials in t,
//! i.e. N SGs: D(h) ≈ 1/(πα²) Σ_j c_j exp((2 k_j/α²)(h·n − 1)) with
//! k_j = s_j (the nodes) and c_j = w_j s_j (weights times nodes). N = 1
//! is the usual single lobe (k = c = 1); the mixture keeps the peak value
//! (Σ c_j = 1 exactly) and converges to the GGX shape as N grows.

/// Most lobes the shading pass accepts.
pub const MAX_NDF_LOBES: u32 = 8;

/// The mixture's coefficients for one lobe count.
#[derive(Debug, Clone, PartialEq)]
pub struct NdfLobes {
    /// (c_j, k_j): amplitude fraction and sharpness multiple of each lobe.
    pub lobes: Vec<(f64, f64)>,
}

impl NdfLobes {
    /// The N-lobe mixture, N in 1..=[`MAX_NDF_LOBES`].
    pub fn new(n: u32) -> Result<Self, String> {
        if !(1..=MAX_NDF_LOBES).contains(&n) {
            return Err(format!("{n} NDF lobes: must be 1..={MAX_NDF_LOBES}"));
        }
        let lobes = gauss_laguerre(n as usize)
            .into_iter()
            .map(|(s, w)| (w * s, s))
            .collect();
        Ok(Self { lobes })
    }

    /// The mixture's value relative to the peak, at t = (2/α²)(1 − h·n).
    pub fn shape(&self, t: f64) -> f64 {
        self.lobes.iter().map(|(c, k)| c * (-k * t).exp()).sum()
    }

    /// Packed for the GPU: (c_j, k_j) pairs as f32.
    pub fn packed(&self) -> Vec<f32> {
        self.lobes
            .iter()
            .flat_map(|&(c, k)| [c as f32, k as f32])
            .collect()
    }
}

/// Nodes and weights of n-point Gauss–Laguerre quadrature
/// (∫₀^∞ e^{−x} f(x) dx ≈ Σ w_i f(x_i)), by Newton's method on L_n from
/// the usual asymptotic starting points (Numerical Recipes' `gaulag`).
fn gauss_laguerre(n: usize) -> Vec<(f64, f64)> {
    let nf = n as f64;
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(n);
    let mut z = 0.0;
    for i in 0..n {
        z = match i {
            0 => 3.0 / (1.0 + 2.4 * nf),
            1 => z + 15.0 / (1.0 + 2.5 * nf),
            _ => {
                let ai = (i - 1) as f64;
                z + (1.0 + 2.55 * ai) / (1.9 * ai) * (z - out[i - 2].0)
            }
        };
        let mut dp = 1.0;
        for _ in 0..100 {
            // L_n(z) and L_{n−1}(z) by the three-term recurrence.
            let (mut p1, mut p2) = (1.0, 0.0);
            for j in 0..n {
                let jf = j as f64;
                let p3 = p2;
                p2 = p1;
                p1 = ((2.0 * jf + 1.0 - z) * p2 - jf * p3) / (jf + 1.0);
            }
            dp = nf * (p1 - p2) / z;
            let step = p1 / dp;
            z -= step;
            if step.abs() <= 1e-15 * z.abs().max(1.0) {
                break;
            }
        }
        // w_i = 1 / (x_i L_n'(x_i)²).
        out.push((z, 1.0 / (z * dp * dp)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule integrates e^{−x} x^k exactly (k!) up to degree 2n − 1.
    #[test]
    fn gauss_laguerre_is_exact_for_polynomials() {
        for n in 1..=MAX_NDF_LOBES as usize {
            let rule = gauss_laguerre(n);
            let mut factorial = 1.0;
            for k in 0..(2 * n) {
                if k > 0 {
                    factorial *= k as f64;
                }
                let q: f64 = rule.iter().map(|(x, w)| w * x.powi(k as i32)).sum();
                assert!((q / factorial - 1.0).abs() < 1e-9, "n {n} k {k}: {q}");
            }
        }
    }

    /// One lobe is the classic SG (c = k = 1); every mixture keeps the peak
    /// and gets closer to 1/(1 + t)² as lobes are added.
    #[test]
    fn mixtures_keep_the_peak_and_converge_to_the_ggx_shape() {
        assert_eq!(NdfLobes::new(1).unwrap().lobes.len(), 1);
        let one = &NdfLobes::new(1).unwrap().lobes[0];
        assert!((one.0 - 1.0).abs() < 1e-12 && (one.1 - 1.0).abs() < 1e-12);
        let mut last = f64::INFINITY;
        for n in 1..=MAX_NDF_LOBES {
            let m = NdfLobes::new(n).unwrap();
            assert!((m.shape(0.0) - 1.0).abs() < 1e-12);
            // L2 error over t in [0, 20], where GGX holds most of its mass.
            let err: f64 = (0..2000)
                .map(|i| {
                    let t = (i as f64 + 0.5) * 0.01;
                    (m.shape(t) - 1.0 / (1.0 + t).powi(2)).powi(2) * 0.01
                })
                .sum::<f64>()
                .sqrt();
            assert!(err < last, "{n} lobes: {err} ≥ {last}");
            last = err;
        }
        assert!(last < 0.02, "{last}");
        assert!(NdfLobes::new(0).is_err() && NdfLobes::new(MAX_NDF_LOBES + 1).is_err());
    }
}

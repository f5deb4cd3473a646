//! Total variation over the grid: the sum over neighbouring node pairs of
//! their squared differences, per channel group weighted (colour, density).
//! A colour difference larger than [`TvWeights::colour_edge`] is likewise
//! penalised as its size, so that a lamp's HDR radiance is not drained
//! into its neighbours by a weight that smooths a dim surface's speckle.
//! It smooths what the views do not pin down, floaters above all. A
//! density difference larger than [`TvWeights::density_edge`] is penalised
//! less than its square (a Charbonnier penalty, growing as its size
//! rather than its square), so that a surface's rise is not diffused over
//! many nodes: a squared penalty, taken as a plain step at each of 2000
//! steps at the default weight, spreads a step's rise over 12 nodes. It is
//! applied as a plain gradient step after Adam's ([`tv_step`]): through
//! Adam, whose step is normalised per value, any weight moved the values no
//! ray reads by a full step. Mirrored by `shaders/train/tv.wgsl` (the
//! gradient) and `shaders/train/descend.wgsl` (the step).

use glam::UVec3;

/// The total variation's weights.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TvWeights {
    /// Weight of the colour channels' differences (squared while small).
    pub colour: f64,
    /// The colour difference (in radiance) from which its penalty grows as
    /// its size rather than its square, as [`Self::density_edge`] does for
    /// density: a lamp's few bright nodes beside dim ones are pulled by at
    /// most about this much a step, not in proportion to their radiance,
    /// while a speckle below it is smoothed. Infinite: squared everywhere.
    pub colour_edge: f64,
    /// Weight of the density's differences (squared while small).
    pub density: f64,
    /// The density difference (in σ's units) from which its penalty grows
    /// as its size rather than its square: ε in 2ε²(√(1 + (d/ε)²) − 1),
    /// which is d² for |d| ≪ ε; positive. Infinite: squared everywhere.
    pub density_edge: f64,
    /// Weight λ of the density's sparsity prior: each node's
    /// λε²·ln(1 + (σ₊/ε)²), σ₊ its density where positive and ε
    /// [`Self::sparsity_edge`] (λσ₊² where that is infinite). A density
    /// below the edge (a haze) is pulled toward zero in proportion, by up
    /// to λε; one far beyond it (an opaque surface, a medium such as
    /// foliage), hardly at all. Total variation alone leaves a haze in
    /// front of uniformly coloured surfaces, which the photographs cannot
    /// tell from the surface.
    pub sparsity: f64,
    /// The sparsity prior's edge ε (in σ's units; positive, infinite:
    /// σ₊² everywhere): the density at which its pull is strongest.
    pub sparsity_edge: f64,
}

impl TvWeights {
    /// No total variation.
    pub const NONE: TvWeights = TvWeights {
        colour: 0.0,
        colour_edge: f64::INFINITY,
        density: 0.0,
        density_edge: f64::INFINITY,
        sparsity: 0.0,
        sparsity_edge: f64::INFINITY,
    };

    /// Squared differences everywhere, weighted `colour` and `density`.
    pub fn squared(colour: f64, density: f64) -> TvWeights {
        TvWeights {
            colour,
            colour_edge: f64::INFINITY,
            density,
            density_edge: f64::INFINITY,
            sparsity: 0.0,
            sparsity_edge: f64::INFINITY,
        }
    }

    /// Whether the step changes anything.
    pub fn is_none(&self) -> bool {
        self.colour == 0.0 && self.density == 0.0 && self.sparsity == 0.0
    }

    /// 1 / [`Self::density_edge`] (0 where squared everywhere), as the
    /// shader takes it.
    pub fn density_edge_inverse(&self) -> f64 {
        1.0 / self.density_edge
    }

    /// 1 / [`Self::colour_edge`] (0 where squared everywhere), as the
    /// shader takes it.
    pub fn colour_edge_inverse(&self) -> f64 {
        1.0 / self.colour_edge
    }

    /// 1 / [`Self::sparsity_edge`] (0 where σ₊² everywhere), as the
    /// shader takes it.
    pub fn sparsity_edge_inverse(&self) -> f64 {
        1.0 / self.sparsity_edge
    }
}

/// The penalty of a difference `d` with edge inverse `inv`
/// ([`TvWeights::density_edge_inverse`], [`TvWeights::colour_edge_inverse`]):
/// d² for |d| ≪ 1/inv, growing as 2|d|/inv beyond.
fn edge_penalty(d: f64, inv: f64) -> f64 {
    if inv == 0.0 {
        d * d
    } else {
        2.0 * ((1.0 + (d * inv).powi(2)).sqrt() - 1.0) / (inv * inv)
    }
}

/// ∂[`edge_penalty`]/∂d over 2: d / √(1 + (d·inv)²). Mirrored in
/// `shaders/train/tv.wgsl`.
fn edge_pull(d: f64, inv: f64) -> f64 {
    d / (1.0 + (d * inv).powi(2)).sqrt()
}

/// A node's sparsity penalty over its weight, for density `sigma` and edge
/// inverse `inv`: ε²·ln(1 + (σ₊/ε)²) with ε = 1/inv, σ₊² where inv is 0.
fn sparsity_penalty(sigma: f64, inv: f64) -> f64 {
    let s = sigma.max(0.0);
    if inv == 0.0 {
        s * s
    } else {
        (s * inv).powi(2).ln_1p() / (inv * inv)
    }
}

/// ∂[`sparsity_penalty`]/∂σ over 2: σ₊ / (1 + (σ₊·inv)²). Mirrored in
/// `shaders/train/tv.wgsl`.
fn sparsity_pull(sigma: f64, inv: f64) -> f64 {
    let s = sigma.max(0.0);
    s / (1.0 + (s * inv).powi(2))
}

/// The total variation of `nodes` (r, g, b, σ, x fastest) with weights
/// `tv`, the density's sparsity prior included.
pub fn tv_loss(nodes: &[[f32; 4]], res: UVec3, tv: TvWeights) -> f64 {
    let w = [tv.colour, tv.colour, tv.colour, tv.density];
    let inv = tv.density_edge_inverse();
    let colour_inv = tv.colour_edge_inverse();
    let sparsity_inv = tv.sparsity_edge_inverse();
    let idx = |i: u32, j: u32, k: u32| (i + res.x * (j + res.y * k)) as usize;
    let mut sum = 0.0;
    for k in 0..res.z {
        for j in 0..res.y {
            for i in 0..res.x {
                let v = nodes[idx(i, j, k)];
                sum += tv.sparsity * sparsity_penalty(v[3] as f64, sparsity_inv);
                let next = [
                    (i + 1 < res.x).then(|| idx(i + 1, j, k)),
                    (j + 1 < res.y).then(|| idx(i, j + 1, k)),
                    (k + 1 < res.z).then(|| idx(i, j, k + 1)),
                ];
                for m in next.into_iter().flatten() {
                    for c in 0..3 {
                        sum += w[c] * edge_penalty(v[c] as f64 - nodes[m][c] as f64, colour_inv);
                    }
                    sum += w[3] * edge_penalty(v[3] as f64 - nodes[m][3] as f64, inv);
                }
            }
        }
    }
    sum
}

/// ∂[`tv_loss`]/∂node for every node.
pub fn tv_gradient(nodes: &[[f32; 4]], res: UVec3, tv: TvWeights) -> Vec<[f64; 4]> {
    let w = [tv.colour, tv.colour, tv.colour, tv.density];
    let inv = tv.density_edge_inverse();
    let colour_inv = tv.colour_edge_inverse();
    let sparsity_inv = tv.sparsity_edge_inverse();
    let idx = |i: u32, j: u32, k: u32| (i + res.x * (j + res.y * k)) as usize;
    let mut out = vec![[0.0; 4]; nodes.len()];
    for k in 0..res.z {
        for j in 0..res.y {
            for i in 0..res.x {
                let n = idx(i, j, k);
                let v = nodes[n];
                out[n][3] += 2.0 * tv.sparsity * sparsity_pull(v[3] as f64, sparsity_inv);
                let c = [i, j, k];
                for a in 0..3 {
                    for d in [-1i64, 1] {
                        let mut m = c.map(|x| x as i64);
                        m[a] += d;
                        let r = [res.x, res.y, res.z][a] as i64;
                        if m[a] < 0 || m[a] >= r {
                            continue;
                        }
                        let q = nodes[idx(m[0] as u32, m[1] as u32, m[2] as u32)];
                        for ch in 0..3 {
                            out[n][ch] +=
                                2.0 * w[ch] * edge_pull(v[ch] as f64 - q[ch] as f64, colour_inv);
                        }
                        out[n][3] += 2.0 * w[3] * edge_pull(v[3] as f64 - q[3] as f64, inv);
                    }
                }
            }
        }
    }
    out
}

/// Largest weight for which the step is stable: a node has six neighbours,
/// so a step of weight w moves it by up to 12·w of its difference to them
/// (less where a density difference is beyond its edge).
pub const MAX_TV_WEIGHT: f64 = 1.0 / 12.0;

/// One total-variation step over `nodes`: each value minus the gradient of
/// [`tv_loss`], the colours kept within 0 and the radiance limit
/// ([`crate::scene::RADIANCE_LIMIT`]; a density may be negative:
/// [`crate::field::density_at`]).
pub fn tv_step(nodes: &mut [[f32; 4]], res: UVec3, tv: TvWeights) {
    let g = tv_gradient(nodes, res, tv);
    let limit = crate::scene::RADIANCE_LIMIT as f32;
    for (n, g) in nodes.iter_mut().zip(g) {
        for c in 0..3 {
            n[c] = (n[c] - g[c] as f32).clamp(0.0, limit);
        }
        n[3] -= g[3] as f32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    #[test]
    fn the_tv_gradient_matches_finite_differences() {
        let res = UVec3::new(4, 3, 5);
        let mut rng = Pcg32::new(2, 2);
        let nodes: Vec<[f32; 4]> = (0..60)
            .map(|_| [0; 4].map(|_: i32| rng.next_f64() as f32))
            .collect();
        // Squared everywhere, and with an edge inside the differences'
        // range (0–1) so that both sides of it are read.
        // Sparsity with and without its edge, the last at an edge of its
        // own beside total variation's; the densities shifted so
        // that some are negative (no pull there).
        let nodes: Vec<[f32; 4]> = nodes
            .into_iter()
            .map(|[r, g, b, s]| [r, g, b, s - 0.2])
            .collect();
        for tv in [
            TvWeights::squared(0.7, 2.0),
            TvWeights {
                density_edge: 0.2,
                ..TvWeights::squared(0.7, 2.0)
            },
            TvWeights {
                density_edge: 0.2,
                sparsity: 0.9,
                sparsity_edge: 0.2,
                ..TvWeights::squared(0.7, 2.0)
            },
            TvWeights {
                sparsity: 0.9,
                ..TvWeights::squared(0.7, 2.0)
            },
            TvWeights {
                colour_edge: 0.3,
                density_edge: 0.2,
                sparsity: 0.9,
                sparsity_edge: 0.05,
                ..TvWeights::squared(0.7, 2.0)
            },
        ] {
            let g = tv_gradient(&nodes, res, tv);
            for n in [0usize, 17, 59] {
                for c in 0..4 {
                    let h = 1e-3f32;
                    let mut a = nodes.clone();
                    let mut b = nodes.clone();
                    a[n][c] += h;
                    b[n][c] -= h;
                    let numeric = (tv_loss(&a, res, tv) - tv_loss(&b, res, tv)) / (2.0 * h as f64);
                    assert!(
                        (numeric - g[n][c]).abs() < 1e-3,
                        "{tv:?} {n} {c}: {numeric} vs {}",
                        g[n][c]
                    );
                }
            }
        }
    }

    /// The width, in nodes, over which a density step of `height` rises
    /// from a tenth to nine tenths of it after `steps` total-variation
    /// steps of weight `tv` along a row of 64 nodes.
    fn rise_width(height: f32, steps: u32, tv: TvWeights) -> usize {
        let res = UVec3::new(64, 1, 1);
        let mut nodes: Vec<[f32; 4]> = (0..64)
            .map(|i| [0.0, 0.0, 0.0, if i < 32 { 0.0 } else { height }])
            .collect();
        for _ in 0..steps {
            tv_step(&mut nodes, res, tv);
        }
        let rising = |f: f32| nodes.iter().position(|n| n[3] > f * height).unwrap();
        rising(0.9) - rising(0.1)
    }

    /// A surface's rise, a density step far beyond the edge, stays sharp
    /// over 2000 steps at the trainer's default weight. Squared
    /// differences diffuse it as heat (diffusivity 2w per step): its rise
    /// from a tenth to nine tenths widens to 2.56·√(4wt) ≈ 12.4 nodes; so
    /// does a step far below the edge.
    #[test]
    fn a_surface_beyond_the_edge_is_not_diffused() {
        let squared = TvWeights::squared(0.0, 3e-3);
        let edged = TvWeights {
            density_edge: 1.0,
            ..squared
        };
        let diffused = rise_width(100.0, 2000, squared);
        assert!((11..=13).contains(&diffused), "squared: {diffused} nodes");
        let sharp = rise_width(100.0, 2000, edged);
        assert!(sharp <= 1, "beyond the edge: {sharp} nodes");
        let faint = rise_width(0.01, 2000, edged);
        assert_eq!(faint, diffused, "a step far below the edge");
    }

    /// The sparsity prior clears a haze below the edge and leaves an
    /// opaque node be: 2000 steps at λ = 3e-3 with the edge at an optical
    /// depth of 0.1 per spacing (h = 1) take a haze of 0.05 down by
    /// e^(−2λt/(1 + 0.25)) ≈ 7e-5 of itself, and a node of 5 down by
    /// under 2λε²t/σ ≈ 2.4e-2 (a tenth of a percent of itself: ε²/σ²
    /// weakens its pull).
    #[test]
    fn sparsity_clears_a_haze_and_keeps_a_surface() {
        let res = UVec3::new(3, 1, 1);
        let tv = TvWeights {
            sparsity: 3e-3,
            sparsity_edge: 0.1,
            ..TvWeights::NONE
        };
        let mut nodes = vec![[0.0, 0.0, 0.0, 0.05], [0.0; 4], [0.0, 0.0, 0.0, 5.0]];
        for _ in 0..2000 {
            tv_step(&mut nodes, res, tv);
        }
        assert!(
            nodes[0][3] > 0.0 && nodes[0][3] < 0.05 * 1e-3,
            "haze {}",
            nodes[0][3]
        );
        assert_eq!(nodes[1][3], 0.0);
        assert!(
            nodes[2][3] > 4.97 && nodes[2][3] < 5.0,
            "surface {}",
            nodes[2][3]
        );
    }

    /// The prior's edge sets what it spares: over 3000 steps at λ = 1e-3
    /// (h = 1) and nothing pulling back, a haze of 0.005 falls below 1 %
    /// of itself at an edge of 0.1 and of 0.03 alike (0.25 % measured),
    /// while a medium of 0.1 (PLANTS' foliage is about 0.09 per spacing
    /// at 128 nodes) keeps under 1 % of itself at the edge of 0.1, where
    /// the pull is strongest (0.4 %), and over a quarter at 0.03 (34 %).
    #[test]
    fn a_lower_sparsity_edge_spares_a_medium_and_still_clears_a_haze() {
        let res = UVec3::new(2, 1, 1);
        let run = |edge: f64| {
            let tv = TvWeights {
                sparsity: 1e-3,
                sparsity_edge: edge,
                ..TvWeights::NONE
            };
            let mut nodes = vec![[0.0, 0.0, 0.0, 0.005], [0.0, 0.0, 0.0, 0.1]];
            for _ in 0..3000 {
                tv_step(&mut nodes, res, tv);
            }
            (nodes[0][3] / 0.005, nodes[1][3] / 0.1)
        };
        let (haze_wide, medium_wide) = run(0.1);
        let (haze_low, medium_low) = run(0.03);
        assert!(
            haze_wide < 0.01 && haze_low < 0.01,
            "haze {haze_wide} {haze_low}"
        );
        assert!(medium_wide < 0.01, "medium at 0.1: {medium_wide}");
        assert!(medium_low > 0.25, "medium at 0.03: {medium_low}");
    }

    /// A lamp's bright node beside dim ones keeps its radiance under the
    /// colour's edge, where squared differences drain it into them; a
    /// speckle far below the edge is smoothed as squared differences
    /// smooth it. 3000 steps at weight 1e-3, a row of nodes.
    #[test]
    fn a_lamp_beyond_the_colour_edge_is_not_drained() {
        let run = |lamp: f32, tv: TvWeights| {
            let res = UVec3::new(9, 1, 1);
            let mut nodes: Vec<[f32; 4]> = (0..9)
                .map(|i| {
                    let v = if i == 4 { lamp } else { 0.1 };
                    [v, v, v, 1.0]
                })
                .collect();
            for _ in 0..3000 {
                tv_step(&mut nodes, res, tv);
            }
            nodes[4][0]
        };
        let squared = TvWeights::squared(1e-3, 0.0);
        let edged = TvWeights {
            colour_edge: 0.2,
            ..squared
        };
        let drained = run(160.0, squared);
        assert!(drained < 0.2 * 160.0, "squared: {drained}");
        let kept = run(160.0, edged);
        assert!(kept > 0.95 * 160.0, "beyond the edge: {kept}");
        let (faint_squared, faint_edged) = (run(0.12, squared), run(0.12, edged));
        assert!(
            (faint_squared - faint_edged).abs() < 1e-4 && faint_edged < 0.11,
            "below the edge: {faint_squared} {faint_edged}"
        );
    }
}

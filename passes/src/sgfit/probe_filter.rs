//! What the fit fits: the probe blurred by a small angular Gaussian, so
//! that no feature of it is narrower than the sharpest lobe the fit may
//! use. Mirrored by the `filter_probe` kernel of `shaders/sgfit/fit.wgsl`.
//!
//! A least-squares fit of a lobe to a feature narrower than the lobe
//! overshoots the feature's energy (by up to 2× for a needle: the best
//! amplitude is ⟨G, L⟩/⟨G, G⟩, and ∫G/∫G² = 2 for an SG), and a lobe
//! narrower than the texel spacing, evaluated at texel centres, has an
//! energy in the fit unrelated to its true integral. Each probe texel holds
//! its mean radiance (a box of one texel, variance h²/12 per axis, h the
//! texel spacing); this filter, an isotropic SG kernel K of variance h²/2
//! widens every feature to a variance
//! of at least 7h²/12, and [`super::model::max_sharpness`] lets no lobe be
//! narrower than that, so a lobe can match a light smaller than a texel
//! with its energy. The kernel is angular, not a filter of the map's
//! texels, because texels are not square on the sphere: a texel-space
//! filter turns round lobes into ellipses no SG can fit.
//!
//! Each texel s spreads its energy Ω_s L_s over its neighbours t (the
//! texels whose centres lie where K exceeds [`KERNEL_CUTOFF`]) in
//! proportion to K(d_t·d_s) Ω_t, normalised by Z_s = Σ_t K(d_t·d_s) Ω_t,
//! so F_t = Σ_s K(d_t·d_s) Ω_s L_s / Z_s keeps the probe's energy exactly
//! (the neighbour relation is symmetric) and a constant within about a
//! per cent. Invalid texels (NaN, infinite or negative) add nothing and
//! stay invalid.

use super::model::texel_valid;
use crate::probe::DirectionMap;

/// The kernel is cut where it falls below this fraction of its peak.
pub const KERNEL_CUTOFF: f64 = 1e-3;

/// The kernel's sharpness for a map of `texels` texels: variance h²/2,
/// h² = 4π/texels, so κ = texels/(2π).
pub fn filter_sharpness(texels: usize) -> f64 {
    texels as f64 / (2.0 * std::f64::consts::PI)
}

/// The filter of one direction map as a sparse matrix: texel t's filtered
/// radiance is Σ weight·L_s over its row. Built once per map on the CPU;
/// the GPU fit applies the same rows (one definition).
#[derive(Debug, Clone)]
pub struct ProbeFilter {
    /// Row t spans `entries[offsets[t]..offsets[t + 1]]`.
    pub offsets: Vec<u32>,
    /// (source texel s, weight K(d_t·d_s) Ω_s / Z_s) of every row.
    pub entries: Vec<(u32, f64)>,
}

impl ProbeFilter {
    /// The filter for `map`. Neighbours are every texel whose centre lies
    /// within the kernel's cut-off angle, found through a grid of 3D cells
    /// that size (so the relation is symmetric across the map's folds,
    /// edges and poles, and the probe's energy is kept exactly).
    pub fn new(map: &DirectionMap) -> Self {
        let n = map.texels();
        let xy = |i: usize| (i as u32 % map.width, i as u32 / map.width);
        let dirs: Vec<glam::DVec3> = (0..n).map(|i| map.direction(xy(i).0, xy(i).1)).collect();
        let omega: Vec<f64> = (0..n).map(|i| map.solid_angle(xy(i).0, xy(i).1)).collect();
        let kappa = filter_sharpness(n);
        // K ≥ cutoff ⇔ d_t·d_s ≥ 1 + ln(cutoff)/κ ⇔ |d_t − d_s|² ≤ −2 ln(cutoff)/κ.
        let reach = (-2.0 * KERNEL_CUTOFF.ln() / kappa).sqrt();
        let cells = ((2.0 / reach).floor() as i64).max(1);
        let cell = |d: glam::DVec3| {
            let c = ((d + glam::DVec3::ONE) * 0.5 * cells as f64).floor();
            let c = c.clamp(glam::DVec3::ZERO, glam::DVec3::splat((cells - 1) as f64));
            (c.x as i64, c.y as i64, c.z as i64)
        };
        let mut grid: std::collections::HashMap<(i64, i64, i64), Vec<usize>> = Default::default();
        for (i, d) in dirs.iter().enumerate() {
            grid.entry(cell(*d)).or_default().push(i);
        }
        let near = |t: usize| -> Vec<usize> {
            let (cx, cy, cz) = cell(dirs[t]);
            let mut out = Vec::new();
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        if let Some(v) = grid.get(&(cx + dx, cy + dy, cz + dz)) {
                            out.extend(v.iter().copied().filter(|&s| {
                                (dirs[s] - dirs[t]).length_squared() <= reach * reach
                            }));
                        }
                    }
                }
            }
            out.sort_unstable();
            out
        };
        let kernel = |a: usize, b: usize| (kappa * (dirs[a].dot(dirs[b]) - 1.0)).exp();
        let neighbours: Vec<Vec<usize>> = (0..n).map(near).collect();
        // Z_s: Σ over s's neighbours t of K Ω_t, how much of s's energy
        // they take.
        let z: Vec<f64> = (0..n)
            .map(|s| neighbours[s].iter().map(|&t| kernel(s, t) * omega[t]).sum())
            .collect();
        let mut offsets = vec![0u32];
        let mut entries = Vec::new();
        for (t, row) in neighbours.iter().enumerate() {
            for &s in row {
                entries.push((s as u32, kernel(t, s) * omega[s] / z[s]));
            }
            offsets.push(entries.len() as u32);
        }
        Self { offsets, entries }
    }

    /// The filtered probe (rgb; alpha as given), row by row. Invalid texels
    /// are returned as they are and add nothing to their neighbours.
    pub fn apply(&self, texels: &[[f64; 4]]) -> Vec<[f64; 4]> {
        (0..self.offsets.len() - 1)
            .map(|t| {
                let own = texels[t];
                if !texel_valid(&own) {
                    return own;
                }
                let mut sum = [0.0; 3];
                let row = self.offsets[t] as usize..self.offsets[t + 1] as usize;
                for &(s, w) in &self.entries[row] {
                    let l = &texels[s as usize];
                    if texel_valid(l) {
                        for c in 0..3 {
                            sum[c] += w * l[c];
                        }
                    }
                }
                [sum[0], sum[1], sum[2], own[3]]
            })
            .collect()
    }
}

/// [`ProbeFilter::new`] for `map` applied to `texels`.
pub fn filter_probe(map: &DirectionMap, texels: &[[f64; 4]]) -> Vec<[f64; 4]> {
    ProbeFilter::new(map).apply(texels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::probe::MapKind;
    use crate::rng::Pcg32;

    fn energy(map: &DirectionMap, t: &[[f64; 4]]) -> [f64; 3] {
        let mut e = [0.0; 3];
        for (i, v) in t.iter().enumerate() {
            let w = map.solid_angle(i as u32 % map.width, i as u32 / map.width);
            for c in 0..3 {
                e[c] += w * v[c];
            }
        }
        e
    }

    #[test]
    fn the_filter_keeps_constants_and_the_probe_energy() {
        for (kind, n) in [
            (MapKind::Octahedral, 8),
            (MapKind::Octahedral, 32),
            (MapKind::Octahedral, 64),
            (MapKind::Octahedral, 17),
            (MapKind::Equirect, 12),
        ] {
            let map = DirectionMap::new(kind, n);
            let flat = vec![[1.0, 2.0, 3.0, 0.0]; map.texels()];
            let worst = filter_probe(&map, &flat)
                .iter()
                .map(|t| (t[0] - 1.0).abs().max((t[2] / 3.0 - 1.0).abs()))
                .fold(0.0, f64::max);
            eprintln!(
                "{kind:?} {n}: a constant moves by up to {:.3} %",
                100.0 * worst
            );
            // Small maps and the equirect map's tiny polar texels resolve the
            // kernel worst.
            let tol = if kind == MapKind::Octahedral && n >= 32 {
                5e-3
            } else {
                3e-2
            };
            assert!(worst < tol, "{kind:?} {n}: {worst}");
            let mut rng = Pcg32::new(7, n as u64);
            let texels: Vec<[f64; 4]> = (0..map.texels())
                .map(|_| {
                    let spike = if rng.next_f64() < 0.05 { 100.0 } else { 1.0 };
                    [
                        spike * rng.next_f64(),
                        rng.next_f64(),
                        2.0 * rng.next_f64(),
                        0.0,
                    ]
                })
                .collect();
            let (a, b) = (
                energy(&map, &texels),
                energy(&map, &filter_probe(&map, &texels)),
            );
            for c in 0..3 {
                assert!(
                    (b[c] / a[c] - 1.0).abs() < 1e-12,
                    "{kind:?} {n}: {a:?} vs {b:?}"
                );
            }
        }
    }

    #[test]
    fn a_single_bright_texel_keeps_its_energy_anywhere() {
        let map = DirectionMap::new(MapKind::Octahedral, 32);
        let mut worst: f64 = 0.0;
        for i in (0..map.texels()).step_by(7) {
            let mut t = vec![[0.0; 4]; map.texels()];
            t[i] = [1.0, 1.0, 1.0, 0.0];
            let (a, b) = (energy(&map, &t), energy(&map, &filter_probe(&map, &t)));
            worst = worst.max((b[0] / a[0] - 1.0).abs());
        }
        assert!(worst < 1e-12, "{worst}");
    }
}

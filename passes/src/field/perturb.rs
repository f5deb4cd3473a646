//! Fields as a trainer leaves them: a clean baked field made noisy, cloudy
//! and thin, so that what reads a field (the environment estimate first of
//! all) can be tested on fields it did not make. Three defects, each with a
//! strength, applied in a fixed order from one seed:
//! - **noise**: every occupied node's colour times a log-normal factor of
//!   standard deviation `noise` (per channel), and its density times one
//!   of the same spread;
//! - **floaters**: `floaters` small blobs of density in empty space (radius
//!   1–3 node spacings, peak density the field's 90th-percentile occupied
//!   density) with a colour drawn from the field's own occupied nodes, as
//!   a trainer leaves where few views constrain it;
//! - **see-through**: every node's density times `1 − see_through`, so
//!   surfaces let part of the light through.

use glam::{DVec3, UVec3};

use super::{GridField, DEFAULT_OCCUPANCY_BLOCK};
use crate::rng::Pcg32;

/// How strongly to perturb a field (all zero: unchanged).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Perturbation {
    /// Log-normal standard deviation of colour and density per node.
    pub noise: f64,
    /// Number of floaters.
    pub floaters: u32,
    /// Fraction of density removed everywhere, in [0, 1).
    pub see_through: f64,
    /// Seed.
    pub seed: u64,
}

impl Perturbation {
    /// Parses `noise=0.2,floaters=40,see-through=0.5,seed=3` (any subset).
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut p = Self::default();
        for item in text.split(',').filter(|s| !s.trim().is_empty()) {
            let (key, value) = item
                .split_once('=')
                .ok_or_else(|| format!("`{item}`: expected key=value"))?;
            let num = |v: &str| {
                v.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite() && *x >= 0.0)
                    .ok_or_else(|| format!("`{key}` = `{v}` must be a number ≥ 0"))
            };
            match key.trim() {
                "noise" => p.noise = num(value)?,
                "floaters" => p.floaters = num(value)? as u32,
                "see-through" => p.see_through = num(value)?,
                "seed" => p.seed = num(value)? as u64,
                other => {
                    return Err(format!(
                        "unknown key `{other}` (noise, floaters, see-through, seed)"
                    ))
                }
            }
        }
        if p.see_through >= 1.0 {
            return Err(format!("`see-through` = {} must be < 1", p.see_through));
        }
        if p.noise > 2.0 {
            return Err(format!("`noise` = {} must be ≤ 2", p.noise));
        }
        Ok(p)
    }

    /// Whether it changes anything.
    pub fn is_none(&self) -> bool {
        self.noise == 0.0 && self.floaters == 0 && self.see_through == 0.0
    }
}

/// A standard normal deviate (Box–Muller).
fn gaussian(rng: &mut Pcg32) -> f64 {
    let [u, v] = rng.next_2d();
    (-2.0 * (1.0 - u).ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
}

/// `field` with the defects of `p` (occupancy rebuilt; view-dependent
/// colour kept as it was).
pub fn perturb(field: &GridField, p: &Perturbation) -> GridField {
    let mut nodes = field.nodes.clone();
    let mut rng = Pcg32::new(p.seed, 0x9E27);
    let occupied: Vec<usize> = (0..nodes.len()).filter(|&i| nodes[i][3] > 0.0).collect();
    if p.noise > 0.0 {
        for &i in &occupied {
            let n = &mut nodes[i];
            for c in n.iter_mut().take(3) {
                *c *= (p.noise * gaussian(&mut rng)).exp() as f32;
            }
            n[3] *= (p.noise * gaussian(&mut rng)).exp() as f32;
        }
    }
    if p.floaters > 0 && !occupied.is_empty() {
        let mut densities: Vec<f32> = occupied.iter().map(|&i| field.nodes[i][3]).collect();
        densities.sort_by(f32::total_cmp);
        let peak = densities[densities.len() * 9 / 10] as f64;
        let spacing = field.spacing();
        let res = field.resolution;
        for _ in 0..p.floaters {
            // A centre in empty space, a colour from a random occupied node.
            let centre = (0..64).find_map(|_| {
                let u = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
                let x = field.bounds.min + u * field.bounds.size();
                let node = (u * (res - UVec3::ONE).as_dvec3()).round().as_uvec3();
                (field.nodes[field.index(node.x, node.y, node.z)][3] <= 0.0).then_some(x)
            });
            let Some(centre) = centre else { continue };
            let colour = field.nodes[occupied[rng.next_u32() as usize % occupied.len()]];
            let radius = (1.0 + 2.0 * rng.next_f64()) * spacing.max_element();
            let lo = ((centre - radius - field.bounds.min) / spacing)
                .floor()
                .max(DVec3::ZERO);
            let hi = ((centre + radius - field.bounds.min) / spacing)
                .ceil()
                .min((res - UVec3::ONE).as_dvec3());
            for k in lo.z as u32..=hi.z as u32 {
                for j in lo.y as u32..=hi.y as u32 {
                    for i in lo.x as u32..=hi.x as u32 {
                        let x =
                            field.bounds.min + DVec3::new(i as f64, j as f64, k as f64) * spacing;
                        let s = ((x - centre).length() / radius).min(1.0);
                        let sigma = (peak * (1.0 - s * s).powi(2)) as f32;
                        let n = &mut nodes[field.index(i, j, k)];
                        if sigma > n[3] {
                            *n = [colour[0], colour[1], colour[2], sigma];
                        }
                    }
                }
            }
        }
    }
    if p.see_through > 0.0 {
        let keep = (1.0 - p.see_through) as f32;
        for n in &mut nodes {
            n[3] *= keep;
        }
    }
    GridField::new(
        field.resolution,
        field.bounds,
        nodes,
        DEFAULT_OCCUPANCY_BLOCK,
    )
    .with_sh(field.sh_degree, field.sh.clone())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;

    fn slab() -> GridField {
        let res = UVec3::splat(16);
        let nodes = (0..16 * 16 * 16)
            .map(|i| {
                let y = (i / 16) % 16;
                if y < 4 {
                    [0.5, 0.4, 0.3, 50.0]
                } else {
                    [0.0; 4]
                }
            })
            .collect();
        GridField::new(res, Aabb::new(DVec3::ZERO, DVec3::ONE), nodes, 4)
    }

    #[test]
    fn parse_reads_keys_and_refuses_bad_ones() {
        let p = Perturbation::parse("noise=0.2, floaters=12,see-through=0.5,seed=7").unwrap();
        assert_eq!(
            p,
            Perturbation {
                noise: 0.2,
                floaters: 12,
                see_through: 0.5,
                seed: 7
            }
        );
        assert!(Perturbation::parse("").unwrap().is_none());
        for bad in ["noise", "fog=1", "see-through=1", "noise=-1", "noise=nan"] {
            assert!(Perturbation::parse(bad).is_err(), "{bad}");
        }
    }

    /// Each defect does what it says, and only it: noise keeps the mean
    /// colour within a few percent and leaves empty space empty; floaters
    /// add density only where there was none before; see-through scales
    /// every density.
    #[test]
    fn each_defect_changes_what_it_says() {
        let f = slab();
        let mean = |g: &GridField| {
            let occ: Vec<_> = g.nodes.iter().filter(|n| n[3] > 0.0).collect();
            occ.iter().map(|n| n[0] as f64).sum::<f64>() / occ.len() as f64
        };
        let noisy = perturb(
            &f,
            &Perturbation {
                noise: 0.2,
                ..Default::default()
            },
        );
        assert!((mean(&noisy) / mean(&f) - 1.02).abs() < 0.03);
        assert!(f
            .nodes
            .iter()
            .zip(&noisy.nodes)
            .all(|(a, b)| (a[3] == 0.0) == (b[3] == 0.0)));
        let cloudy = perturb(
            &f,
            &Perturbation {
                floaters: 10,
                ..Default::default()
            },
        );
        let added = f
            .nodes
            .iter()
            .zip(&cloudy.nodes)
            .filter(|(a, b)| a[3] == 0.0 && b[3] > 0.0)
            .count();
        assert!(added > 10, "{added}");
        let y_low = |i: usize| (i / 16) % 16 < 4;
        assert!(f
            .nodes
            .iter()
            .zip(&cloudy.nodes)
            .enumerate()
            .all(|(i, (a, b))| !y_low(i) || a == b));
        let thin = perturb(
            &f,
            &Perturbation {
                see_through: 0.75,
                ..Default::default()
            },
        );
        assert!(f
            .nodes
            .iter()
            .zip(&thin.nodes)
            .all(|(a, b)| (b[3] - 0.25 * a[3]).abs() < 1e-6));
    }
}

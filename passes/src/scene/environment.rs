//! The distant environment light of a recipe: black, a list of spherical
//! Gaussians, or an equirectangular EXR map. Evaluated, sampled and given
//! a sampling density for the path tracer's next-event estimation.

use std::f64::consts::PI;
use std::path::Path;

use glam::DVec3;

use crate::sg::SgLobe;
use crate::sgfit::model::luminance;

/// Distant light arriving from every direction.
#[derive(Debug, Clone)]
pub enum Environment {
    /// No distant light (every source lies inside the field, like PLANTS).
    Black,
    /// A sum of SG lobes.
    Lobes {
        /// The lobes.
        lobes: Vec<SgLobe>,
        /// Probability of sampling each lobe (∝ its luminance integral).
        weights: Vec<f64>,
    },
    /// An equirectangular map (+Y up; u = φ/2π with φ = atan2(z, x), v = θ/π
    /// from +Y), piecewise constant per pixel.
    Map(EquirectMap),
}

impl Environment {
    /// An SG environment; lobe directions are normalised (a lobe without
    /// a direction, which the scene loader refuses, is dropped).
    pub fn from_lobes(mut lobes: Vec<SgLobe>) -> Self {
        lobes.retain_mut(|l| match super::vec3::unit(l.direction) {
            Some(d) => {
                l.direction = d;
                true
            }
            None => false,
        });
        if lobes.is_empty() {
            return Environment::Black;
        }
        let energy: Vec<f64> = lobes
            .iter()
            .map(|l| luminance(l.integral()).max(0.0))
            .collect();
        let total: f64 = energy.iter().sum();
        if total <= 0.0 {
            return Environment::Black;
        }
        let weights = energy.iter().map(|e| e / total).collect();
        Environment::Lobes { lobes, weights }
    }

    /// Radiance arriving from unit direction `d`.
    pub fn eval(&self, d: DVec3) -> DVec3 {
        match self {
            Environment::Black => DVec3::ZERO,
            Environment::Lobes { lobes, .. } => lobes.iter().map(|l| l.eval(d)).sum(),
            Environment::Map(m) => m.eval(d),
        }
    }

    /// Whether there is any light to sample.
    pub fn is_black(&self) -> bool {
        matches!(self, Environment::Black)
    }

    /// A direction sampled roughly ∝ radiance, with its density.
    pub fn sample(&self, u: [f64; 3]) -> Option<(DVec3, f64)> {
        match self {
            Environment::Black => None,
            Environment::Lobes { lobes, weights } => {
                let mut acc = 0.0;
                let mut pick = lobes.len() - 1;
                for (i, w) in weights.iter().enumerate() {
                    acc += w;
                    if u[0] < acc {
                        pick = i;
                        break;
                    }
                }
                let d = lobes[pick].sample([u[1], u[2]]);
                Some((d, self.pdf(d)))
            }
            Environment::Map(m) => m.sample([u[1], u[2]]),
        }
    }

    /// The density with which [`Self::sample`] picks `d`.
    pub fn pdf(&self, d: DVec3) -> f64 {
        match self {
            Environment::Black => 0.0,
            Environment::Lobes { lobes, weights } => {
                lobes.iter().zip(weights).map(|(l, w)| w * l.pdf(d)).sum()
            }
            Environment::Map(m) => m.pdf(d),
        }
    }
}

/// An equirectangular HDR map with a luminance-proportional sampler.
#[derive(Debug, Clone)]
pub struct EquirectMap {
    width: usize,
    height: usize,
    texels: Vec<DVec3>,
    /// Cumulative row probabilities (height + 1 entries, last = 1).
    row_cdf: Vec<f64>,
    /// Per row, cumulative column probabilities (width + 1 entries each).
    col_cdf: Vec<Vec<f64>>,
    /// Probability of each texel.
    texel_p: Vec<f64>,
}

impl EquirectMap {
    /// Builds a map from linear RGB texels (row-major, top row = +Y) scaled
    /// by `scale`. Errors name the first non-finite or negative texel.
    pub fn new(
        width: usize,
        height: usize,
        texels: Vec<DVec3>,
        scale: f64,
    ) -> Result<Self, String> {
        if width < 2 || height < 1 || texels.len() != width * height {
            return Err(format!("{width}x{height} map with {} texels", texels.len()));
        }
        for (i, t) in texels.iter().enumerate() {
            if !t.is_finite() || t.min_element() < 0.0 {
                return Err(format!(
                    "pixel ({}, {}) is {t}: environment maps must be finite and non-negative",
                    i % width,
                    i / width
                ));
            }
        }
        let texels: Vec<DVec3> = texels.into_iter().map(|t| t * scale).collect();
        if let Some(i) = texels
            .iter()
            .position(|t| t.max_element() > super::RADIANCE_LIMIT)
        {
            return Err(format!(
                "pixel ({}, {}) is {} after the scale: above the radiance limit {:e} (lower `scale`)",
                i % width,
                i / width,
                texels[i],
                super::RADIANCE_LIMIT
            ));
        }
        let mut weight = vec![0.0; width * height];
        for y in 0..height {
            let sin = (PI * (y as f64 + 0.5) / height as f64).sin();
            for x in 0..width {
                weight[y * width + x] = luminance(texels[y * width + x]) * sin + 1e-12 * sin;
            }
        }
        let total: f64 = weight.iter().sum();
        let texel_p: Vec<f64> = weight.iter().map(|w| w / total).collect();
        let mut row_cdf = vec![0.0];
        let mut col_cdf = Vec::with_capacity(height);
        for y in 0..height {
            let row = &texel_p[y * width..(y + 1) * width];
            let row_sum: f64 = row.iter().sum();
            row_cdf.push(row_cdf[y] + row_sum);
            let mut c = vec![0.0];
            for (x, p) in row.iter().enumerate() {
                c.push(c[x] + p / row_sum);
            }
            col_cdf.push(c);
        }
        Ok(Self {
            width,
            height,
            texels,
            row_cdf,
            col_cdf,
            texel_p,
        })
    }

    /// Loads an EXR file (its RGB channels) scaled by `scale`.
    pub fn load(path: &Path, scale: f64) -> Result<Self, String> {
        let img = inlay_engine::HdrImage::load_exr(path).map_err(|e| e.to_string())?;
        let texels = img
            .pixels
            .iter()
            .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
            .collect();
        Self::new(img.width as usize, img.height as usize, texels, scale)
            .map_err(|e| format!("{}: {e}", path.display()))
    }

    fn texel_of(&self, d: DVec3) -> usize {
        let theta = d.y.clamp(-1.0, 1.0).acos();
        // Straight up or down φ is 0 whatever the zeros' signs (atan2 of
        // ±0 reads 0 or ±π), as the learnt sky reads it
        // (crate::field::sky::sky_corners).
        let phi = if d.x == 0.0 && d.z == 0.0 {
            0.0
        } else {
            d.z.atan2(d.x).rem_euclid(2.0 * PI)
        };
        let x = ((phi / (2.0 * PI)) * self.width as f64) as usize;
        let y = ((theta / PI) * self.height as f64) as usize;
        y.min(self.height - 1) * self.width + x.min(self.width - 1)
    }

    /// Radiance from unit direction `d`.
    pub fn eval(&self, d: DVec3) -> DVec3 {
        self.texels[self.texel_of(d)]
    }

    /// A direction ∝ luminance·sin θ per texel, uniform within the texel's
    /// (φ, θ) rectangle, with its density.
    pub fn sample(&self, u: [f64; 2]) -> Option<(DVec3, f64)> {
        let y = self
            .row_cdf
            .partition_point(|&c| c <= u[0])
            .clamp(1, self.height)
            - 1;
        let row = &self.col_cdf[y];
        let x = row.partition_point(|&c| c <= u[1]).clamp(1, self.width) - 1;
        // Re-use the fractional position inside the chosen bins.
        let fy =
            ((u[0] - self.row_cdf[y]) / (self.row_cdf[y + 1] - self.row_cdf[y])).clamp(0.0, 1.0);
        let fx = ((u[1] - row[x]) / (row[x + 1] - row[x])).clamp(0.0, 1.0);
        let theta = PI * (y as f64 + fy) / self.height as f64;
        let phi = 2.0 * PI * (x as f64 + fx) / self.width as f64;
        let d = DVec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        );
        let p = self.pdf(d);
        (p > 0.0).then_some((d, p))
    }

    /// Density of [`Self::sample`] at `d`: texel probability over the
    /// texel's solid angle (area-element sin θ at the direction).
    pub fn pdf(&self, d: DVec3) -> f64 {
        let sin = (1.0 - d.y * d.y).max(0.0).sqrt();
        if sin <= 0.0 {
            return 0.0;
        }
        let texel_area = (2.0 * PI / self.width as f64) * (PI / self.height as f64);
        self.texel_p[self.texel_of(d)] / (texel_area * sin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    /// E[f/pdf] over env samples must equal the uniform-sphere estimate of
    /// ∫ L(ω) dω for both kinds.
    #[test]
    fn sampling_is_unbiased() {
        let lobes = Environment::from_lobes(vec![
            SgLobe {
                direction: DVec3::new(0.3, 1.0, 0.0),
                sharpness: 30.0,
                amplitude: DVec3::splat(50.0),
            },
            SgLobe {
                direction: DVec3::X,
                sharpness: 0.5,
                amplitude: DVec3::new(0.2, 0.3, 0.4),
            },
        ]);
        let mut texels = vec![DVec3::splat(0.1); 32 * 16];
        texels[3 * 32 + 5] = DVec3::splat(200.0);
        let map = Environment::Map(EquirectMap::new(32, 16, texels, 1.0).unwrap());
        for env in [lobes, map] {
            let mut rng = Pcg32::new(9, 9);
            let n = 200_000;
            let mut est = 0.0;
            for _ in 0..n {
                let (d, p) = env
                    .sample([rng.next_f64(), rng.next_f64(), rng.next_f64()])
                    .unwrap();
                est += env.eval(d).y / p;
            }
            est /= n as f64;
            let mut uni = 0.0;
            let m = 2_000_000;
            for _ in 0..m {
                let [a, b] = rng.next_2d();
                let z = 1.0 - 2.0 * a;
                let r = (1.0 - z * z).sqrt();
                let phi = 2.0 * PI * b;
                uni += env.eval(DVec3::new(r * phi.cos(), z, r * phi.sin())).y;
            }
            uni *= 4.0 * PI / m as f64;
            assert!((est / uni - 1.0).abs() < 0.02, "{est} vs {uni}");
        }
    }

    #[test]
    fn bad_texels_are_named() {
        let mut t = vec![DVec3::ONE; 8];
        t[5] = DVec3::new(f64::NAN, 0.0, 0.0);
        let e = EquirectMap::new(4, 2, t, 1.0).unwrap_err();
        assert!(e.contains("pixel (1, 1)"), "{e}");
    }

    /// Straight up or down reads the same texel whatever the signs of the
    /// zeros, the one the learnt sky's φ = 0 reads.
    #[test]
    fn a_vertical_ray_reads_one_texel() {
        let texels: Vec<DVec3> = (0..32).map(|i| DVec3::splat(i as f64)).collect();
        let map = EquirectMap::new(8, 4, texels, 1.0).unwrap();
        for y in [1.0, -1.0] {
            let reads: Vec<DVec3> = [(0.0, 0.0), (-0.0, 0.0), (0.0, -0.0), (-0.0, -0.0)]
                .iter()
                .map(|&(x, z)| map.eval(DVec3::new(x, y, z)))
                .collect();
            assert!(reads.iter().all(|r| *r == reads[0]), "{y}: {reads:?}");
            let row = if y > 0.0 { 0.0 } else { 24.0 };
            assert_eq!(reads[0], DVec3::splat(row));
        }
    }
}

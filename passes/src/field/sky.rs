//! A field's sky: what a ray sees once it leaves the field's bounds,
//! learnt with a trained field (`inlay train --sky`) and drawn behind it
//! ([`crate::sky_behind`]). Radiance as a function of direction only (beyond
//! the box, where the photographs' cameras see the rest of the world: the
//! sky, a far wall), an equirectangular map of 2n × n texels in the scene
//! environment's convention (+Y up, u = φ/2π with φ = atan2(z, x), v = θ/π
//! from +Y; [`crate::scene::EquirectMap`]), read bilinearly between texel
//! centres, wrapping round in φ and held at the first and last rows in θ.
//! `shaders/field/sky.wgsl` mirrors [`Sky::corners`]. A field file's sky
//! is the EXR beside it ([`sky_path`]).

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use glam::DVec3;

/// Largest sky height [`Sky::new`] takes (2048 × 1024 texels, 16 MiB on
/// the device with the gradient and Adam's moments).
pub const MAX_SKY_HEIGHT: u32 = 1024;

/// A learnt sky: `2·height × height` linear RGB texels, row-major, the top
/// row looking along +Y.
#[derive(Debug, Clone, PartialEq)]
pub struct Sky {
    /// Texels across (2 × height).
    pub width: u32,
    /// Texels down.
    pub height: u32,
    /// The texels' radiance.
    pub texels: Vec<DVec3>,
}

impl Sky {
    /// A sky of `2·height × height` texels, every one `colour`.
    pub fn uniform(height: u32, colour: DVec3) -> Self {
        let height = height.clamp(1, MAX_SKY_HEIGHT);
        Self {
            width: 2 * height,
            height,
            texels: vec![colour; (2 * height * height) as usize],
        }
    }

    /// A sky from texels (row-major, `width = 2·height`), refused with a
    /// reason when the sizes disagree or a texel is negative or not finite.
    pub fn new(width: u32, height: u32, texels: Vec<DVec3>) -> Result<Self, String> {
        if height == 0 || height > MAX_SKY_HEIGHT || width != 2 * height {
            return Err(format!(
                "{width}x{height} texels: a sky is 2n x n with n in 1..={MAX_SKY_HEIGHT}"
            ));
        }
        if texels.len() != (width * height) as usize {
            return Err(format!("{} texels for {width}x{height}", texels.len()));
        }
        if let Some(i) = texels
            .iter()
            .position(|t| !t.is_finite() || t.min_element() < 0.0)
        {
            return Err(format!(
                "texel ({}, {}) is {}: a sky's radiance is finite and non-negative",
                i as u32 % width,
                i as u32 / width,
                texels[i]
            ));
        }
        Ok(Self {
            width,
            height,
            texels,
        })
    }

    /// The four texels direction `d` (unit) reads and their weights
    /// (summing to 1).
    pub fn corners(&self, d: DVec3) -> [(usize, f64); 4] {
        sky_corners(self.width, self.height, d)
    }

    /// Radiance from unit direction `d`.
    pub fn eval(&self, d: DVec3) -> DVec3 {
        self.corners(d)
            .iter()
            .map(|&(i, w)| w * self.texels[i])
            .sum()
    }

    /// Gives each texel not `seen` the mean of its seen neighbours (left,
    /// right, wrapping round in φ; up, down), then of those filled so,
    /// ring by ring: the sky where no photograph looked past the field
    /// goes on as the nearest it did see. Nothing seen leaves it as it is.
    pub fn fill_unseen(&mut self, seen: &[bool]) {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut known = seen.to_vec();
        known.resize(w * h, false);
        loop {
            let mut ring = Vec::new();
            for y in 0..h {
                for x in 0..w {
                    if known[y * w + x] {
                        continue;
                    }
                    let mut near = vec![y * w + (x + w - 1) % w, y * w + (x + 1) % w];
                    if y > 0 {
                        near.push((y - 1) * w + x);
                    }
                    if y + 1 < h {
                        near.push((y + 1) * w + x);
                    }
                    let from: Vec<usize> = near.into_iter().filter(|&n| known[n]).collect();
                    if !from.is_empty() {
                        let mean =
                            from.iter().map(|&n| self.texels[n]).sum::<DVec3>() / from.len() as f64;
                        ring.push((y * w + x, mean));
                    }
                }
            }
            if ring.is_empty() {
                return;
            }
            for (i, c) in ring {
                self.texels[i] = c;
                known[i] = true;
            }
        }
    }

    /// The sky as an image (for an EXR file: rows top to bottom, alpha 1).
    pub fn to_image(&self) -> inlay_engine::HdrImage {
        inlay_engine::HdrImage {
            width: self.width,
            height: self.height,
            pixels: self
                .texels
                .iter()
                .map(|t| {
                    let t = t.as_vec3();
                    [t.x, t.y, t.z, 1.0]
                })
                .collect(),
        }
    }

    /// The sky in the EXR file `path`, refused with the file's name and
    /// the reason where it cannot be read or is not a sky.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let image = inlay_engine::HdrImage::load_exr(path)?;
        Self::from_image(&image).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
    }

    /// The sky as a scene's distant light: an equirect map of the same
    /// texels (read per texel where the sky reads bilinearly; lit through
    /// an SG fit, the two do not differ).
    pub fn to_environment(&self) -> Result<crate::scene::Environment, String> {
        let map = crate::scene::EquirectMap::new(
            self.width as usize,
            self.height as usize,
            self.texels.clone(),
            1.0,
        )?;
        Ok(crate::scene::Environment::Map(map))
    }

    /// The sky an image holds ([`Self::to_image`]'s), refused with a
    /// reason where [`Self::new`] would refuse it.
    pub fn from_image(image: &inlay_engine::HdrImage) -> Result<Self, String> {
        let texels = image
            .pixels
            .iter()
            .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
            .collect();
        Self::new(image.width, image.height, texels)
    }
}

/// Where the sky learnt with the field file `field` is kept: FIELD.sky.exr
/// beside it (an equirect map in the scene environment's convention, which
/// a scene's `[environment] equirect` can name too).
pub fn sky_path(field: &Path) -> PathBuf {
    field.with_extension("sky.exr")
}

/// The four texels of a `width × height` sky that unit direction `d` reads
/// bilinearly, and their weights: texel (x, y)'s centre looks along
/// φ = 2π(x + ½)/width, θ = π(y + ½)/height.
pub fn sky_corners(width: u32, height: u32, d: DVec3) -> [(usize, f64); 4] {
    let theta = (d.x.hypot(d.z)).atan2(d.y);
    // Straight up or down φ is 0, whatever the zeros' signs.
    let phi = if d.x == 0.0 && d.z == 0.0 {
        0.0
    } else {
        d.z.atan2(d.x).rem_euclid(2.0 * PI)
    };
    let u = (phi / (2.0 * PI) * width as f64 - 0.5).clamp(-0.5, width as f64 - 0.5);
    let x0 = u.floor();
    let fx = u - x0;
    let w = width as i64;
    let x0 = (x0 as i64).rem_euclid(w) as usize;
    let x1 = (x0 + 1) % width as usize;
    let v = (theta / PI * height as f64 - 0.5).clamp(0.0, (height - 1) as f64);
    let y0 = v.floor();
    let fy = v - y0;
    let y0 = y0 as usize;
    let y1 = (y0 + 1).min(height as usize - 1);
    let row = |y: usize| y * width as usize;
    [
        (row(y0) + x0, (1.0 - fx) * (1.0 - fy)),
        (row(y0) + x1, fx * (1.0 - fy)),
        (row(y1) + x0, (1.0 - fx) * fy),
        (row(y1) + x1, fx * fy),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    fn direction(theta: f64, phi: f64) -> DVec3 {
        DVec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        )
    }

    /// At a texel's centre the sky reads that texel alone, the texel the
    /// scene's equirect map reads there (one convention for both).
    #[test]
    fn a_texel_centre_reads_its_texel_as_the_scene_map_does() {
        let (w, h) = (16u32, 8u32);
        let mut rng = Pcg32::new(3, 1);
        let texels: Vec<DVec3> = (0..w * h)
            .map(|_| DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()))
            .collect();
        let sky = Sky::new(w, h, texels.clone()).unwrap();
        let map = crate::scene::EquirectMap::new(w as usize, h as usize, texels, 1.0).unwrap();
        for y in 0..h {
            for x in 0..w {
                let d = direction(
                    PI * (y as f64 + 0.5) / h as f64,
                    2.0 * PI * (x as f64 + 0.5) / w as f64,
                );
                let i = (y * w + x) as usize;
                assert!((sky.eval(d) - sky.texels[i]).abs().max_element() < 1e-9);
                assert!((map.eval(d) - sky.texels[i]).abs().max_element() < 1e-12);
            }
        }
    }

    /// The weights sum to 1 everywhere, the poles included, and the sky is
    /// continuous across the seam at φ = 0 and over the poles' rows.
    #[test]
    fn the_weights_sum_to_one_and_the_seam_is_continuous() {
        let sky = Sky::new(
            8,
            4,
            (0..32)
                .map(|i| DVec3::splat(i as f64 * 0.37 % 1.9))
                .collect(),
        )
        .unwrap();
        let mut rng = Pcg32::new(5, 2);
        for _ in 0..500 {
            let d = direction(PI * rng.next_f64(), 2.0 * PI * rng.next_f64());
            let total: f64 = sky.corners(d).iter().map(|c| c.1).sum();
            assert!((total - 1.0).abs() < 1e-12 && sky.corners(d).iter().all(|c| c.1 >= 0.0));
        }
        for theta in [0.0, 0.3, 1.5, 2.9, PI] {
            let a = sky.eval(direction(theta, 1e-9));
            let b = sky.eval(direction(theta, 2.0 * PI - 1e-9));
            assert!((a - b).abs().max_element() < 1e-6, "θ {theta}: {a} {b}");
        }
        // Straight up or down reads φ = 0 whatever the zeros' signs (as
        // the shader, where atan2(0, 0) is not defined).
        assert!(sky.eval(DVec3::Y).is_finite() && sky.eval(-DVec3::Y).is_finite());
        let down = DVec3::new(-0.0, -1.0, -0.0);
        assert_eq!(sky.corners(down), sky.corners(DVec3::new(0.0, -1.0, 0.0)));
        assert_eq!(
            sky.corners(down),
            sky.corners(DVec3::new(1e-300, -1.0, 0.0))
        );
    }

    /// The unseen texels take the nearest seen ones' colour, ring by ring
    /// (across the seam too); the seen ones keep theirs; nothing seen
    /// changes nothing.
    #[test]
    fn unseen_texels_go_on_as_the_nearest_seen() {
        let mut sky = Sky::uniform(4, DVec3::splat(0.5));
        let mut seen = vec![false; 32];
        // Row 2: texel 0 red, texel 7 (its neighbour across the seam) blue.
        sky.texels[16] = DVec3::X;
        sky.texels[23] = DVec3::Z;
        seen[16] = true;
        seen[23] = true;
        let before = sky.clone();
        sky.fill_unseen(&[false; 32]);
        assert_eq!(sky, before);
        sky.fill_unseen(&seen);
        assert_eq!(sky.texels[16], DVec3::X);
        assert_eq!(sky.texels[23], DVec3::Z);
        // Texel 1 of row 2 sees only texel 0; texel 6 only texel 7.
        assert_eq!(sky.texels[17], DVec3::X);
        assert_eq!(sky.texels[22], DVec3::Z);
        // Straight above texel 0 (row 1), and two rows up (row 0).
        assert_eq!(sky.texels[8], DVec3::X);
        assert_eq!(sky.texels[0], DVec3::X);
        // Every texel is a mix of red and blue now, the grey gone.
        assert!(sky
            .texels
            .iter()
            .all(|t| t.y == 0.0 && (t.x + t.z - 1.0).abs() < 1e-12));
    }

    /// Bad sizes and texels are refused, naming the texel.
    #[test]
    fn a_bad_sky_is_refused() {
        assert!(Sky::new(6, 4, vec![DVec3::ZERO; 24]).is_err());
        assert!(Sky::new(8, 4, vec![DVec3::ZERO; 31]).is_err());
        let mut t = vec![DVec3::ONE; 32];
        t[9] = DVec3::new(0.0, f64::NAN, 0.0);
        let e = Sky::new(8, 4, t).unwrap_err();
        assert!(e.contains("(1, 1)"), "{e}");
        let sky = Sky::uniform(4, DVec3::splat(0.5));
        assert_eq!(Sky::from_image(&sky.to_image()).unwrap(), sky);
    }
}

//! Image figures for comparing inlay with an independent renderer: relative
//! differences, PSNR on tonemapped values, the inserted object's brightness
//! and error inside its mask, and the cast shadow as the ratio of the
//! images with and without the object.

use glam::DVec3;
use inlay_engine::HdrImage;
use inlay_passes::bake::PathTracer;
use inlay_passes::camera::CameraFrame;
use inlay_passes::geometry::ray_box;
use inlay_passes::geometry::MeshScene;
use inlay_passes::object::PlacedObject;
use inlay_passes::scene::{Environment, Recipe};
use rayon::prelude::*;

/// Rec. 709 luminance.
pub fn luminance(c: DVec3) -> f64 {
    c.dot(DVec3::new(0.2126, 0.7152, 0.0722))
}

/// An image as f64 RGB, row-major from the top.
#[derive(Debug, Clone)]
pub struct Rgb {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The pixels.
    pub pixels: Vec<DVec3>,
}

impl Rgb {
    /// The colour of an HDR image (its fourth channel dropped).
    pub fn of(image: &HdrImage) -> Self {
        Self {
            width: image.width,
            height: image.height,
            pixels: image
                .pixels
                .iter()
                .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
                .collect(),
        }
    }

    /// The per-pixel mean of two images of one size.
    pub fn mean(a: &Rgb, b: &Rgb) -> Self {
        Self {
            width: a.width,
            height: a.height,
            pixels: a
                .pixels
                .iter()
                .zip(&b.pixels)
                .map(|(x, y)| 0.5 * (x + y))
                .collect(),
        }
    }

    /// As an HDR image (alpha 1).
    pub fn to_hdr(&self) -> HdrImage {
        HdrImage {
            width: self.width,
            height: self.height,
            pixels: self
                .pixels
                .iter()
                .map(|p| [p.x as f32, p.y as f32, p.z as f32, 1.0])
                .collect(),
        }
    }
}

/// Σ|a − b| / Σ|b| over the pixels where `mask` holds (luminance).
pub fn relative_l1(a: &Rgb, b: &Rgb, mask: impl Fn(usize) -> bool) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (i, (x, y)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        if mask(i) {
            num += (luminance(*x) - luminance(*y)).abs();
            den += luminance(*y).abs();
        }
    }
    if den > 0.0 {
        num / den
    } else {
        f64::NAN
    }
}

/// Mean luminance of `a` over the mask divided by that of `b`.
pub fn mean_ratio(a: &Rgb, b: &Rgb, mask: impl Fn(usize) -> bool) -> f64 {
    let (mut sa, mut sb) = (0.0, 0.0);
    for (i, (x, y)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        if mask(i) {
            sa += luminance(*x);
            sb += luminance(*y);
        }
    }
    sa / sb
}

/// The median over the mask of |a − b| / b in luminance (pixels where b is
/// black are left out).
pub fn median_relative_error(a: &Rgb, b: &Rgb, mask: impl Fn(usize) -> bool) -> f64 {
    median(
        a.pixels
            .iter()
            .zip(&b.pixels)
            .enumerate()
            .filter(|(i, (_, y))| mask(*i) && luminance(**y) > 0.0)
            .map(|(_, (x, y))| (luminance(*x) / luminance(*y) - 1.0).abs())
            .collect(),
    )
}

/// The upper median of `values` (NaN when empty).
fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// The median over the mask of |s0 − s1| / (s0 + s1) in luminance: how far
/// the mean of two independent renders (seeds) lies from the noise-free
/// image in the median pixel, since the half-difference of two seeds has
/// the same spread as their mean's error. A perfect renderer compared with
/// the mean of the seeds by [`median_relative_error`] scores about this.
pub fn median_seed_noise(s0: &Rgb, s1: &Rgb, mask: impl Fn(usize) -> bool) -> f64 {
    median(
        s0.pixels
            .iter()
            .zip(&s1.pixels)
            .enumerate()
            .map(|(i, (x, y))| (i, luminance(*x), luminance(*y)))
            .filter(|&(i, x, y)| mask(i) && x + y > 0.0)
            .map(|(_, x, y)| (x - y).abs() / (x + y))
            .collect(),
    )
}

/// The engine's sRGB encoding (of a value clamped to [0, 1]), in f64.
fn srgb(x: f64) -> f64 {
    inlay_engine::tonemap::srgb_encode(x as f32) as f64
}

/// PSNR (dB) of `a` against `b` on sRGB-encoded values clamped to [0, 1]
/// at `exposure`, over every channel of the pixels where `mask` holds.
pub fn psnr(a: &Rgb, b: &Rgb, exposure: f64, mask: impl Fn(usize) -> bool) -> f64 {
    let (mut se, mut n) = (0.0, 0usize);
    for (i, (x, y)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        if !mask(i) {
            continue;
        }
        for c in 0..3 {
            let d = srgb(x[c] * exposure) - srgb(y[c] * exposure);
            se += d * d;
        }
        n += 3;
    }
    let mse = se / n.max(1) as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        -10.0 * mse.log10()
    }
}

/// Pearson correlation of x and y over the mask.
pub fn correlation(x: &[f64], y: &[f64], mask: &impl Fn(usize) -> bool) -> f64 {
    let idx: Vec<usize> = (0..x.len()).filter(|&i| mask(i)).collect();
    let n = idx.len() as f64;
    let mx = idx.iter().map(|&i| x[i]).sum::<f64>() / n;
    let my = idx.iter().map(|&i| y[i]).sum::<f64>() / n;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for &i in &idx {
        let (a, b) = (x[i] - mx, y[i] - my);
        sxy += a * b;
        sxx += a * a;
        syy += b * b;
    }
    sxy / (sxx * syy).sqrt()
}

/// The mean of each pixel's (2·`radius` + 1)² neighbours where `mask` holds
/// (the pixel itself where none does): Monte-Carlo noise averaged down,
/// across `mask`'s edges nothing mixed in.
pub fn masked_box_mean(img: &Rgb, radius: u32, mask: impl Fn(usize) -> bool) -> Rgb {
    let (w, h) = (img.width as i64, img.height as i64);
    let r = radius as i64;
    let pixels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let (mut sum, mut n) = (DVec3::ZERO, 0u32);
            for yy in (y - r).max(0)..=(y + r).min(h - 1) {
                for xx in (x - r).max(0)..=(x + r).min(w - 1) {
                    let i = (yy * w + xx) as usize;
                    if mask(i) {
                        sum += img.pixels[i];
                        n += 1;
                    }
                }
            }
            if n == 0 {
                img.pixels[(y * w + x) as usize]
            } else {
                sum / n as f64
            }
        })
        .collect();
    Rgb {
        width: img.width,
        height: img.height,
        pixels,
    }
}

/// A surface point further than this many bounding radii from every object
/// counts as far from them.
pub const FAR_RADII: f64 = 4.0;

/// The shadow's ratio images are means over (2 · this + 1)² pixels.
pub const SHADOW_BOX: u32 = 1;

/// Which pixels see a surface point further than [`FAR_RADII`] bounding
/// radii from each of `spheres` (centre, radius), by `cover`'s points.
pub fn far_pixels(cover: &Coverage, spheres: &[(DVec3, f64)]) -> Vec<bool> {
    cover
        .point
        .iter()
        .map(|p| {
            p.is_some_and(|p| {
                spheres
                    .iter()
                    .all(|(c, r)| (p - *c).length() > FAR_RADII * r)
            })
        })
        .collect()
}

/// The shadow's ratio image ([`shadow_ratio`]) of [`SHADOW_BOX`] means
/// over the pixels where `field_only` holds (the field alone seen): Cycles'
/// per-pixel noise (5–19 % at 512 samples) would otherwise put hundreds of
/// pixels below 0.9 by chance (ROOM: 1241 per pixel, 721 after the means)
/// and cap the correlation.
pub fn box_shadow_ratio(
    with: &Rgb,
    bare: &Rgb,
    field_only: impl Fn(usize) -> bool + Copy,
) -> Vec<f64> {
    shadow_ratio(
        &masked_box_mean(with, SHADOW_BOX, field_only),
        &masked_box_mean(bare, SHADOW_BOX, field_only),
    )
}

/// The shadow an object casts: luminance of the image with the object over
/// the image without it, 1 where the bare image is black.
pub fn shadow_ratio(with: &Rgb, bare: &Rgb) -> Vec<f64> {
    with.pixels
        .iter()
        .zip(&bare.pixels)
        .map(|(w, b)| {
            let b = luminance(*b);
            if b > 1e-6 {
                luminance(*w) / b
            } else {
                1.0
            }
        })
        .collect()
}

/// The cast shadow of inlay against the truth's, over the field's pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowFigures {
    /// Correlation of the darkening 1 − ratio, inlay against the truth.
    pub correlation: f64,
    /// Pixels darkened below 0.9 by inlay over those by the truth.
    pub area_ratio: f64,
    /// Pixels the truth darkens below 0.9.
    pub truth_area: usize,
    /// inlay's mean darkening over the far pixels.
    pub far_darkening: f64,
    /// The truth's own mean darkening there.
    pub truth_far_darkening: f64,
    /// How many pixels are far.
    pub far_pixels: usize,
    /// The umbra: pixels the truth darkens below [`UMBRA`].
    pub umbra_pixels: usize,
    /// The truth's mean ratio over the umbra.
    pub truth_umbra: f64,
    /// inlay's mean ratio over the same pixels.
    pub umbra: f64,
    /// The area ratio at each of [`AREA_THRESHOLDS`]: where a shadow's
    /// edge is a broad plateau near 0.9, the one threshold's figure swings
    /// with a percent of darkening, and its neighbours show it.
    pub area_ratios: [f64; 4],
    /// inlay's total darkening Σ max(1 − ratio, 0) over the truth's, over
    /// the pixels either darkens below [`SHADOW_EDGE`]: how much light the
    /// shadow takes in all, whatever its threshold.
    pub darkening_ratio: f64,
}

/// The ratios at which [`ShadowFigures::area_ratios`] counts the shadow's
/// pixels (the figure is the one at 0.9).
pub const AREA_THRESHOLDS: [f64; 4] = [0.8, 0.85, 0.9, 0.95];

/// The ratio below which a pixel counts towards
/// [`ShadowFigures::darkening_ratio`] (above it, noise and far veils).
pub const SHADOW_EDGE: f64 = 0.97;

/// The shadow ratio below which the truth's shadow counts as its umbra,
/// where the shadow's depth (not its extent) is compared.
pub const UMBRA: f64 = 0.5;

/// The shadow figures over the pixels where `field` holds (the field alone
/// seen); the far-field darkening over those where `far` holds too.
pub fn shadow_figures(
    inlay: &[f64],
    truth: &[f64],
    field: impl Fn(usize) -> bool,
    far: impl Fn(usize) -> bool,
) -> ShadowFigures {
    let di: Vec<f64> = inlay.iter().map(|r| 1.0 - r).collect();
    let dt: Vec<f64> = truth.iter().map(|r| 1.0 - r).collect();
    let area_below = |r: &[f64], t: f64| (0..r.len()).filter(|&i| field(i) && r[i] < t).count();
    let area = |r: &[f64]| area_below(r, 0.9);
    let far: Vec<usize> = (0..truth.len()).filter(|&i| field(i) && far(i)).collect();
    let mean_over = |d: &[f64]| far.iter().map(|&i| d[i]).sum::<f64>() / far.len().max(1) as f64;
    let truth_area = area(truth);
    let umbra: Vec<usize> = (0..truth.len())
        .filter(|&i| field(i) && truth[i] < UMBRA)
        .collect();
    let umbra_mean =
        |r: &[f64]| umbra.iter().map(|&i| r[i]).sum::<f64>() / umbra.len().max(1) as f64;
    ShadowFigures {
        correlation: correlation(&di, &dt, &field),
        area_ratio: area(inlay) as f64 / truth_area.max(1) as f64,
        truth_area,
        far_darkening: mean_over(&di),
        truth_far_darkening: mean_over(&dt),
        far_pixels: far.len(),
        umbra_pixels: umbra.len(),
        truth_umbra: umbra_mean(truth),
        umbra: umbra_mean(inlay),
        area_ratios: AREA_THRESHOLDS
            .map(|t| area_below(inlay, t) as f64 / area_below(truth, t).max(1) as f64),
        darkening_ratio: {
            let shadow = (0..truth.len())
                .filter(|&i| field(i) && (truth[i] < SHADOW_EDGE || inlay[i] < SHADOW_EDGE));
            let (mut a, mut b) = (0.0, 0.0);
            for i in shadow {
                a += di[i].max(0.0);
                b += dt[i].max(0.0);
            }
            a / b.max(f64::MIN_POSITIVE)
        },
    }
}

/// The geometry seen through each pixel, traced from the recipe and the
/// objects themselves (not from any render).
#[derive(Debug, Clone)]
pub struct Coverage {
    /// The fraction of the pixel's rays that meet the field (a surface or
    /// medium of the recipe inside its bounds) before any object.
    pub field: Vec<f64>,
    /// The fraction that hit an object before any opaque surface of the
    /// field (seen directly or through a medium such as glass).
    pub object: Vec<f64>,
    /// The fraction that cross a medium (glass, foliage) before the first
    /// opaque surface.
    pub medium: Vec<f64>,
    /// Where the ray through the pixel's centre first meets the field.
    pub point: Vec<Option<DVec3>>,
}

/// [`Coverage`] of `camera`'s pixels with `side`² stratified rays each.
pub fn coverage(
    recipe: &Recipe,
    objects: &[PlacedObject],
    camera: &CameraFrame,
    side: u32,
) -> Coverage {
    let meshes = MeshScene::new(objects);
    let env = Environment::Black;
    let tracer = PathTracer::new(recipe, &env, 0).with_objects(&meshes);
    let surface_hit = |ray: &inlay_passes::geometry::Ray| -> Option<f64> {
        let (t0, t1) = ray_box(ray, &recipe.bounds)?;
        tracer.nearest_surface(ray, t0.max(0.0), t1).map(|(t, _)| t)
    };
    let field_hit = |ray: &inlay_passes::geometry::Ray| -> Option<f64> {
        let (t0, t1) = ray_box(ray, &recipe.bounds)?;
        let t0 = t0.max(0.0);
        let surface = surface_hit(ray);
        let medium = recipe
            .primitives
            .iter()
            .filter(|p| p.medium_density.is_some())
            .filter_map(|p| p.shape.interval(ray))
            .filter(|&(a, b)| b > t0 && a < t1)
            .map(|(a, _)| a.max(t0))
            .reduce(f64::min);
        match (surface, medium) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    };
    let through_medium = |ray: &inlay_passes::geometry::Ray, t_end: f64| -> bool {
        ray_box(ray, &recipe.bounds).is_some_and(|(t0, t1)| {
            let (t0, t1) = (t0.max(0.0), t1.min(t_end));
            recipe
                .primitives
                .iter()
                .filter(|p| p.medium_density.is_some())
                .filter_map(|p| p.shape.interval(ray))
                .any(|(a, b)| b > t0 && a < t1)
        })
    };
    let (w, h) = (camera.width, camera.height);
    let per_pixel: Vec<(f64, f64, f64, Option<DVec3>)> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let (mut field, mut object, mut medium) = (0.0, 0.0, 0.0);
            for j in 0..side * side {
                let jx = ((j % side) as f64 + 0.5) / side as f64;
                let jy = ((j / side) as f64 + 0.5) / side as f64;
                let ray = camera.ray(x as f64 + jx, y as f64 + jy);
                let t_object = tracer
                    .nearest_object(&ray, 0.0, f64::INFINITY)
                    .map_or(f64::INFINITY, |(t, _)| t);
                let t_field = field_hit(&ray).unwrap_or(f64::INFINITY);
                let t_surface = surface_hit(&ray).unwrap_or(f64::INFINITY);
                if t_object < t_surface {
                    object += 1.0;
                }
                if t_field < t_object {
                    field += 1.0;
                }
                if through_medium(&ray, t_surface.min(t_object)) {
                    medium += 1.0;
                }
            }
            let centre = camera.ray(x as f64 + 0.5, y as f64 + 0.5);
            let point = field_hit(&centre).map(|t| centre.at(t));
            let n = (side * side) as f64;
            (field / n, object / n, medium / n, point)
        })
        .collect();
    let mut c = Coverage {
        field: Vec::with_capacity(per_pixel.len()),
        object: Vec::with_capacity(per_pixel.len()),
        medium: Vec::with_capacity(per_pixel.len()),
        point: Vec::with_capacity(per_pixel.len()),
    };
    for (f, o, m, p) in per_pixel {
        c.field.push(f);
        c.object.push(o);
        c.medium.push(m);
        c.point.push(p);
    }
    c
}

/// The image averaged over `block` × `block` pixel blocks (partial blocks
/// at the edges dropped) where every pixel of the block holds `mask`:
/// Monte-Carlo noise falls by the block's side while a bias stays. Blocks
/// that fail the mask are black in both images alike.
pub fn block_means(img: &Rgb, block: u32, mask: impl Fn(usize) -> bool) -> Rgb {
    let (bw, bh) = (img.width / block, img.height / block);
    let mut pixels = Vec::with_capacity((bw * bh) as usize);
    for by in 0..bh {
        for bx in 0..bw {
            let mut sum = DVec3::ZERO;
            let mut ok = true;
            for y in by * block..(by + 1) * block {
                for x in bx * block..(bx + 1) * block {
                    let i = (y * img.width + x) as usize;
                    ok &= mask(i);
                    sum += img.pixels[i];
                }
            }
            pixels.push(if ok {
                sum / (block * block) as f64
            } else {
                DVec3::ZERO
            });
        }
    }
    Rgb {
        width: bw,
        height: bh,
        pixels,
    }
}

/// Truth | inlay | |inlay − truth| side by side, one image.
pub fn side_by_side(truth: &Rgb, inlay: &Rgb) -> Rgb {
    let (w, h) = (truth.width as usize, truth.height as usize);
    let mut pixels = Vec::with_capacity(3 * w * h);
    for y in 0..h {
        for panel in 0..3 {
            for x in 0..w {
                let (t, i) = (truth.pixels[y * w + x], inlay.pixels[y * w + x]);
                pixels.push(match panel {
                    0 => t,
                    1 => i,
                    _ => (i - t).abs(),
                });
            }
        }
    }
    Rgb {
        width: 3 * w as u32,
        height: h as u32,
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(v: &[f64]) -> Rgb {
        Rgb {
            width: v.len() as u32,
            height: 1,
            pixels: v.iter().map(|&x| DVec3::splat(x)).collect(),
        }
    }

    #[test]
    fn figures_of_known_images() {
        let a = img(&[1.0, 2.0, 3.0, 4.0]);
        let b = img(&[1.0, 2.0, 3.0, 2.0]);
        assert!((relative_l1(&a, &b, |_| true) - 2.0 / 8.0).abs() < 1e-12);
        assert!((mean_ratio(&a, &b, |i| i < 2) - 1.0).abs() < 1e-12);
        assert!((median_relative_error(&a, &b, |_| true) - 0.0).abs() < 1e-12);
        assert!((median_relative_error(&a, &b, |i| i == 3) - 1.0).abs() < 1e-12);
        assert_eq!(psnr(&a, &a, 1.0, |_| true), f64::INFINITY);
        // Seeds 1 and 3 around a truth of 2: a half-difference of 1 over a
        // mean of 2; identical seeds carry no noise.
        let (s0, s1) = (img(&[1.0, 2.0, 6.0]), img(&[3.0, 2.0, 2.0]));
        assert!((median_seed_noise(&s0, &s1, |_| true) - 0.5).abs() < 1e-12);
        assert_eq!(median_seed_noise(&s0, &s1, |i| i == 1), 0.0);
        assert!((correlation(&[1.0, 2.0, 3.0], &[2.0, 4.0, 6.0], &|_| true) - 1.0).abs() < 1e-12);
        assert!((srgb(1.0) - 1.0).abs() < 1e-6 && srgb(-1.0) == 0.0);
        // The box mean skips masked-out neighbours and keeps a lone pixel.
        let row = img(&[1.0, 3.0, 5.0, 7.0]);
        let boxed = masked_box_mean(&row, 1, |i| i != 2);
        let v: Vec<f64> = boxed.pixels.iter().map(|p| p.x).collect();
        assert_eq!(v, vec![2.0, 2.0, 5.0, 7.0]);
        let b4 = block_means(&img(&[1.0, 3.0, 5.0, 7.0]), 2, |_| true);
        assert_eq!(b4.pixels, vec![DVec3::ZERO; 0]);
        let wide = Rgb {
            width: 2,
            height: 2,
            pixels: [1.0, 3.0, 5.0, 7.0]
                .iter()
                .map(|&v| DVec3::splat(v))
                .collect(),
        };
        assert_eq!(
            block_means(&wide, 2, |_| true).pixels,
            vec![DVec3::splat(4.0)]
        );
        assert_eq!(block_means(&wide, 2, |i| i != 3).pixels, vec![DVec3::ZERO]);
    }

    #[test]
    fn shadow_figures_of_a_known_shadow() {
        let truth = [1.0, 0.4, 0.8, 1.0, 1.0, 0.3];
        let inlay = [1.0, 0.6, 0.8, 0.98, 1.0, 0.3];
        // Pixel 5 is the object; pixels 3 and 4 are far.
        let f = shadow_figures(&inlay, &truth, |i| i != 5, |i| i == 3 || i == 4);
        assert_eq!(f.truth_area, 2);
        assert!((f.area_ratio - 1.0).abs() < 1e-12);
        assert!((f.far_darkening - 0.01).abs() < 1e-12);
        assert!(f.truth_far_darkening.abs() < 1e-12);
        assert_eq!(f.far_pixels, 2);
        assert!(f.correlation > 0.9);
        // The umbra is pixel 1 alone (pixel 5 is not the field's).
        assert_eq!(f.umbra_pixels, 1);
        assert!((f.truth_umbra - 0.4).abs() < 1e-12 && (f.umbra - 0.6).abs() < 1e-12);
        // The total darkening over the pixels either darkens below 0.97
        // (1, 2; pixel 3 stays above it in both): 0.6 against 0.8.
        assert!((f.darkening_ratio - 0.75).abs() < 1e-12);
    }

    #[test]
    fn a_plateau_at_the_threshold_shows_in_the_neighbouring_areas() {
        // Both pixels of a broad edge near 0.9, inlay 0.04 darker on one.
        let (truth, inlay) = ([0.88, 0.92, 1.0], [0.88, 0.88, 1.0]);
        let f = shadow_figures(&inlay, &truth, |_| true, |_| false);
        assert_eq!(AREA_THRESHOLDS, [0.8, 0.85, 0.9, 0.95]);
        assert_eq!(f.area_ratios, [0.0, 0.0, 2.0, 1.0]);
        assert_eq!(f.area_ratio, f.area_ratios[2]);
        assert!((f.darkening_ratio - 1.2).abs() < 1e-12);
    }
}

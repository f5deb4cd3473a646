//! The no-reference quality score that rejects poor views before surface
//! points are drawn from them.
//!
//! The paper rejects views whose BRISQUE score exceeds 50. BRISQUE's score
//! comes from a support-vector regressor trained on the LIVE database;
//! that trained model is not bundled here, so this is a documented score
//! on the same 0 (best) to 100 (worst) scale, rejecting at the same 50,
//! built from what makes a radiance-field render a poor source of surface
//! points: it is the worst of three parts, each 0..100.
//! - **Empty**: few pixels whose ray ends in the field (Ô ≥ 0.5):
//!   100·(1 − coverage/0.5), so a view under 25 % covered is rejected.
//! - **Flat or blurred**: little local structure. The render is tone
//!   mapped (exposure setting the covered pixels' mean luminance to 0.18,
//!   ACES, sRGB, 8 bits) and, as in BRISQUE's MSCN step, the local standard
//!   deviation is taken over a 7 × 7 Gaussian window (σ = 7/6); a pixel is
//!   structured when it exceeds 2 grey levels. 100·(1 − structured/0.1):
//!   under 5 % structured pixels (a uniform wall filling the view, the
//!   inside of a solid, a defocused render) is rejected.
//! - **Near clutter** (floaters, a camera inside matter): covered pixels
//!   whose expected depth is under a tenth of the view's distance to the
//!   field's centre, 100·near/0.5, so over 25 % of such pixels is rejected.

use inlay_engine::tonemap::tonemap_to_srgb8;

/// A view rendered by the ray march: per pixel (Ĉ, Ô) and D̂.
#[derive(Debug, Clone)]
pub struct ViewImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Premultiplied colour Ĉ and opacity Ô, row-major from the top.
    pub colour_opacity: Vec<[f32; 4]>,
    /// Opacity-weighted depth D̂ (the expected depth is D̂/Ô).
    pub depth: Vec<f32>,
}

/// A view's score and its parts (each 0 best .. 100 worst).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QualityScore {
    /// The score: the worst part.
    pub score: f64,
    /// Part for too few covered pixels.
    pub empty: f64,
    /// Part for too little local structure.
    pub flat: f64,
    /// Part for matter right in front of the camera.
    pub near: f64,
}

/// Coverage at which the empty part reaches 0.
const COVERAGE_FULL: f64 = 0.5;
/// Fraction of structured pixels at which the flat part reaches 0.
const STRUCTURE_FULL: f64 = 0.1;
/// Local standard deviation (8-bit grey levels) that counts as structure.
const STRUCTURE_LEVELS: f64 = 2.0;
/// Expected depth, as a fraction of the view distance, that counts as near.
const NEAR_FRACTION: f64 = 0.1;
/// Fraction of near pixels at which the near part reaches 100.
const NEAR_FULL: f64 = 0.5;

fn luminance(c: [f64; 3]) -> f64 {
    crate::sgfit::model::luminance(glam::DVec3::from_array(c))
}

/// The score of `view`, taken `distance` from the point it looks at.
pub fn view_quality(view: &ViewImage, distance: f64) -> QualityScore {
    let n = view.colour_opacity.len().max(1);
    let covered: Vec<bool> = view.colour_opacity.iter().map(|p| p[3] >= 0.5).collect();
    let coverage = covered.iter().filter(|c| **c).count() as f64 / n as f64;
    let near = view
        .colour_opacity
        .iter()
        .zip(&view.depth)
        .filter(|(p, d)| p[3] >= 0.5 && ((**d / p[3]) as f64) < NEAR_FRACTION * distance)
        .count() as f64
        / n as f64;
    let structured = structured_fraction(view, &covered);
    let part = |x: f64| (100.0 * x).clamp(0.0, 100.0);
    let empty = part(1.0 - coverage / COVERAGE_FULL);
    let flat = part(1.0 - structured / STRUCTURE_FULL);
    let near = part(near / NEAR_FULL);
    QualityScore {
        score: empty.max(flat).max(near),
        empty,
        flat,
        near,
    }
}

/// The fraction of pixels whose 7 × 7 Gaussian-weighted grey-level standard
/// deviation exceeds [`STRUCTURE_LEVELS`].
fn structured_fraction(view: &ViewImage, covered: &[bool]) -> f64 {
    let (w, h) = (view.width as usize, view.height as usize);
    let lum: Vec<f64> = view
        .colour_opacity
        .iter()
        .map(|p| luminance([p[0] as f64, p[1] as f64, p[2] as f64]))
        .collect();
    let count = covered.iter().filter(|c| **c).count();
    let mean = if count == 0 {
        0.0
    } else {
        lum.iter()
            .zip(covered)
            .filter(|(_, c)| **c)
            .map(|(l, _)| l)
            .sum::<f64>()
            / count as f64
    };
    let exposure = if mean > 1e-12 { 0.18 / mean } else { 1.0 };
    let grey: Vec<f64> = view
        .colour_opacity
        .iter()
        .map(|p| {
            let c = tonemap_to_srgb8([p[0], p[1], p[2]], exposure as f32);
            luminance([c[0] as f64, c[1] as f64, c[2] as f64])
        })
        .collect();
    let sigma = 7.0 / 6.0;
    let kernel: Vec<f64> = (-3..=3)
        .map(|i: i32| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let ksum: f64 = kernel.iter().sum();
    let kernel: Vec<f64> = kernel.iter().map(|k| k / ksum).collect();
    let blur = |img: &[f64]| -> Vec<f64> {
        let mut tmp = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                tmp[y * w + x] = (0..7)
                    .map(|k| {
                        let xs = (x as i64 + k as i64 - 3).clamp(0, w as i64 - 1) as usize;
                        kernel[k] * img[y * w + xs]
                    })
                    .sum();
            }
        }
        let mut out = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                out[y * w + x] = (0..7)
                    .map(|k| {
                        let ys = (y as i64 + k as i64 - 3).clamp(0, h as i64 - 1) as usize;
                        kernel[k] * tmp[ys * w + x]
                    })
                    .sum();
            }
        }
        out
    };
    let mu = blur(&grey);
    let sq: Vec<f64> = grey.iter().map(|g| g * g).collect();
    let mu2 = blur(&sq);
    let structured = mu
        .iter()
        .zip(&mu2)
        .filter(|(m, m2)| (**m2 - **m * **m).max(0.0).sqrt() > STRUCTURE_LEVELS)
        .count();
    structured as f64 / (w * h).max(1) as f64
}

//! How far a trained field's surfaces spread along the rays that see them:
//! the one sign of uncertain depth that needs no known scene. Where the
//! photographs pin a surface (a texture seen from several sides, an edge)
//! its rendering weight gathers within a node spacing or two; where they
//! cannot (a plain floor, whose colour a translucent sheet in front of it
//! reproduces from every side) the weight spreads over many spacings and
//! the expected depth lies anywhere within the spread. Measured against the
//! recipes on 40 held-out views, the pixels whose weight spreads over
//! [`WIDE_SPREAD`] spacings or more stood a median 3.3–10.4 spacings off
//! (PLANTS' foliage, a medium that spreads by nature, 2.0–2.4), the
//! others 0.1–1.9 (docs/benchmarks.md, issue 25's forty-third pass).

use rayon::prelude::*;

use super::geometry::SURFACE_OPACITY;
use super::lattice::{lattice_stride, Lattice};
use super::pixels::pixel_ray;
use crate::dataset::{Frame, PixelState};
use crate::field::RadianceField;
use crate::geometry::Ray;
use crate::march::{march_samples, MarchKnobs, MarchSample};

/// Standard deviation of a ray's depth, in node spacings, from which the
/// field's surface along it counts as spread: its expected depth uncertain
/// by more than the depth target's one spacing several times over.
pub const WIDE_SPREAD: f64 = 4.0;

/// Share of a view's surface pixels spread over [`WIDE_SPREAD`] or more
/// from which `inlay train` warns that the photographs leave the depth
/// open: of the 40 measured views, 12 of the 14 at or above it missed the
/// depth target of one spacing, 7 of the 26 below it (a compact wrong
/// surface does not spread).
pub const WIDE_SHARE_WARNING: f64 = 0.1;

/// How a ray's rendering weight lies along it ([`ray_weights`]), in the
/// ray's units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayWeights {
    /// Σ wᵢ: the field's opacity along the ray.
    pub opacity: f64,
    /// The expected depth Σ wᵢtᵢ / Σ wᵢ.
    pub mean: f64,
    /// The weighted standard deviation of the depth, √(Σ wᵢ(tᵢ − t̄)² /
    /// Σ wᵢ).
    pub spread: f64,
    /// The depth by which the ray has gathered the tail's share of its
    /// weight.
    pub front: f64,
    /// The depth by which it has gathered all but the tail's share.
    pub back: f64,
}

/// The samples of the march's quadrature along `ray` (unit direction)
/// through `field` that carry weight ([`march_samples`]), in order.
pub fn weighted_samples(
    field: &dyn RadianceField,
    ray: &Ray,
    march: &MarchKnobs,
) -> Vec<MarchSample> {
    let mut samples = Vec::new();
    march_samples(field, ray, f64::INFINITY, march, |s| {
        if s.weight > 0.0 {
            samples.push(*s);
        }
    });
    samples
}

impl RayWeights {
    /// How the weight of a ray's `samples` ([`weighted_samples`]) lies
    /// along it, each sample's weight at its midpoint (as the expected
    /// depth is read), with `tail` the share of the weight
    /// [`RayWeights::front`] and [`RayWeights::back`] leave out at each
    /// end; None where the ray gathers less than [`SURFACE_OPACITY`] (no
    /// surface to place). The moments are summed as offsets from the first
    /// sample's depth, so that a far surface loses no precision to t².
    pub fn of(samples: &[MarchSample], tail: f64) -> Option<RayWeights> {
        let origin = samples.first()?.t;
        let (mut w0, mut w1, mut w2) = (0.0, 0.0, 0.0);
        for s in samples {
            let d = s.t - origin;
            w0 += s.weight;
            w1 += s.weight * d;
            w2 += s.weight * d * d;
        }
        if w0 < SURFACE_OPACITY {
            return None;
        }
        let mean = w1 / w0;
        let at_share = |share: f64| {
            let mut gathered = 0.0;
            samples
                .iter()
                .find(|s| {
                    gathered += s.weight;
                    gathered >= share * w0
                })
                .map_or(samples[samples.len() - 1].t, |s| s.t)
        };
        Some(RayWeights {
            opacity: w0,
            mean: origin + mean,
            spread: (w2 / w0 - mean * mean).max(0.0).sqrt(),
            front: at_share(tail),
            back: at_share(1.0 - tail),
        })
    }
}

/// How the weight of `ray` (unit direction) through `field` lies along it
/// ([`RayWeights::of`] its [`weighted_samples`]).
pub fn ray_weights(
    field: &dyn RadianceField,
    ray: &Ray,
    march: &MarchKnobs,
    tail: f64,
) -> Option<RayWeights> {
    RayWeights::of(&weighted_samples(field, ray, march), tail)
}

/// The weighted standard deviation of the depth along `ray` (unit
/// direction) through `field` ([`RayWeights::spread`]), in the ray's
/// units; None where the ray gathers less than [`SURFACE_OPACITY`].
pub fn depth_spread(field: &dyn RadianceField, ray: &Ray, march: &MarchKnobs) -> Option<f64> {
    ray_weights(field, ray, march, 0.0).map(|w| w.spread)
}

/// One view's surfaces' spread ([`surface_spread`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SurfaceSpread {
    /// Every `stride`-th pixel of every `stride`-th row was read.
    pub stride: u32,
    /// The lattice of pixels read: its width and height.
    pub size: (u32, u32),
    /// Each pixel read's spread in node spacings, row by row; NaN where
    /// it is masked or the field holds no surface along it.
    pub spreads: Vec<f32>,
}

impl SurfaceSpread {
    /// Pixels read whose ray the field makes opaque (at least
    /// [`SURFACE_OPACITY`]).
    pub fn surfaces(&self) -> usize {
        self.spreads.iter().filter(|s| !s.is_nan()).count()
    }

    /// Of those, the pixels whose depth spreads over [`WIDE_SPREAD`] node
    /// spacings or more.
    pub fn wide(&self) -> usize {
        self.spreads
            .iter()
            .filter(|&&s| s as f64 >= WIDE_SPREAD)
            .count()
    }

    /// The share of the surface pixels that spread wide (0 where there are
    /// none).
    pub fn wide_share(&self) -> f64 {
        match self.surfaces() {
            0 => 0.0,
            n => self.wide() as f64 / n as f64,
        }
    }
}

/// Pixels a view's spread reads at most: a photograph of more is read on
/// every n-th pixel of every n-th row, n the least that keeps it under
/// (a share, which so many pixels read to within half a percent).
pub const SPREAD_PIXELS: u64 = 1 << 16;

/// How far `field`'s surfaces spread along the rays through the centres of
/// `frame`'s usable pixels ([`depth_spread`], in the field's smallest node
/// spacing).
pub fn surface_spread(
    frame: &Frame,
    field: &crate::field::GridField,
    march: &MarchKnobs,
) -> SurfaceSpread {
    let (w, h) = (frame.intrinsics.width, frame.intrinsics.height);
    let lattice = Lattice::new(w, h, lattice_stride(w as u64 * h as u64, SPREAD_PIXELS));
    let spacing = field.spacing().min_element();
    let spreads: Vec<f32> = (0..lattice.len())
        .into_par_iter()
        .map(|i| {
            let p = lattice.pixel(i);
            if frame.image.state[p as usize] == PixelState::Masked {
                return f32::NAN;
            }
            pixel_ray(frame, p)
                .and_then(|ray| depth_spread(field, &ray, march))
                .map_or(f32::NAN, |s| (s / spacing) as f32)
        })
        .collect();
    SurfaceSpread {
        stride: lattice.stride,
        size: (lattice.columns(), lattice.rows()),
        spreads,
    }
}

/// A pixel's spread as a colour (linear RGB in [0, 1]): white where the
/// surface gathers at a point, darkening to orange at [`WIDE_SPREAD`]
/// node spacings and beyond; black where there is no surface (NaN).
pub fn spread_colour(spread: f32) -> [f32; 3] {
    if spread.is_nan() {
        return [0.0; 3];
    }
    let t = (spread as f64 / WIDE_SPREAD).clamp(0.0, 1.0) as f32;
    let orange = [1.0, 0.35, 0.0];
    [0, 1, 2].map(|c| 1.0 + t * (orange[c] - 1.0))
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, UVec3};

    use super::*;
    use crate::field::{GridField, DEFAULT_OCCUPANCY_BLOCK};
    use crate::geometry::Aabb;
    use crate::train::geometry::tests::{foggy_slab, frame, march, slab};

    /// A medium of density σ everywhere in [0, 1]³.
    fn medium(sigma: f32) -> GridField {
        let nodes = vec![[0.5, 0.5, 0.5, sigma]; 64];
        let bounds = Aabb::new(DVec3::ZERO, DVec3::ONE);
        GridField::new(UVec3::splat(4), bounds, nodes, DEFAULT_OCCUPANCY_BLOCK)
    }

    /// 4096 samples along the diagonal, none skipped, no early stop.
    fn fine_march() -> MarchKnobs {
        MarchKnobs {
            samples_per_ray: 4096,
            termination: 0.0,
            skip_empty: false,
        }
    }

    /// A ray along x through the middle of [`medium`]'s box, entering it
    /// at t = 1.
    fn across_the_medium() -> Ray {
        Ray {
            origin: DVec3::new(-1.0, 0.5, 0.5),
            dir: DVec3::X,
        }
    }

    /// Along a ray through a homogeneous medium of density σ the weight
    /// falls as σe^{−σt}, whose standard deviation is the mean free path
    /// 1/σ (the unit box cuts off e^{−40} of it at σ = 40). The march's
    /// samples of width h read it as 1/(2 sinh(σh/2)), within (σh)²/24 of
    /// it: 1.2·10⁻⁵ at 4096 samples. A medium too thin to hide half the
    /// light holds no surface.
    #[test]
    fn a_homogeneous_medium_spreads_by_its_mean_free_path() {
        let (knobs, ray) = (fine_march(), across_the_medium());
        for sigma in [10.0, 40.0] {
            let spread = depth_spread(&medium(sigma), &ray, &knobs).unwrap();
            let exact = 1.0 / sigma as f64;
            let truncated = (exact * exact
                - (-(sigma as f64)).exp() / (1.0 - (-(sigma as f64)).exp()).powi(2))
            .sqrt();
            assert!(
                (spread / truncated - 1.0).abs() < 1e-4,
                "σ {sigma}: {spread} against {truncated}"
            );
        }
        assert_eq!(depth_spread(&medium(0.5), &ray, &knobs), None);
    }

    /// In the same medium the weight's share gathered by depth t is
    /// (1 − e^{−σt}) / (1 − e^{−σ}) over the unit box, so the depth that
    /// gathers share q is −ln(1 − q(1 − e^{−σ}))/σ, and the expected depth
    /// 1/σ − e^{−σ}/(1 − e^{−σ}). The front and back are read at a
    /// sample's midpoint: within a sample's width (1/4096) of those.
    #[test]
    fn a_homogeneous_medium_gathers_its_weight_where_the_closed_form_says() {
        let (knobs, ray) = (fine_march(), across_the_medium());
        let sigma = 10.0f64;
        let kept = 1.0 - (-sigma).exp();
        let at = |q: f64| 1.0 - (1.0 - q * kept).ln() / sigma;
        let w = ray_weights(&medium(sigma as f32), &ray, &knobs, 0.05).unwrap();
        let mean = 1.0 + 1.0 / sigma - (-sigma).exp() / kept;
        assert!((w.mean - mean).abs() < 1e-4, "{w:?} against {mean}");
        assert!((w.opacity - kept).abs() < 1e-6, "{w:?}");
        for (got, q) in [(w.front, 0.05), (w.back, 0.95)] {
            assert!(
                (got - at(q)).abs() <= 1.0 / 4096.0,
                "{w:?}: {q} at {}",
                at(q)
            );
        }
    }

    /// Seen from above, a bare opaque floor gathers each ray's weight
    /// within a spacing; a fog of optical depth 1 a unit over it spreads
    /// every ray's; a faint one (0.05 a unit, 7 % of the light) too little
    /// to count. Masked pixels are not read, and a photograph of more than
    /// [`SPREAD_PIXELS`] is read on a coarser lattice.
    #[test]
    fn a_floor_under_a_fog_spreads_wide_and_a_bare_one_does_not() {
        let f = frame();
        // (The corner pixels' rays leave through the bounds' sides above
        // the floor: through the fog alone where there is one.)
        let bare = surface_spread(&f, &slab(-0.5), &march());
        assert!(bare.surfaces() > 800, "{bare:?}");
        assert_eq!((bare.wide(), bare.stride), (0, 1));
        let fog = surface_spread(&f, &foggy_slab(-0.5, 1.0), &march());
        assert!(fog.surfaces() >= bare.surfaces(), "{fog:?}");
        assert!(fog.wide_share() > 0.95, "{fog:?}");
        let faint = surface_spread(&f, &foggy_slab(-0.5, 0.05), &march());
        assert_eq!(faint.wide(), 0, "{faint:?}");
        // The 8 × 8 pixels at the centre, all on the floor, masked.
        let mut masked = frame();
        for y in 12..20 {
            masked.image.state[y * 32 + 12..y * 32 + 20].fill(PixelState::Masked);
        }
        let without = surface_spread(&masked, &slab(-0.5), &march());
        assert_eq!(without.surfaces(), bare.surfaces() - 64);
        let mut large = frame();
        let (w, h) = (300u32, 300u32);
        large.intrinsics = crate::dataset::Intrinsics::centred(w, h, 40.0);
        large.image.width = w;
        large.image.height = h;
        large.image.radiance = vec![[0.5; 3]; (w * h) as usize];
        large.image.state = vec![PixelState::Value; (w * h) as usize];
        let coarse = surface_spread(&large, &slab(-0.5), &march());
        assert_eq!((coarse.stride, coarse.wide()), (2, 0));
        let share = coarse.surfaces() as f64 / (150.0 * 150.0);
        let whole = bare.surfaces() as f64 / 1024.0;
        assert!((share - whole).abs() < 0.02, "{share} against {whole}");
        assert_eq!(coarse.size, (150, 150));
        assert_eq!(coarse.spreads.len(), 150 * 150);
        // Each pixel's spread: NaN off the surfaces and on masked pixels.
        assert_eq!((bare.size, bare.spreads.len()), ((32, 32), 1024));
        assert!(without.spreads[16 * 32 + 16].is_nan());
        assert!(!bare.spreads[16 * 32 + 16].is_nan());
        assert!(bare.spreads.iter().all(|&v| v.is_nan() || v < 1.0));
        assert_eq!(SurfaceSpread::default().wide_share(), 0.0);
    }

    /// White at a point, orange from [`WIDE_SPREAD`] on, black where no
    /// surface is.
    #[test]
    fn a_spread_is_drawn_white_to_orange() {
        assert_eq!(spread_colour(f32::NAN), [0.0; 3]);
        assert_eq!(spread_colour(0.0), [1.0; 3]);
        let near = |a: [f32; 3], b: [f32; 3]| (0..3).all(|c| (a[c] - b[c]).abs() < 1e-6);
        assert!(near(spread_colour(WIDE_SPREAD as f32), [1.0, 0.35, 0.0]));
        assert!(near(spread_colour(40.0), [1.0, 0.35, 0.0]));
        let half = spread_colour(0.5 * WIDE_SPREAD as f32);
        assert!(near(half, [1.0, 0.675, 0.5]), "{half:?}");
    }
}

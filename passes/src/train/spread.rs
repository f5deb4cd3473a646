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
use super::pixels::pixel_ray;
use crate::dataset::{Frame, PixelState};
use crate::field::RadianceField;
use crate::geometry::Ray;
use crate::march::{march_samples, MarchKnobs};

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

/// The weighted standard deviation of the depth along `ray` (unit
/// direction) through `field`, √(Σ wᵢ(tᵢ − t̄)² / Σ wᵢ) over the march's
/// samples ([`march_samples`]: each sample's weight at its midpoint, as
/// the expected depth is read), in the ray's units; None where the ray
/// gathers less than [`SURFACE_OPACITY`] (no surface to place). Summed as
/// offsets from the first weighted sample's depth, so that a far surface
/// loses no precision to t².
pub fn depth_spread(field: &dyn RadianceField, ray: &Ray, march: &MarchKnobs) -> Option<f64> {
    let (mut origin, mut w0, mut w1, mut w2) = (None, 0.0, 0.0, 0.0);
    march_samples(field, ray, f64::INFINITY, march, |s| {
        if s.weight <= 0.0 {
            return;
        }
        let d = s.t - *origin.get_or_insert(s.t);
        w0 += s.weight;
        w1 += s.weight * d;
        w2 += s.weight * d * d;
    });
    if w0 < SURFACE_OPACITY {
        return None;
    }
    let mean = w1 / w0;
    Some((w2 / w0 - mean * mean).max(0.0).sqrt())
}

/// One view's surfaces' spread ([`surface_spread`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SurfaceSpread {
    /// Pixels read whose ray the field makes opaque (at least
    /// [`SURFACE_OPACITY`]).
    pub surfaces: usize,
    /// Of those, the pixels whose depth spreads over [`WIDE_SPREAD`] node
    /// spacings or more.
    pub wide: usize,
    /// Every `stride`-th pixel of every `stride`-th row was read.
    pub stride: u32,
}

impl SurfaceSpread {
    /// The share of the surface pixels that spread wide (0 where there are
    /// none).
    pub fn wide_share(&self) -> f64 {
        if self.surfaces == 0 {
            0.0
        } else {
            self.wide as f64 / self.surfaces as f64
        }
    }
}

/// Pixels a view's spread reads at most: a photograph of more is read on
/// every n-th pixel of every n-th row, n the least that keeps it under
/// (a share, which so many pixels read to within half a percent).
pub const SPREAD_PIXELS: u32 = 1 << 16;

/// How far `field`'s surfaces spread along the rays through the centres of
/// `frame`'s usable pixels ([`depth_spread`], in the field's smallest node
/// spacing).
pub fn surface_spread(
    frame: &Frame,
    field: &crate::field::GridField,
    march: &MarchKnobs,
) -> SurfaceSpread {
    let (w, h) = (frame.intrinsics.width, frame.intrinsics.height);
    let stride = (((w as f64 * h as f64) / SPREAD_PIXELS as f64).sqrt().ceil() as u32).max(1);
    let spacing = field.spacing().min_element();
    let pixels: Vec<u32> = (0..h)
        .step_by(stride as usize)
        .flat_map(|y| (0..w).step_by(stride as usize).map(move |x| y * w + x))
        .filter(|&p| frame.image.state[p as usize] != PixelState::Masked)
        .collect();
    let spreads: Vec<f64> = pixels
        .into_par_iter()
        .filter_map(|p| depth_spread(field, &pixel_ray(frame, p)?, march))
        .collect();
    SurfaceSpread {
        surfaces: spreads.len(),
        wide: spreads
            .iter()
            .filter(|&&s| s >= WIDE_SPREAD * spacing)
            .count(),
        stride,
    }
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

    /// Along a ray through a homogeneous medium of density σ the weight
    /// falls as σe^{−σt}, whose standard deviation is the mean free path
    /// 1/σ (the unit box cuts off e^{−40} of it at σ = 40). The march's
    /// samples of width h read it as 1/(2 sinh(σh/2)), within (σh)²/24 of
    /// it: 1.2·10⁻⁵ at 4096 samples. A medium too thin to hide half the
    /// light holds no surface.
    #[test]
    fn a_homogeneous_medium_spreads_by_its_mean_free_path() {
        let knobs = MarchKnobs {
            samples_per_ray: 4096,
            termination: 0.0,
            skip_empty: false,
        };
        let ray = Ray {
            origin: DVec3::new(-1.0, 0.5, 0.5),
            dir: DVec3::X,
        };
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
        assert!(bare.surfaces > 800, "{bare:?}");
        assert_eq!((bare.wide, bare.stride), (0, 1));
        let fog = surface_spread(&f, &foggy_slab(-0.5, 1.0), &march());
        assert!(fog.surfaces >= bare.surfaces, "{fog:?}");
        assert!(fog.wide_share() > 0.95, "{fog:?}");
        let faint = surface_spread(&f, &foggy_slab(-0.5, 0.05), &march());
        assert_eq!(faint.wide, 0, "{faint:?}");
        // The 8 × 8 pixels at the centre, all on the floor, masked.
        let mut masked = frame();
        for y in 12..20 {
            masked.image.state[y * 32 + 12..y * 32 + 20].fill(PixelState::Masked);
        }
        let without = surface_spread(&masked, &slab(-0.5), &march());
        assert_eq!(without.surfaces, bare.surfaces - 64);
        let mut large = frame();
        let (w, h) = (300u32, 300u32);
        large.intrinsics = crate::dataset::Intrinsics::centred(w, h, 40.0);
        large.image.width = w;
        large.image.height = h;
        large.image.radiance = vec![[0.5; 3]; (w * h) as usize];
        large.image.state = vec![PixelState::Value; (w * h) as usize];
        let coarse = surface_spread(&large, &slab(-0.5), &march());
        assert_eq!((coarse.stride, coarse.wide), (2, 0));
        let share = coarse.surfaces as f64 / (150.0 * 150.0);
        let whole = bare.surfaces as f64 / 1024.0;
        assert!((share - whole).abs() < 0.02, "{share} against {whole}");
        assert_eq!(SurfaceSpread::default().wide_share(), 0.0);
    }
}

//! A trained field's geometry in a view, scored against known surfaces
//! (a recipe's, for a dataset `render-views` made): at each pixel the
//! field's expected depth D̂/Ô against the first surface along the ray
//! inside the field's bounds, and the opacity the field gathers well in
//! front of that surface (haze). A floor that floats or that the camera
//! sees through, or a room full of haze, spoils occlusion, probes,
//! shadows and the environment estimate even where the held-out views'
//! PSNR is good, and the PSNR cannot tell.

use glam::DVec3;

use crate::dataset::{Frame, PixelState};
use crate::field::GridField;
use crate::geometry::{ray_box, Ray};
use crate::march::{march_ray, MarchKnobs};

use super::pixels::pixel_ray;

/// Opacity from which a pixel counts as showing a surface of the field
/// (its expected depth then lies on what hides the rest).
pub const SURFACE_OPACITY: f64 = 0.5;

/// Node spacings in front of a known surface from which the field's
/// opacity counts as haze ([`GeometryScore::haze`]): a trained surface's
/// own blur and offset are not haze. ROOM trained from its open side put
/// its surfaces a median 2–4 spacings in front of the recipe's, its
/// surface pixels' weight spread over 7 or more, and with a margin of 3
/// nearly half their light counted as haze where the free space was all
/// but clear (44–51 %, on a field trained as at the defaults with an
/// opacity prior too weak to change its figures). With 8, that field (0.3 per metre of free space) hides
/// 16–24 %, those whose free space reads 1.25–3.1 per metre 33–52 %
/// (docs/fidelity.md, "Thirty-second pass").
pub const HAZE_MARGIN: f64 = 8.0;

/// One view's geometry against the known surfaces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeometryScore {
    /// Pixels where a known surface lies inside the field's bounds and the
    /// field is opaque (Ô ≥ [`SURFACE_OPACITY`]): the depths compared.
    pub compared: usize,
    /// Median |D̂/Ô − t_surface| over them, in the field's node spacings
    /// (its smallest); NaN where none was compared.
    pub median_error: f64,
    /// Median of the signed D̂/Ô − t_surface over the same pixels, in node
    /// spacings: negative where the field's surfaces lie in front of the
    /// known ones (NaN where none was compared).
    pub median_signed_error: f64,
    /// Median over the same pixels of |D̂/Ô − t_surface|·|d·n| (d the
    /// ray's unit direction, n the known surface's normal where the ray
    /// meets it), in node spacings: how far the field's depth lies from
    /// the known surface's tangent plane. A ray meeting a floor at 16° of
    /// elevation reads an offset δ along its normal as δ / sin 16° ≈ 3.6δ
    /// of depth; this reads δ (NaN where none was compared).
    pub median_normal_offset: f64,
    /// Share of the pixels with a known surface inside the bounds where
    /// the field is not opaque: the camera sees through it (NaN: no such
    /// pixel).
    pub see_through: f64,
    /// Share of the pixels with no known surface inside the bounds where
    /// the field is opaque: floaters (NaN: no such pixel).
    pub floating: f64,
    /// Mean opacity the field gathers before [`HAZE_MARGIN`] node spacings
    /// in front of the known surface, over the pixels with one: the share
    /// of the surface's light that haze in the room hides from the camera
    /// (and from any point the estimate reads light at). 0 on a clean
    /// field; NaN where no pixel has a known surface.
    pub haze: f64,
}

/// The first known surface along a ray within (t_min, t_max): its
/// distance and its unit normal there, None where there is none.
pub type KnownSurface<'a> = dyn Fn(&Ray, f64, f64) -> Option<(f64, DVec3)> + Sync + 'a;

/// Scores `field`'s geometry in `frame`'s usable pixels: `surface(ray,
/// t_min, t_max)` gives the distance to the first known surface along the
/// ray within (t_min, t_max) and the surface's unit normal there, None
/// where there is none.
pub fn geometry_score(
    frame: &Frame,
    field: &GridField,
    march: &MarchKnobs,
    surface: &KnownSurface<'_>,
) -> GeometryScore {
    use rayon::prelude::*;
    let spacing = field.spacing().min_element();
    let (w, h) = (frame.intrinsics.width, frame.intrinsics.height);
    // Per pixel: (a known surface, the field opaque, signed depth error,
    // the opacity in front of the known surface, |d·n| there).
    let pixels: Vec<(bool, bool, f64, f64, f64)> = (0..w * h)
        .into_par_iter()
        .filter(|&p| frame.image.state[p as usize] != PixelState::Masked)
        .filter_map(|p| {
            let ray = pixel_ray(frame, p)?;
            let (t0, t1) = ray_box(&ray, &field.bounds)?;
            let known = surface(&ray, t0.max(0.0), t1);
            let m = march_ray(field, &ray, f64::INFINITY, march);
            let opaque = m.opacity >= SURFACE_OPACITY;
            let error = match known {
                Some((t, _)) if opaque => (m.depth / m.opacity - t) / spacing,
                _ => f64::NAN,
            };
            let facing = known.map_or(f64::NAN, |(_, n)| (ray.dir.dot(n) / ray.dir.length()).abs());
            let haze = known.map_or(f64::NAN, |(t, _)| {
                let front = t - HAZE_MARGIN * spacing;
                if front <= t0 {
                    0.0
                } else {
                    march_ray(field, &ray, front, march).opacity
                }
            });
            Some((known.is_some(), opaque, error, haze, facing))
        })
        .collect();
    let mut signed: Vec<f64> = pixels.iter().map(|p| p.2).filter(|e| !e.is_nan()).collect();
    let mut errors: Vec<f64> = signed.iter().map(|e| e.abs()).collect();
    let mut offsets: Vec<f64> = pixels
        .iter()
        .filter(|p| !p.2.is_nan())
        .map(|p| (p.2 * p.4).abs())
        .collect();
    errors.sort_by(f64::total_cmp);
    signed.sort_by(f64::total_cmp);
    offsets.sort_by(f64::total_cmp);
    type Pixel = (bool, bool, f64, f64, f64);
    let share = |of: &dyn Fn(&Pixel) -> bool, among: &dyn Fn(&Pixel) -> bool| {
        let n = pixels.iter().filter(|p| among(p)).count();
        let k = pixels.iter().filter(|p| among(p) && of(p)).count();
        if n == 0 {
            f64::NAN
        } else {
            k as f64 / n as f64
        }
    };
    GeometryScore {
        compared: errors.len(),
        median_error: median(&errors),
        median_signed_error: median(&signed),
        median_normal_offset: median(&offsets),
        see_through: share(&|p| !p.1, &|p| p.0),
        floating: share(&|p| p.1, &|p| !p.0),
        haze: mean(pixels.iter().map(|p| p.3).filter(|o| !o.is_nan())),
    }
}

/// The mean of `v` (NaN when empty).
fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    if n == 0 {
        f64::NAN
    } else {
        sum / n as f64
    }
}

/// The median of sorted `v` (NaN when empty).
fn median(v: &[f64]) -> f64 {
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, UVec3};

    use super::*;
    use crate::dataset::pixels::{FrameImage, PixelCounts};
    use crate::dataset::{Intrinsics, Pose};
    use crate::field::DEFAULT_OCCUPANCY_BLOCK;
    use crate::geometry::Aabb;

    /// A 24³ field over [−1, 1]³ opaque below `floor` (density 400 a unit),
    /// empty above.
    fn slab(floor: f64) -> GridField {
        foggy_slab(floor, 0.0)
    }

    /// [`slab`] with density `fog` a unit above `floor`.
    fn foggy_slab(floor: f64, fog: f32) -> GridField {
        let n = 24u32;
        let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        let h = 2.0 / (n - 1) as f64;
        let mut nodes = Vec::new();
        for _z in 0..n {
            for y in 0..n {
                for _x in 0..n {
                    let sigma = if -1.0 + y as f64 * h <= floor {
                        400.0
                    } else {
                        fog
                    };
                    nodes.push([0.5, 0.5, 0.5, sigma]);
                }
            }
        }
        GridField::new(UVec3::splat(n), bounds, nodes, DEFAULT_OCCUPANCY_BLOCK)
    }

    /// A camera above the field looking down at its centre, 32² pixels.
    fn frame() -> Frame {
        let (w, h) = (32, 32);
        Frame {
            index: 0,
            image_path: "view.exr".into(),
            pose: Pose::looking_at(DVec3::new(0.3, 2.5, 0.2), DVec3::ZERO, DVec3::Z),
            intrinsics: Intrinsics::centred(w, h, 40.0),
            exposure_time: None,
            exif_exposure: None,
            image: FrameImage {
                width: w,
                height: h,
                radiance: vec![[0.5; 3]; (w * h) as usize],
                state: vec![PixelState::Value; (w * h) as usize],
                alpha: Vec::new(),
                counts: PixelCounts::default(),
            },
        }
    }

    /// The plane y = `y` as the known surface.
    fn plane(y: f64) -> impl Fn(&Ray, f64, f64) -> Option<(f64, DVec3)> + Sync {
        move |ray: &Ray, t0: f64, t1: f64| {
            let t = (y - ray.origin.y) / ray.dir.y;
            (t > t0 && t < t1).then_some((t, DVec3::Y))
        }
    }

    fn march() -> MarchKnobs {
        MarchKnobs {
            samples_per_ray: 512,
            termination: 1e-4,
            skip_empty: false,
        }
    }

    /// The slab's density falls from its last opaque nodes to zero over a
    /// node spacing: a plane half way is within half a spacing of the
    /// field's depth, one two spacings lower about two spacings off (the
    /// rays are within 25° of vertical), the field's surface in front of
    /// it (the signed error negative); nothing sees through and nothing
    /// floats.
    #[test]
    fn a_slab_scores_its_offset_in_node_spacings() {
        let h = 2.0 / 23.0;
        let top = -1.0 + 11.0 * h;
        let field = slab(top + 0.5 * h);
        let f = frame();
        let on = geometry_score(&f, &field, &march(), &plane(top + 0.5 * h));
        assert!(on.compared > 900, "{on:?}");
        assert!(on.median_error < 0.5, "{on:?}");
        assert!(on.see_through == 0.0 && on.floating.is_nan(), "{on:?}");
        assert!(on.haze == 0.0, "{on:?}");
        let off = geometry_score(&f, &field, &march(), &plane(top - 1.5 * h));
        assert!(
            (off.median_error - on.median_error - 2.0).abs() < 0.5,
            "{on:?} {off:?}"
        );
        assert_eq!(off.median_signed_error, -off.median_error, "{off:?}");
        // Within 25° of the normal, the normal offset is 0.9–1 of the error.
        assert!(
            off.median_normal_offset <= off.median_error
                && off.median_normal_offset > 0.9 * off.median_error,
            "{off:?}"
        );
    }

    /// Seen at a grazing angle, the same offset reads several times as
    /// much depth along the rays, and the same along the slab's normal:
    /// a camera 0.55 above the slab's top and 2.5 along x meets it at
    /// 9–16° of elevation.
    #[test]
    fn an_offset_along_the_normal_does_not_grow_at_grazing_rays() {
        let h = 2.0 / 23.0;
        let top = -1.0 + 11.0 * h;
        let field = slab(top + 0.5 * h);
        let f = Frame {
            pose: Pose::looking_at(
                DVec3::new(2.5, top + 0.55, 0.0),
                DVec3::new(0.0, top, 0.0),
                DVec3::Y,
            ),
            intrinsics: Intrinsics::centred(32, 32, 12.0),
            ..frame()
        };
        let on = geometry_score(&f, &field, &march(), &plane(top + 0.5 * h));
        let off = geometry_score(&f, &field, &march(), &plane(top - 1.5 * h));
        // (Fewer rays meet the lower plane inside the bounds.)
        assert!(on.compared > 300 && off.compared > 300, "{on:?} {off:?}");
        let along = off.median_error - on.median_error;
        let normal = off.median_normal_offset - on.median_normal_offset;
        assert!(along > 6.0, "{on:?} {off:?}");
        assert!((normal - 2.0).abs() < 0.3, "{on:?} {off:?}");
        assert!(on.median_normal_offset <= on.median_error);
    }

    /// Fog of density 2 above the slab hides 1 − e^(−2L) of it, L the
    /// ray's length from the box's top (1 − top above the surface) to
    /// [`HAZE_MARGIN`] spacings short of the surface along the ray: from
    /// (1 − top) − 8h straight down to (1 − top)/cos 25° − 8h at the
    /// frame's corners; and its weight draws the field's expected depth in
    /// front of the surface.
    #[test]
    fn fog_in_front_of_a_surface_is_haze() {
        let h = 2.0 / 23.0;
        let top = -1.0 + 11.0 * h + 0.5 * h;
        let fog = 2.0f32;
        let g = geometry_score(&frame(), &foggy_slab(top, fog), &march(), &plane(top));
        let fog_length = |cos: f64| (1.0 - top) / cos - HAZE_MARGIN * h;
        let least = 1.0 - (-(fog as f64) * fog_length(1.0)).exp();
        let most = 1.0 - (-(fog as f64) * fog_length(25f64.to_radians().cos())).exp();
        assert!(
            g.haze > least - 1e-3 && g.haze < most,
            "{g:?}: {least}..{most}"
        );
        // The fog's weight pulls the expected depth in front of the slab.
        assert!(
            g.see_through == 0.0 && g.median_signed_error < -1.0,
            "{g:?}"
        );
    }

    /// An empty field is seen through wherever a surface is known, and an
    /// opaque one floats wherever none is.
    #[test]
    fn see_through_and_floaters_are_counted() {
        let f = frame();
        let empty = geometry_score(&f, &slab(-2.0), &march(), &plane(0.0));
        assert!(empty.compared == 0 && empty.see_through == 1.0 && empty.median_error.is_nan());
        assert_eq!(empty.haze, 0.0, "{empty:?}");
        let nothing = |_: &Ray, _: f64, _: f64| None::<(f64, DVec3)>;
        let full = geometry_score(&f, &slab(0.0), &march(), &nothing);
        assert!(full.compared == 0 && full.floating == 1.0 && full.see_through.is_nan());
        assert!(full.haze.is_nan(), "{full:?}");
    }
}

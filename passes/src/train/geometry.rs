//! A trained field's geometry in a view, scored against a known scene
//! (a recipe's, for a dataset `render-views` made): at each pixel the
//! field's expected depth D̂/Ô against the known scene's own along the ray
//! inside the field's bounds (its first opaque surface, and the
//! semi-transparent media in front of it, weighed as the march weighs a
//! field's density), and the opacity the field gathers well in front of
//! what the scene holds there (haze). A floor that floats or that the camera
//! sees through, or a room full of haze, spoils occlusion, probes,
//! shadows and the environment estimate even where the held-out views'
//! PSNR is good, and the PSNR cannot tell.

use glam::DVec3;

use crate::bake::PathTracer;
use crate::dataset::{Frame, PixelState};
use crate::field::GridField;
use crate::geometry::{ray_box, Ray};
use crate::march::{march_ray, MarchKnobs};
use crate::scene::Recipe;

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

/// One view's geometry against the known scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeometryScore {
    /// Pixels where the known scene is opaque inside the field's bounds
    /// (its opacity along the ray at least [`SURFACE_OPACITY`]: an opaque
    /// surface, or media dense enough) and so is the field: the depths
    /// compared.
    pub compared: usize,
    /// Median |D̂/Ô − D/O| over them, in the field's node spacings (its
    /// smallest), D/O the known scene's expected depth ([`known_depth`]:
    /// the surface's distance where no medium lies in front of it); NaN
    /// where none was compared.
    pub median_error: f64,
    /// Median of the signed D̂/Ô − D/O over the same pixels, in node
    /// spacings: negative where the field's surfaces lie in front of the
    /// known ones (NaN where none was compared).
    pub median_signed_error: f64,
    /// Median over the same pixels of |D̂/Ô − D/O|·|d·n| (d the ray's unit
    /// direction, n the known surface's normal where the ray meets it), in
    /// node spacings: how far the field's depth lies from the known
    /// surface's tangent plane. A ray meeting a floor at 16° of elevation
    /// reads an offset δ along its normal as δ / sin 16° ≈ 3.6δ of depth;
    /// this reads δ. Where media in front of the surface carry more than
    /// half the known weight, the depth is taken along the ray (a volume
    /// has no tangent plane). NaN where none was compared.
    pub median_normal_offset: f64,
    /// Share of the pixels where the known scene is opaque where the field
    /// is not: the camera sees through it (NaN: no such pixel).
    pub see_through: f64,
    /// Share of the other pixels where the field is opaque: floaters (NaN:
    /// no such pixel).
    pub floating: f64,
    /// Mean opacity the field gathers before [`HAZE_MARGIN`] node spacings
    /// in front of the first thing the known scene holds along the ray
    /// (a surface, or a medium's edge), over the pixels where the scene is
    /// opaque: the share of its light that haze in the free space hides
    /// from the camera (and from any point the estimate reads light at).
    /// A medium the scene holds is not haze. 0 on a clean field; NaN where
    /// no pixel's scene is opaque.
    pub haze: f64,
}

/// A stretch of a homogeneous medium along a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MediumSpan {
    /// Ray distance where the ray enters the medium.
    pub enter: f64,
    /// Ray distance where it leaves it.
    pub leave: f64,
    /// Extinction per unit of ray distance (the rays' directions are
    /// unit).
    pub density: f64,
}

/// What a known scene holds along a ray within (t_min, t_max): its first
/// opaque surface (distance and unit normal there) and the media the ray
/// crosses (any of them may reach past the surface: [`known_depth`] stops
/// there).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KnownAlong {
    /// The first opaque surface: its distance and unit normal; None where
    /// the ray meets none.
    pub surface: Option<(f64, DVec3)>,
    /// The media the ray crosses.
    pub media: Vec<MediumSpan>,
}

/// The known scene along a ray within (t_min, t_max).
pub type KnownContent<'a> = dyn Fn(&Ray, f64, f64) -> KnownAlong + Sync + 'a;

/// `recipe`'s content along a ray within (t_min, t_max): the first opaque
/// surface `tracer` (made from the same recipe) finds, and the media
/// primitives the ray crosses, clipped to the interval.
pub fn recipe_along(
    recipe: &Recipe,
    tracer: &PathTracer,
    ray: &Ray,
    t_min: f64,
    t_max: f64,
) -> KnownAlong {
    let surface = tracer
        .nearest_surface(ray, t_min, t_max)
        .map(|(t, i)| (t, recipe.primitives[i].shape.normal(ray.at(t))));
    let media = recipe
        .primitives
        .iter()
        .filter_map(|p| {
            let density = p.medium_density?;
            let (a, b) = p.shape.interval(ray)?;
            let (enter, leave) = (a.max(t_min), b.min(t_max));
            (leave > enter).then_some(MediumSpan {
                enter,
                leave,
                density,
            })
        })
        .collect();
    KnownAlong { surface, media }
}

/// A known scene's expected depth along a ray, the moments the march takes
/// of a field: D = ∫ t σ(t) T(t) dt over the media up to the surface plus
/// t_s T(t_s), O = 1 − T where no surface is met (1 where one is).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KnownDepth {
    /// D, in ray distance.
    pub depth: f64,
    /// O.
    pub opacity: f64,
    /// The surface's share of the weight, T(t_s) (0 where none is met).
    pub surface_weight: f64,
    /// The distance of the first thing along the ray (a medium's edge or
    /// the surface), None where there is nothing.
    pub first: Option<f64>,
}

/// The expected depth of `known` along a ray from `t_min` to `t_max`, in
/// closed form over the homogeneous spans (overlapping media add their
/// densities): a span [a, b] of density σ reached with transmittance T
/// adds T·(a(1 − e) + (b − a)((1 − e)/x − e)) to D and T(1 − e) to O, x =
/// σ(b − a), e = e^(−x) (the integral of t σ e^(−σ(t − a)), written so
/// that neither a thin nor a dense span cancels).
pub fn known_depth(known: &KnownAlong, t_min: f64, t_max: f64) -> KnownDepth {
    let surface = known
        .surface
        .filter(|&(t, _)| t >= t_min && t <= t_max)
        .map(|(t, _)| t);
    let end = surface.unwrap_or(t_max);
    let mut cuts = vec![t_min, end];
    for m in &known.media {
        cuts.extend([m.enter, m.leave].map(|t| t.clamp(t_min, end)));
    }
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let (mut depth, mut opacity, mut transmittance) = (0.0, 0.0, 1.0);
    let mut first = surface;
    for w in cuts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let mid = 0.5 * (a + b);
        let sigma: f64 = known
            .media
            .iter()
            .filter(|m| m.enter <= mid && mid < m.leave)
            .map(|m| m.density)
            .sum();
        if sigma <= 0.0 || b <= a {
            continue;
        }
        first = Some(first.map_or(a, |f: f64| f.min(a)));
        let x = sigma * (b - a);
        let gone = -(-x).exp_m1();
        let kept = 1.0 - gone;
        depth += transmittance * (a * gone + (b - a) * (gone / x - kept));
        opacity += transmittance * gone;
        transmittance *= kept;
    }
    let surface_weight = if let Some(t) = surface {
        depth += transmittance * t;
        opacity += transmittance;
        transmittance
    } else {
        0.0
    };
    KnownDepth {
        depth,
        opacity,
        surface_weight,
        first,
    }
}

/// One pixel's geometry against the known scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelDepth {
    /// The known scene is opaque along the pixel's ray inside the bounds
    /// (opacity at least [`SURFACE_OPACITY`]).
    pub known: bool,
    /// The field is opaque along it.
    pub opaque: bool,
    /// D̂/Ô − D/O in node spacings where both are opaque (negative: the
    /// field's surface in front), else NaN.
    pub error: f64,
    /// The opacity the field gathers before [`HAZE_MARGIN`] spacings in
    /// front of the first thing the known scene holds (NaN where the scene
    /// is not opaque).
    pub haze: f64,
    /// |d·n| at the known surface where it carries at least half the known
    /// weight, else 1.
    pub facing: f64,
}

/// Each of `frame`'s pixels' geometry against the known scene
/// `content(ray, t_min, t_max)` holds inside the field's bounds, row by
/// row: None where the pixel is masked or its ray misses the bounds.
pub fn depth_pixels(
    frame: &Frame,
    field: &GridField,
    march: &MarchKnobs,
    content: &KnownContent<'_>,
) -> Vec<Option<PixelDepth>> {
    use rayon::prelude::*;
    let spacing = field.spacing().min_element();
    let (w, h) = (frame.intrinsics.width, frame.intrinsics.height);
    (0..w * h)
        .into_par_iter()
        .map(|p| {
            if frame.image.state[p as usize] == PixelState::Masked {
                return None;
            }
            let ray = pixel_ray(frame, p)?;
            let (t0, t1) = ray_box(&ray, &field.bounds)?;
            let t0 = t0.max(0.0);
            let along = content(&ray, t0, t1);
            let k = known_depth(&along, t0, t1);
            let known = k.opacity >= SURFACE_OPACITY;
            let m = march_ray(field, &ray, f64::INFINITY, march);
            let opaque = m.opacity >= SURFACE_OPACITY;
            let error = if known && opaque {
                (m.depth / m.opacity - k.depth / k.opacity) / spacing
            } else {
                f64::NAN
            };
            let facing = match along.surface {
                Some((_, n)) if k.surface_weight >= 0.5 * k.opacity => {
                    (ray.dir.dot(n) / ray.dir.length()).abs()
                }
                _ => 1.0,
            };
            let haze = match k.first {
                Some(first) if known => {
                    let front = first - HAZE_MARGIN * spacing;
                    if front <= t0 {
                        0.0
                    } else {
                        march_ray(field, &ray, front, march).opacity
                    }
                }
                _ => f64::NAN,
            };
            Some(PixelDepth {
                known,
                opaque,
                error,
                haze,
                facing,
            })
        })
        .collect()
}

/// The node spacings of depth error at which [`depth_error_colour`] is
/// fully blue (in front) or red (behind).
pub const DEPTH_ERROR_FULL: f64 = 4.0;

/// A pixel's geometry as a colour (linear RGB in [0, 1]): white where the
/// field's depth matches the known scene's, fading to blue as the field's
/// surface lies further in front and to red as it lies further behind
/// (fully at [`DEPTH_ERROR_FULL`] spacings), magenta where the camera
/// sees through a known surface, green where the field is opaque over
/// nothing known, black where neither holds anything or there is no
/// pixel (None).
pub fn depth_error_colour(p: Option<&PixelDepth>) -> [f32; 3] {
    let Some(p) = p else {
        return [0.0; 3];
    };
    match (p.known, p.opaque) {
        (false, false) => [0.0; 3],
        (true, false) => [1.0, 0.0, 1.0],
        (false, true) => [0.0, 1.0, 0.0],
        (true, true) => {
            let fade = 1.0 - (p.error.abs() / DEPTH_ERROR_FULL).min(1.0) as f32;
            if p.error < 0.0 {
                [fade, fade, 1.0]
            } else {
                [1.0, fade, fade]
            }
        }
    }
}

/// Scores `field`'s geometry in `frame`'s usable pixels against the known
/// scene `content(ray, t_min, t_max)` holds along each pixel's ray inside
/// the field's bounds ([`depth_pixels`], [`score_pixels`]).
pub fn geometry_score(
    frame: &Frame,
    field: &GridField,
    march: &MarchKnobs,
    content: &KnownContent<'_>,
) -> GeometryScore {
    score_pixels(&depth_pixels(frame, field, march, content))
}

/// The score of a view's pixels ([`depth_pixels`]).
pub fn score_pixels(pixels: &[Option<PixelDepth>]) -> GeometryScore {
    let pixels: Vec<&PixelDepth> = pixels.iter().flatten().collect();
    let mut signed: Vec<f64> = pixels
        .iter()
        .map(|p| p.error)
        .filter(|e| !e.is_nan())
        .collect();
    let mut errors: Vec<f64> = signed.iter().map(|e| e.abs()).collect();
    let mut offsets: Vec<f64> = pixels
        .iter()
        .filter(|p| !p.error.is_nan())
        .map(|p| (p.error * p.facing).abs())
        .collect();
    errors.sort_by(f64::total_cmp);
    signed.sort_by(f64::total_cmp);
    offsets.sort_by(f64::total_cmp);
    let share = |of: &dyn Fn(&PixelDepth) -> bool, among: &dyn Fn(&PixelDepth) -> bool| {
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
        see_through: share(&|p| !p.opaque, &|p| p.known),
        floating: share(&|p| p.opaque, &|p| !p.known),
        haze: mean(pixels.iter().map(|p| p.haze).filter(|o| !o.is_nan())),
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
pub(super) mod tests {
    use glam::{DVec3, UVec3};

    use super::*;
    use crate::dataset::pixels::{FrameImage, PixelCounts};
    use crate::dataset::{Intrinsics, Pose};
    use crate::field::DEFAULT_OCCUPANCY_BLOCK;
    use crate::geometry::Aabb;

    /// A 24³ field over [−1, 1]³ opaque below `floor` (density 400 a unit),
    /// empty above.
    pub(in crate::train) fn slab(floor: f64) -> GridField {
        foggy_slab(floor, 0.0)
    }

    /// [`slab`] with density `fog` a unit above `floor`.
    pub(in crate::train) fn foggy_slab(floor: f64, fog: f32) -> GridField {
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
    pub(in crate::train) fn frame() -> Frame {
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
            depth: Vec::new(),
        }
    }

    /// The plane y = `y` as the known surface.
    fn plane(y: f64) -> impl Fn(&Ray, f64, f64) -> KnownAlong + Sync {
        move |ray: &Ray, t0: f64, t1: f64| {
            let t = (y - ray.origin.y) / ray.dir.y;
            KnownAlong {
                surface: (t > t0 && t < t1).then_some((t, DVec3::Y)),
                media: Vec::new(),
            }
        }
    }

    pub(in crate::train) fn march() -> MarchKnobs {
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

    /// The known scene's expected depth in closed form against a midpoint
    /// sum of t σ(t) T(t) over 2·10⁶ steps, the transmittance multiplied
    /// step by step: overlapping media, a medium reaching past the
    /// surface, a thin and a dense one, and no surface at all.
    #[test]
    fn the_known_depth_matches_quadrature() {
        let span = |enter, leave, density| MediumSpan {
            enter,
            leave,
            density,
        };
        let quadrature = |known: &KnownAlong, t_min: f64, t_max: f64| {
            let end = known.surface.map_or(t_max, |(t, _)| t);
            let n = 2_000_000;
            let dt = (end - t_min) / n as f64;
            let (mut depth, mut transmittance) = (0.0, 1.0);
            for i in 0..n {
                let t = t_min + (i as f64 + 0.5) * dt;
                let sigma: f64 = known
                    .media
                    .iter()
                    .filter(|m| m.enter <= t && t < m.leave)
                    .map(|m| m.density)
                    .sum();
                let kept = (-sigma * dt).exp();
                // The step's weight at its midpoint, its transmittance
                // taken half way through the step.
                depth += t * transmittance * (1.0 - kept);
                transmittance *= kept;
            }
            let opacity = 1.0 - transmittance;
            match known.surface {
                Some((t, _)) => (depth + t * transmittance, 1.0),
                None => (depth, opacity),
            }
        };
        let cases = [
            KnownAlong {
                surface: Some((3.0, DVec3::Y)),
                media: vec![span(0.5, 1.5, 2.0), span(1.0, 2.0, 0.7)],
            },
            KnownAlong {
                surface: Some((1.2, DVec3::Y)),
                media: vec![span(0.8, 2.5, 3.0)],
            },
            KnownAlong {
                surface: Some((2.0, DVec3::Y)),
                media: vec![span(0.2, 1.0, 1e-9), span(1.5, 1.6, 1e4)],
            },
            KnownAlong {
                surface: None,
                media: vec![span(0.4, 1.4, 1.5)],
            },
        ];
        for known in &cases {
            let k = known_depth(known, 0.1, 4.0);
            let (depth, opacity) = quadrature(known, 0.1, 4.0);
            assert!(
                (k.opacity - opacity).abs() < 1e-6,
                "{known:?}: {k:?} against {opacity}"
            );
            assert!(
                (k.depth - depth).abs() < 1e-5 * depth,
                "{known:?}: {k:?} against {depth}"
            );
            assert!(k.depth.is_finite() && k.opacity <= 1.0 + 1e-12);
        }
        // The dense span takes every bit of the light: the surface behind
        // it has none of the weight, and the depth is the span's front.
        let dense = known_depth(&cases[2], 0.1, 4.0);
        assert!(
            dense.surface_weight < 1e-12 && (dense.depth - 1.5).abs() < 1e-3,
            "{dense:?}"
        );
        // Nothing along the ray: no weight, no first thing.
        let none = known_depth(&KnownAlong::default(), 0.1, 4.0);
        assert_eq!((none.depth, none.opacity, none.first), (0.0, 0.0, None));
    }

    /// Fog the known scene holds too is no haze, and the field that
    /// renders it is scored against the scene's own expected depth: the
    /// fog of `fog_in_front_of_a_surface_is_haze` given to both.
    #[test]
    fn a_medium_the_scene_holds_is_neither_haze_nor_depth_error() {
        let h = 2.0 / 23.0;
        let top = -1.0 + 11.0 * h + 0.5 * h;
        let fog = 2.0;
        let field = foggy_slab(top, fog as f32);
        let foggy_plane = |ray: &Ray, t0: f64, t1: f64| {
            let mut known = plane(top)(ray, t0, t1);
            let end = known.surface.map_or(t1, |(t, _)| t);
            known.media.push(MediumSpan {
                enter: t0,
                leave: end,
                density: fog,
            });
            known
        };
        let with = geometry_score(&frame(), &field, &march(), &foggy_plane);
        let without = geometry_score(&frame(), &field, &march(), &plane(top));
        assert!(
            with.haze == 0.0 && without.haze > 0.5,
            "{with:?} {without:?}"
        );
        assert!(
            with.median_error < 0.5 && without.median_signed_error < -1.0,
            "{with:?} {without:?}"
        );
    }

    /// A ray through PLANTS' left foliage crosses its medium (density 6 a
    /// unit, 0.52 across its centre) before the wall behind it; a ray
    /// through CUPS' glass crosses the glass, and neither medium is taken
    /// for the surface.
    #[test]
    fn a_recipes_media_are_found_along_a_ray() {
        use std::path::Path;
        let along = |name: &str, ray: Ray| {
            let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.toml"));
            let scene = crate::scene::load_scene(&path).unwrap();
            let recipe = scene.recipe().unwrap();
            let tracer = PathTracer::new(recipe, &scene.environment, 0);
            recipe_along(recipe, &tracer, &ray, 0.0, 10.0)
        };
        let foliage = along(
            "plants",
            Ray {
                origin: DVec3::new(-0.45, 0.52, 2.0),
                dir: DVec3::NEG_Z,
            },
        );
        assert_eq!(foliage.media.len(), 1, "{foliage:?}");
        let m = foliage.media[0];
        assert!(
            (m.enter - 2.04).abs() < 1e-9 && (m.leave - 2.56).abs() < 1e-9,
            "{m:?}"
        );
        assert_eq!(m.density, 6.0);
        let (t, n) = foliage.surface.unwrap();
        assert!((t - 2.85).abs() < 1e-9 && n == DVec3::Z, "{foliage:?}");
        let glass = along(
            "cups",
            Ray {
                origin: DVec3::new(0.0, 0.2, 2.0),
                dir: DVec3::NEG_Z,
            },
        );
        assert_eq!(glass.media.len(), 1, "{glass:?}");
        assert!((glass.media[0].leave - glass.media[0].enter - 0.26).abs() < 1e-9);
        assert!(glass.surface.unwrap().0 > glass.media[0].leave, "{glass:?}");
    }

    /// An empty field is seen through wherever a surface is known, and an
    /// opaque one floats wherever none is.
    #[test]
    fn see_through_and_floaters_are_counted() {
        let f = frame();
        let empty = geometry_score(&f, &slab(-2.0), &march(), &plane(0.0));
        assert!(empty.compared == 0 && empty.see_through == 1.0 && empty.median_error.is_nan());
        assert_eq!(empty.haze, 0.0, "{empty:?}");
        let nothing = |_: &Ray, _: f64, _: f64| KnownAlong::default();
        let full = geometry_score(&f, &slab(0.0), &march(), &nothing);
        assert!(full.compared == 0 && full.floating == 1.0 && full.see_through.is_nan());
        assert!(full.haze.is_nan(), "{full:?}");
    }

    /// Each kind of pixel reads as its own colour, and the error's sign and
    /// size as blue or red of growing strength.
    #[test]
    fn a_depth_error_reads_as_its_colour() {
        let p = |known, opaque, error| PixelDepth {
            known,
            opaque,
            error,
            haze: f64::NAN,
            facing: 1.0,
        };
        assert_eq!(depth_error_colour(None), [0.0; 3]);
        assert_eq!(
            depth_error_colour(Some(&p(false, false, f64::NAN))),
            [0.0; 3]
        );
        assert_eq!(
            depth_error_colour(Some(&p(true, false, f64::NAN))),
            [1.0, 0.0, 1.0]
        );
        assert_eq!(
            depth_error_colour(Some(&p(false, true, f64::NAN))),
            [0.0, 1.0, 0.0]
        );
        assert_eq!(depth_error_colour(Some(&p(true, true, 0.0))), [1.0; 3]);
        assert_eq!(
            depth_error_colour(Some(&p(true, true, -2.0))),
            [0.5, 0.5, 1.0]
        );
        assert_eq!(
            depth_error_colour(Some(&p(true, true, 9.0))),
            [1.0, 0.0, 0.0]
        );
    }
}

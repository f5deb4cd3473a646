//! Surface points drawn from a rendered view (METHOD.md eq. 4): the point
//! at the ray's expected depth, x = o + (D̂/Ô)·d, its normal −∇σ/|∇σ|, and
//! the pixel's radiance Ĉ/Ô as the value the Lambertian model must explain.
//!
//! A pixel is a candidate when its ray passes through the field (Ô ≥ 0.5)
//! and the point is on a surface the model describes: the normal faces
//! the camera, the point is on a surface rather than inside
//! semi-transparent matter such as foliage or glass, where the Lambertian
//! surface model does not hold ([`SurfaceTest`]), the pixel is not mixed
//! (its radiance's luminance and that of the field's own colour at the
//! point differ by at most
//! [`MAX_MIXED_DIFFERENCE`] of the larger: a ray that grazes a lamp's glow
//! or a silhouette on its way collects light the point does not reflect),
//! on a trained field the surface does not bend sharply within a node
//! spacing of the point ([`crease_angle`]: on an edge the field has
//! rounded, the normal is a blend of two faces' and the colour the
//! brighter face's), and the radiance is no more than `emitter_ratio` ×
//! the median luminance of every pixel the views saw the field in
//! ([`emitter_limit`]; brighter points are light sources in the field,
//! which no reflector explains). The median was
//! each view's own: a view that saw mostly the dark outside of ROOM's
//! walls took the lit room inside for a light source (3168 of ROOM's
//! pixels left out at 8×, the estimate's error 288 %).

use glam::DVec3;

use super::knobs::EnvEstimateKnobs;
use super::quality::ViewImage;
use crate::camera::CameraFrame;
use crate::field::{GridField, RadianceField};
use crate::geometry::Ray;
use crate::march::{march_samples, MarchKnobs};
use crate::rng::Pcg32;
use crate::sgfit::model::luminance;

/// Smallest |∇σ|·h² of a surface point under [`SurfaceTest::Gradient`]
/// (an opaque surface of the bundled recipes reaches about 5 at its
/// expected depth; a medium's edge about 0.05).
pub const MIN_SURFACE_GRADIENT: f64 = 0.5;

/// The length over which [`SurfaceTest::Weight`] reads a trained field's
/// surface, as a share of the field's largest extent: a node spacing of a
/// 128-node grid. The blur a trainer leaves on a surface is a length in
/// the scene rather than a count of nodes (DOG trained at 256 nodes in
/// 2000 steps spreads a pixel's weight over more spacings than at 128:
/// asked for 65 % of it within two spacings, 97 views of 100 held no
/// surface), so on a finer grid the tests below reach over more nodes
/// ([`trained_surface_scale`]).
pub const TRAINED_SCALE_OF_EXTENT: f64 = 1.0 / 128.0;

/// The length, in the field's units, over which [`SurfaceTest::Weight`]
/// reads the surface: a node spacing, or [`TRAINED_SCALE_OF_EXTENT`] of the
/// field's largest extent where that is more.
pub fn trained_surface_scale(field: &GridField) -> f64 {
    let h = field.spacing().min_element();
    h.max(TRAINED_SCALE_OF_EXTENT * field.bounds.size().max_element())
}

/// Half the width of the stretch of a ray, about its expected depth, that
/// must hold a surface's weight under [`SurfaceTest::Weight`], in
/// [`trained_surface_scale`]s.
pub const SURFACE_HALF_WIDTH: f64 = 2.0;

/// How far either side of a point, in [`trained_surface_scale`]s, the
/// central differences reach that give its normal under
/// [`SurfaceTest::Weight`]. A trained surface rises over several nodes
/// and carries the trainer's node-to-node noise: one spacing reads a node
/// pair's noise against a small part of the rise, two read twice the rise
/// against the same noise. On DOG trained at 128 nodes two spacings took
/// the estimate's error from 29.8 % to 24.6 % over four seeds (and from 21.8 % to 17.4 %
/// with a [`MIN_SURFACE_SHARE`] of 0.65; three spacings 23.6 %;
/// docs/fidelity.md, "Twenty-fourth pass"). A bake's surfaces are sharp,
/// so the gradient test keeps one spacing.
pub const NORMAL_REACH: f64 = 2.0;

/// The length in which `test` measures a surface's reaches: a node
/// spacing for [`SurfaceTest::Gradient`] (a bake's surfaces are sharp),
/// [`trained_surface_scale`] for [`SurfaceTest::Weight`].
pub fn surface_unit(field: &GridField, test: SurfaceTest) -> f64 {
    match test {
        SurfaceTest::Gradient => field.spacing().min_element(),
        SurfaceTest::Weight => trained_surface_scale(field),
    }
}

/// ∇σ at `x` as `test` reads it: central differences one node spacing
/// either side for [`SurfaceTest::Gradient`] (whose steepness test reads
/// its length), [`NORMAL_REACH`] scales for [`SurfaceTest::Weight`].
fn surface_gradient(field: &GridField, x: DVec3, test: SurfaceTest) -> DVec3 {
    let reach = match test {
        SurfaceTest::Gradient => 1.0,
        SurfaceTest::Weight => NORMAL_REACH,
    };
    field.density_gradient_over(x, reach * surface_unit(field, test))
}

/// The unit normal −∇σ/|∇σ| at `x` under `test`, ∇σ by central
/// differences [`NORMAL_REACH`] scales either side under the weight test,
/// one node spacing under the gradient test.
pub fn surface_normal(field: &GridField, x: DVec3, test: SurfaceTest) -> DVec3 {
    -surface_gradient(field, x, test).normalize_or_zero()
}

/// Smallest share of a pixel's opacity within [`SURFACE_HALF_WIDTH`]
/// [`trained_surface_scale`]s of its expected depth for its point to be on
/// a surface under [`SurfaceTest::Weight`]. Over the estimate's views, 95 %
/// of DOG's baked surface pixels reach 0.84 and the tenth of PLANTS'
/// covered pixels that see into its foliage stay under 0.2; DOG trained at
/// 128 nodes, half its pixels reach 0.53 (0.61 with the trainer's
/// distortion loss). 0.65 took the estimate's error on that field from
/// 24.6 % to 17.4 % over four seeds (with the normals over
/// [`NORMAL_REACH`]). With the window in node spacings it left a 256-node
/// field trained in 2000 steps without a surface in 97 views of 100; in
/// [`trained_surface_scale`]s the same field keeps 30 views of 33 and 1691
/// points, as many as at 0.5 (docs/fidelity.md, "Twenty-fifth pass").
pub const MIN_SURFACE_SHARE: f64 = 0.65;

/// Smallest |∇σ|·s² of a point under [`SurfaceTest::Weight`], s the
/// [`trained_surface_scale`] and ∇σ read over [`NORMAL_REACH`] scales
/// either side (the normal's own differences). At this slope a density
/// rising from zero reaches an optical depth of 1 within about 4.5
/// scales; below it the point lies in a haze or on the crest of a faint
/// sheet, where the gradient, and so the normal, is mostly noise. PLANTS
/// trained from 64 views of 256² left a faint haze (σ·s 0.1–0.34, up to
/// 18 cm deep, with no floor below it in places) where its untextured
/// floor is: its lit candidates read under 0.05, their normals 14–38°
/// off the recipe's (median), its surfaces' 0.07–0.2 with 6–9°. The worst
/// haze points held most of the misfit of the recipe's own radiance and
/// light at the points, and the estimate read 64 % of the lights where
/// the answer is black; without them 10 % (docs/fidelity.md,
/// "Twenty-ninth pass"). A bake's surfaces are far steeper.
pub const MIN_TRAINED_GRADIENT: f64 = 0.1;

/// How a surface point is told from one inside a medium.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SurfaceTest {
    /// The density rises like a surface's: |∇σ|·h² ≥
    /// [`MIN_SURFACE_GRADIENT`], h the node spacing. Right for a bake,
    /// whose opaque surfaces are a hundred times steeper than its media.
    /// A trained field's surfaces are as opaque with a hundredth of the
    /// gradient: every surface of DOG trained at 128 nodes fails it.
    #[default]
    Gradient,
    /// The ray's weight sits on a surface: at least [`MIN_SURFACE_SHARE`]
    /// of the pixel's opacity within [`SURFACE_HALF_WIDTH`] node spacings
    /// of its expected depth, and the density there rising at least
    /// [`MIN_TRAINED_GRADIENT`] (about a fiftieth of a bake's surfaces'
    /// slope). Holds on trained fields; but a bake's dense foliage passed
    /// the share alone (PLANTS' all-visible estimate 6.9 % of the lamp's
    /// light against under 2 % with the gradient, at a share of 0.5), so
    /// it is not the default. It also leaves out points on creases
    /// ([`super::knobs::EnvEstimateKnobs::max_crease`]).
    Weight,
}

/// Where a trained surface point's normal is read
/// ([`super::knobs::EnvEstimateKnobs::normals`]; a bake's is read at the
/// point under either).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SurfaceNormals {
    /// −∇σ at the point, over [`NORMAL_REACH`] scales, and the crease test
    /// on the normals a scale away ([`crease_angle`]).
    #[default]
    AtPoint,
    /// −Σ w_i ∇σ(x_i) along the pixel's ray through the surface
    /// (`surface_walk`), and the crease test on the rays beside it: for
    /// the thin shells a trainer's bounded total variation and distortion
    /// loss leave, whose expected depth sits on the density's peak
    /// (docs/fidelity.md, "Thirty-fourth pass").
    AlongRay,
}

/// Largest relative difference between a pixel's luminance and the field's
/// colour at its surface point before the pixel counts as mixed. On PLANTS
/// a floor pixel whose ray grazed the lamp differs by 0.76 (and alone made
/// most of the fit's loss); unmixed pixels of the bundled recipes stay
/// under 0.45.
pub const MAX_MIXED_DIFFERENCE: f64 = 0.5;

/// How far from a point, in [`trained_surface_scale`]s, [`crease_angle`]
/// compares normals.
pub const CREASE_REACH: f64 = 1.0;

/// The largest angle, in degrees, between the normal at surface point `x`
/// (unit `normal`) and the normals [`CREASE_REACH`]
/// [`trained_surface_scale`]s away from it in its tangent plane, four
/// ways, each by central differences a scale either side: how sharply the
/// field's surface bends at the scale the field resolves. A flat surface
/// reads 0, a sphere of radius R scales about asin(1/R), an edge the
/// field blurred over a few nodes tens of degrees. There the point's
/// normal is a blend of two faces' while its colour is mostly the
/// brighter face's: on DOG trained at 128 nodes, the rims of the body's
/// end caps face away from the bulb yet are as bright as its lit top, and
/// the environment fit gave them light from below the horizon
/// (docs/fidelity.md, "Twenty-third pass"). Meant for trained fields,
/// whose density rises over a few nodes: a bake's is zero a node off a
/// curved surface, where the gradient gives no normal, so its round
/// surfaces read as creases.
pub fn crease_angle(field: &GridField, x: DVec3, normal: DVec3) -> f64 {
    let scale = trained_surface_scale(field);
    largest_turn(normal, |t| {
        -field
            .density_gradient_over(x + t * CREASE_REACH * scale, scale)
            .normalize_or_zero()
    })
}

/// The largest angle, in degrees, between unit `normal` and the normals
/// `beside(t)` gives a step along each of four tangent directions t (two
/// orthogonal ones and their opposites); a zero normal reads 90°.
fn largest_turn(normal: DVec3, beside: impl Fn(DVec3) -> DVec3) -> f64 {
    let t1 = normal.any_orthonormal_vector();
    let t2 = normal.cross(t1);
    [t1, -t1, t2, -t2]
        .into_iter()
        .map(|t| normal.dot(beside(t)).clamp(-1.0, 1.0).acos().to_degrees())
        .fold(0.0, f64::max)
}

/// As [`crease_angle`], with each normal read as the pixel's is
/// ([`surface_walk`]): the largest angle, in degrees, between `normal` and
/// the normals of the rays parallel to `ray` that cross the point's
/// tangent plane [`CREASE_REACH`] [`trained_surface_scale`]s from it, four
/// ways, each summed over the stretch of its ray within `half_width` of
/// that plane. An edge's neighbours cross another face, or no surface in
/// that stretch (no normal: 90°).
fn crease_angle_along(
    field: &GridField,
    ray: &Ray,
    depth: f64,
    normal: DVec3,
    half_width: f64,
    knobs: &MarchKnobs,
) -> f64 {
    let scale = trained_surface_scale(field);
    largest_turn(normal, |t| {
        let beside = Ray {
            origin: ray.origin + t * CREASE_REACH * scale,
            dir: ray.dir,
        };
        surface_walk(field, &beside, depth, half_width, knobs, true).1
    })
}

/// One surface point of the field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// x_surf, at the ray's expected depth.
    pub position: DVec3,
    /// Unit normal −∇σ/|∇σ|.
    pub normal: DVec3,
    /// The pixel's radiance Ĉ/Ô (what a(x)/π·E must reproduce).
    pub radiance: DVec3,
    /// The view it came from.
    pub view: u32,
}

/// What one view gave.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ViewPoints {
    /// The points drawn (at most the number asked for).
    pub points: Vec<SurfacePoint>,
    /// The luminance of the radiance (Ĉ/Ô) of each pixel whose ray passes
    /// through the field (Ô ≥ 1/2): what the light-source limit is judged
    /// against ([`emitter_limit`]).
    pub covered_luminance: Vec<f32>,
    /// Covered pixels left out as light sources.
    pub emitters: usize,
    /// Covered pixels left out as not on a surface.
    pub not_surface: usize,
    /// Covered pixels left out as mixed ([`MAX_MIXED_DIFFERENCE`]).
    pub mixed: usize,
    /// Covered pixels left out as on a crease ([`crease_angle`]).
    pub creased: usize,
    /// Candidates tried and left out as seen by no photograph
    /// ([`super::witnesses`]).
    pub unseen: usize,
}

/// Whether a pixel of `radiance` whose surface point is `x`, seen along
/// `dir`, mixes light from elsewhere: its luminance and the field's colour
/// at `x` along `dir` differ by more than [`MAX_MIXED_DIFFERENCE`] of the
/// larger.
pub(crate) fn is_mixed(field: &GridField, x: DVec3, dir: DVec3, radiance: DVec3) -> bool {
    let own = luminance(field.colour(x, dir));
    let seen = luminance(radiance);
    (seen - own).abs() > MAX_MIXED_DIFFERENCE * seen.max(own)
}

/// The reach, in node spacings, of the central differences that give each
/// sample's ∇σ in `surface_walk`'s normal. A trained surface is a shell
/// a few spacings thick whose expected depth lies near its density's peak,
/// where the gradient read at that one point over [`NORMAL_REACH`] scales
/// has lost the rise and holds the node-to-node noise along the surface:
/// ROOM's trained floor (thirty-third pass's field) read its normals a
/// median 31° off the recipe's, its walls 16° and 19°. Summed along the
/// ray with the rendering weights, ∇σ over 2 spacings read 34°, over 1
/// 20°, over ½ 16°, over ¼ 15° (walls 10° and 14°): each sample's
/// gradient should see the shell's rise where the ray crosses it, not
/// reach past it. Over ¼ or ½ spacing it reads more of the node-to-node
/// noise than the point's normal does on thicker shells (synthetic
/// floors: 11–15° against 6–11°); over 1 it is no worse there and 11°
/// against 71° on a shell three spacings thick (docs/fidelity.md,
/// "Thirty-fourth pass").
pub const WEIGHTED_NORMAL_REACH: f64 = 1.0;

/// One walk along `ray` through `field` (marched with `knobs`): the share
/// of its opacity within `half_width` of distance `depth`, and, when
/// `with_normal`, the unit normal those samples show, −Σ w_i ∇σ(x_i) / |…|
/// over them (w_i the rendering weights, ∇σ over
/// [`WEIGHTED_NORMAL_REACH`] node spacings): the side of the shell the
/// ray enters weighs most, as it does in the pixel's colour. Zero where
/// the samples' gradients cancel, or not asked for.
fn surface_walk(
    field: &GridField,
    ray: &Ray,
    depth: f64,
    half_width: f64,
    knobs: &MarchKnobs,
    with_normal: bool,
) -> (f64, DVec3) {
    let reach = WEIGHTED_NORMAL_REACH * field.spacing().min_element();
    let (mut near, mut all, mut gradient) = (0.0, 0.0, DVec3::ZERO);
    march_samples(field, ray, f64::INFINITY, knobs, |s| {
        all += s.weight;
        if (s.t - depth).abs() <= half_width {
            near += s.weight;
            if with_normal {
                gradient += s.weight * field.density_gradient_over(ray.at(s.t), reach);
            }
        }
    });
    let share = if all > 0.0 { near / all } else { 0.0 };
    (share, -gradient.normalize_or_zero())
}

/// Every candidate surface point of `view` (rendered from `frame` with
/// `knobs`), `view_index` naming it, surfaces told and their normals read
/// as `rules` say (`surface_test`, `normals`; under
/// [`SurfaceTest::Weight`], those that bend more than `max_crease` degrees
/// left out), before light sources are left out.
pub fn view_candidates(
    field: &GridField,
    frame: &CameraFrame,
    view: &ViewImage,
    view_index: u32,
    knobs: &MarchKnobs,
    rules: &EnvEstimateKnobs,
) -> ViewPoints {
    let (test, max_crease) = (rules.surface_test, rules.max_crease);
    let along_ray = test == SurfaceTest::Weight && rules.normals == SurfaceNormals::AlongRay;
    let h = field.spacing().min_element();
    let unit = trained_surface_scale(field);
    let half_width = SURFACE_HALF_WIDTH * unit;
    let mut out = ViewPoints::default();
    for (i, (p, d)) in view.colour_opacity.iter().zip(&view.depth).enumerate() {
        let opacity = p[3] as f64;
        if opacity < 0.5 {
            continue;
        }
        let (px, py) = (i as u32 % view.width, i as u32 / view.width);
        let ray = frame.pixel_ray(px, py);
        let depth = *d as f64 / opacity;
        let x = ray.at(depth);
        let radiance = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) / opacity;
        out.covered_luminance.push(luminance(radiance) as f32);
        let g = surface_gradient(field, x, test);
        let at_point = -g.normalize_or_zero();
        // A bake's normal is read at the point; a trained surface's there
        // too, or along the ray through its shell (`surface_walk`).
        let (surface, normal) = match test {
            SurfaceTest::Gradient => (g.length() * h * h >= MIN_SURFACE_GRADIENT, at_point),
            SurfaceTest::Weight => {
                let (share, walked) =
                    surface_walk(field, &ray, depth, half_width, knobs, along_ray);
                (
                    g.length() * unit * unit >= MIN_TRAINED_GRADIENT && share >= MIN_SURFACE_SHARE,
                    if along_ray { walked } else { at_point },
                )
            }
        };
        let surface = surface && normal.dot(ray.dir) < 0.0 && radiance.is_finite();
        if !surface {
            out.not_surface += 1;
            continue;
        }
        if is_mixed(field, x, ray.dir, radiance) {
            out.mixed += 1;
            continue;
        }
        if test == SurfaceTest::Weight
            && max_crease < 180.0
            && if along_ray {
                crease_angle_along(field, &ray, depth, normal, half_width, knobs)
            } else {
                crease_angle(field, x, normal)
            } > max_crease
        {
            out.creased += 1;
            continue;
        }
        out.points.push(SurfacePoint {
            position: x,
            normal,
            radiance: radiance.max(DVec3::ZERO),
            view: view_index,
        });
    }
    out
}

/// The luminance above which a candidate is a light source:
/// `emitter_ratio` × the median luminance of every pixel the `views` saw
/// the field in (0 when there are none). Not the candidates' median: a
/// trained field's surface test may pass few pixels, and those mostly on
/// the light itself (PLANTS trained at 128 nodes: 1525 candidates of
/// 400 700 covered pixels, most of them on the lamp, whose median made
/// the lamp a reflector and the estimate 11 × the scene's light); on
/// the other bakes the two medians agree within 3 %, on PLANTS' the
/// pixels' is 0.15 and the candidates' 0.21.
pub fn emitter_limit<'a>(
    views: impl IntoIterator<Item = &'a ViewPoints>,
    emitter_ratio: f64,
) -> f64 {
    emitter_ratio * covered_median(views)
}

/// The median luminance of every pixel the `views` saw the field in (0
/// when there are none).
pub fn covered_median<'a>(views: impl IntoIterator<Item = &'a ViewPoints>) -> f64 {
    let mut lum: Vec<f32> = views
        .into_iter()
        .flat_map(|v| v.covered_luminance.iter().copied())
        .collect();
    if lum.is_empty() {
        return 0.0;
    }
    let mid = lum.len() / 2;
    *lum.select_nth_unstable_by(mid, f32::total_cmp).1 as f64
}

/// Keeps up to `count` of `view`'s candidates for which `seen` holds,
/// tried in a random order drawn with `rng` until `count` are kept (so
/// that the test runs on few); the others tried are counted as unseen.
/// `seen` may rewrite the point it keeps (its radiance read from the
/// photographs that saw it).
pub fn keep_seen(
    mut view: ViewPoints,
    count: usize,
    rng: &mut Pcg32,
    mut seen: impl FnMut(&mut SurfacePoint) -> bool,
) -> ViewPoints {
    let mut kept = 0;
    let mut next = 0;
    while kept < count && next < view.points.len() {
        let j = next + (rng.next_u32() as usize % (view.points.len() - next));
        view.points.swap(next, j);
        if seen(&mut view.points[next]) {
            view.points.swap(kept, next);
            kept += 1;
        } else {
            view.unseen += 1;
        }
        next += 1;
    }
    view.points.truncate(kept);
    view
}

/// Leaves out `view`'s candidates brighter than `limit` (counted as
/// light sources) and keeps `count` of the rest, chosen with `rng`.
pub fn draw_points(mut view: ViewPoints, limit: f64, count: usize, rng: &mut Pcg32) -> ViewPoints {
    let before = view.points.len();
    view.points.retain(|c| luminance(c.radiance) <= limit);
    view.emitters += before - view.points.len();
    keep_seen(view, count, rng, |_| true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Shape;

    fn view(index: u32, luminances: &[f64]) -> ViewPoints {
        ViewPoints {
            points: luminances
                .iter()
                .map(|&l| SurfacePoint {
                    position: DVec3::ZERO,
                    normal: DVec3::Y,
                    radiance: DVec3::splat(l),
                    view: index,
                })
                .collect(),
            covered_luminance: luminances.iter().map(|&l| l as f32).collect(),
            ..Default::default()
        }
    }

    /// A ray through a thin opaque shell has its weight at its expected
    /// depth; one through a haze as opaque in all has it spread, under
    /// [`MIN_SURFACE_SHARE`] within two node spacings of its expected
    /// depth.
    #[test]
    fn a_shell_holds_the_ray_s_weight_and_a_haze_does_not() {
        use crate::geometry::Aabb;
        use glam::UVec3;
        let res = UVec3::new(41, 2, 2);
        let bounds = Aabb::new(DVec3::ZERO, DVec3::new(4.0, 0.1, 0.1));
        let field = |thin: bool| {
            let nodes = (0..res.x * res.y * res.z)
                .map(|n| {
                    let i = n % res.x;
                    let sigma = match (thin, i) {
                        (true, 20) => 300.0,
                        (true, _) => 0.0,
                        (false, _) => 0.6,
                    };
                    [0.5, 0.5, 0.5, sigma]
                })
                .collect();
            GridField::new(res, bounds, nodes, 4)
        };
        let ray = Ray {
            origin: DVec3::new(-1.0, 0.05, 0.05),
            dir: DVec3::X,
        };
        let knobs = MarchKnobs::default();
        for (thin, expect_surface) in [(true, true), (false, false)] {
            let f = field(thin);
            let m = crate::march::march_ray(&f, &ray, f64::INFINITY, &knobs);
            assert!(m.opacity > 0.85, "{}", m.opacity);
            let (share, _) = surface_walk(
                &f,
                &ray,
                m.depth / m.opacity,
                SURFACE_HALF_WIDTH * trained_surface_scale(&f),
                &knobs,
                false,
            );
            assert_eq!(
                share >= MIN_SURFACE_SHARE,
                expect_surface,
                "thin {thin}: {share}"
            );
        }
    }

    /// A field whose density rises linearly over two node spacings about
    /// the surface `sdf` = 0 (a trained field's soft surface), on 33³ nodes
    /// over the unit cube.
    fn solid(sdf: impl Fn(DVec3) -> f64) -> GridField {
        soft_solid(33, 2.0, 0.0, sdf)
    }

    /// As [`solid`] on `n`³ nodes, the density rising over `rise` node
    /// spacings, each node's scaled by a random factor in 1 ± `noise` (a
    /// trainer's node-to-node noise).
    fn soft_solid(n: u32, rise: f64, noise: f64, sdf: impl Fn(DVec3) -> f64) -> GridField {
        use crate::geometry::Aabb;
        use glam::UVec3;
        let h = 1.0 / (n - 1) as f64;
        let mut rng = Pcg32::new(7, 3);
        let nodes = (0..n * n * n)
            .map(|i| {
                let p = DVec3::new((i % n) as f64, ((i / n) % n) as f64, (i / (n * n)) as f64) * h;
                let jitter = 1.0 + noise * (2.0 * rng.next_f64() - 1.0);
                let sigma = 100.0 * jitter * (0.5 - sdf(p) / (rise * h)).clamp(0.0, 1.0);
                [0.5, 0.5, 0.5, sigma as f32]
            })
            .collect();
        GridField::new(
            UVec3::splat(n),
            Aabb::new(DVec3::ZERO, DVec3::ONE),
            nodes,
            4,
        )
    }

    /// A trained floor's shell: on `n`³ nodes over the unit box, the density
    /// rises to 40 over `rise` node spacings down to the surface, stays
    /// there for `plateau` and falls to zero over `fall`, the surface's
    /// height in each column of nodes
    /// y = ½ + `bump` spacings × a random number in [−1, 1], each node's
    /// density scaled by a random factor in 1 ± `noise`.
    fn shell(n: u32, bump: f64, noise: f64, rise: f64, plateau: f64, fall: f64) -> GridField {
        use crate::geometry::Aabb;
        use glam::UVec3;
        let h = 1.0 / (n - 1) as f64;
        let mut rng = Pcg32::new(11, 5);
        let heights: Vec<f64> = (0..n * n)
            .map(|_| 0.5 + bump * h * (2.0 * rng.next_f64() - 1.0))
            .collect();
        let nodes = (0..n * n * n)
            .map(|i| {
                let (x, y, z) = (i % n, (i / n) % n, i / (n * n));
                let jitter = 1.0 + noise * (2.0 * rng.next_f64() - 1.0);
                let above = (y as f64 * h - heights[(x + n * z) as usize]) / h;
                let profile = if above >= 0.0 {
                    (1.0 - above / rise).max(0.0)
                } else if above >= -plateau {
                    1.0
                } else {
                    (1.0 + (above + plateau) / fall).max(0.0)
                };
                [0.5, 0.5, 0.5, (40.0 * jitter * profile) as f32]
            })
            .collect();
        GridField::new(
            UVec3::splat(n),
            Aabb::new(DVec3::ZERO, DVec3::ONE),
            nodes,
            4,
        )
    }

    /// The median angle, in degrees, between the floor's normal (+y) and
    /// the normals read on `f` along 400 parallel rays onto it: summed
    /// along each ray ([`surface_walk`]) and at its expected depth
    /// ([`surface_normal`]).
    fn floor_normal_errors(f: &GridField) -> (f64, f64) {
        let knobs = MarchKnobs::default();
        let unit = trained_surface_scale(f);
        let angle = |n: DVec3| n.dot(DVec3::Y).clamp(-1.0, 1.0).acos().to_degrees();
        let dir = DVec3::new(1.0, -1.0, 0.4).normalize();
        let (mut walked, mut at_point) = (Vec::new(), Vec::new());
        for i in 0..20 {
            for j in 0..20 {
                let target = DVec3::new(0.2 + 0.03 * i as f64, 0.5, 0.2 + 0.03 * j as f64);
                let ray = Ray {
                    origin: target - dir * 0.4,
                    dir,
                };
                let m = crate::march::march_ray(f, &ray, f64::INFINITY, &knobs);
                let depth = m.depth / m.opacity;
                let (_, n) = surface_walk(f, &ray, depth, SURFACE_HALF_WIDTH * unit, &knobs, true);
                walked.push(angle(n));
                at_point.push(angle(surface_normal(f, ray.at(depth), SurfaceTest::Weight)));
            }
        }
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        (median(walked), median(at_point))
    }

    /// On a shell three spacings thick (as the trainer's bounded total
    /// variation and distortion loss leave ROOM's floor), ∇σ read at the
    /// expected depth over [`NORMAL_REACH`] scales reaches past the shell
    /// on both sides and reads the noise along it; summed along the ray it
    /// reads the rise where the ray enters.
    #[test]
    fn a_thin_shells_normal_is_read_along_the_ray() {
        let (walked, at_point) = floor_normal_errors(&shell(65, 0.3, 0.2, 1.0, 1.0, 1.0));
        assert!(
            walked < 15.0 && at_point > 3.0 * walked,
            "along the ray {walked}°, at the point {at_point}°"
        );
    }

    /// On thicker noisy shells the normal along the ray is no worse than
    /// the one at the point (by a degree).
    #[test]
    fn a_thick_shells_normal_along_the_ray_is_no_worse() {
        for (rise, plateau, fall) in [(2.0, 0.0, 4.0), (2.0, 2.0, 1.0), (3.0, 3.0, 3.0)] {
            let (walked, at_point) = floor_normal_errors(&shell(65, 0.3, 0.2, rise, plateau, fall));
            assert!(
                walked < at_point + 1.0,
                "rise {rise}, plateau {plateau}, fall {fall}: along the ray {walked}°, at the point {at_point}°"
            );
        }
    }

    /// Without noise, a tilted shell's normal is read along the ray to
    /// within a degree.
    #[test]
    fn a_clean_tilted_shells_normal_is_exact() {
        let tilt = DVec3::new(0.3, 1.0, -0.2).normalize();
        let f = soft_solid(65, 2.0, 0.0, |p| (p - DVec3::splat(0.5)).dot(tilt));
        let knobs = MarchKnobs::default();
        let dir = DVec3::new(-0.5, -1.0, 0.3).normalize();
        let ray = Ray {
            origin: DVec3::splat(0.5) - dir * 0.45,
            dir,
        };
        let m = crate::march::march_ray(&f, &ray, f64::INFINITY, &knobs);
        let depth = m.depth / m.opacity;
        let unit = trained_surface_scale(&f);
        let (share, n) = surface_walk(&f, &ray, depth, SURFACE_HALF_WIDTH * unit, &knobs, true);
        assert!(share > 0.9, "{share}");
        let off = n.dot(tilt).clamp(-1.0, 1.0).acos().to_degrees();
        assert!(off < 1.0, "{off}°");
    }

    /// The weight test reads a surface over a length of the scene: a node
    /// spacing of a 128-node grid, more than one spacing of a finer grid.
    #[test]
    fn a_trained_surface_is_read_over_a_length_of_the_scene() {
        let flat = |_: DVec3| 1.0;
        let coarse = soft_solid(33, 2.0, 0.0, flat);
        assert_eq!(trained_surface_scale(&coarse), 1.0 / 32.0);
        let fine = soft_solid(257, 2.0, 0.0, flat);
        assert_eq!(trained_surface_scale(&fine), 1.0 / 128.0);
        assert!((trained_surface_scale(&fine) / fine.spacing().x - 2.0).abs() < 1e-12);
    }

    /// On a floor blurred over six node spacings whose nodes carry a
    /// trainer's noise, the weight test's normal (central differences two
    /// spacings either side) leans less than the gradient test's (one
    /// spacing), on average and at worst: the wider difference reads more
    /// of the surface's rise against the same noise.
    #[test]
    fn the_weight_test_s_normal_reads_through_node_noise() {
        let floor = soft_solid(33, 6.0, 0.4, |p| p.y - 0.5);
        let mut rng = Pcg32::new(5, 1);
        let (mut one, mut two) = (Vec::new(), Vec::new());
        for _ in 0..400 {
            let [u, v] = rng.next_2d();
            let x = DVec3::new(0.2 + 0.6 * u, 0.5, 0.2 + 0.6 * v);
            let lean = |n: DVec3| n.dot(DVec3::Y).clamp(-1.0, 1.0).acos().to_degrees();
            one.push(lean(surface_normal(&floor, x, SurfaceTest::Gradient)));
            two.push(lean(surface_normal(&floor, x, SurfaceTest::Weight)));
        }
        let mean = |a: &[f64]| a.iter().sum::<f64>() / a.len() as f64;
        let worst = |a: &[f64]| a.iter().cloned().fold(0.0, f64::max);
        // Measured: 25.0° and 11.4° on average, 76.7° and 36.9° at worst.
        assert!(mean(&one) > 10.0, "the noise leans one spacing's normals");
        assert!(
            mean(&two) < 0.6 * mean(&one),
            "{} {}",
            mean(&two),
            mean(&one)
        );
        assert!(worst(&two) < worst(&one), "{} {}", worst(&two), worst(&one));
    }

    /// An axis-aligned cube of half-edge `half` about `centre`.
    fn cube(centre: DVec3, half: f64) -> Shape {
        Shape::Box {
            centre,
            half: DVec3::splat(half),
            rotation: glam::DMat3::IDENTITY,
        }
    }

    /// A flat floor does not bend, a sphere of radius R spacings bends by
    /// about asin(1/R), and a box's edge, rounded by the field, bends by
    /// tens of degrees: the crease test leaves out the edge and keeps the
    /// rest.
    #[test]
    fn crease_angle_tells_an_edge_from_a_flat_or_round_surface() {
        let h = 1.0 / 32.0;
        let floor = solid(|p| p.y - 0.5);
        let x = DVec3::new(0.41, 0.5, 0.57);
        let n = -floor.density_gradient(x).normalize();
        assert!(n.dot(DVec3::Y) > 0.999, "{n}");
        let flat = crease_angle(&floor, x, n);
        assert!(flat < 1.0, "flat {flat}");

        let c = DVec3::splat(0.5);
        let r = 10.0 * h;
        let ball = solid(|p| {
            Shape::Sphere {
                centre: c,
                radius: r,
            }
            .sdf(p)
        });
        for d in [DVec3::Y, DVec3::new(1.0, 1.0, 0.3).normalize()] {
            let x = c + d * r;
            let n = -ball.density_gradient(x).normalize();
            let bend = crease_angle(&ball, x, n);
            let expect = (0.1f64).asin().to_degrees();
            assert!(
                (bend - expect).abs() < 3.0,
                "sphere {bend} against {expect}"
            );
            assert!(bend < 15.0);
        }

        // A box's edge along z at (0.65, 0.65), its faces x = 0.65 and y = 0.65.
        let cube = solid(|p| cube(c, 0.15).sdf(p));
        let x = DVec3::new(0.65, 0.65, 0.5);
        let n = -cube.density_gradient(x).normalize();
        let edge = crease_angle(&cube, x, n);
        assert!(edge > 30.0, "edge {edge}");
        // Three spacings from the edge the face is flat again.
        let x = DVec3::new(0.65 - 3.0 * h, 0.65, 0.5);
        let n = -cube.density_gradient(x).normalize();
        let face = crease_angle(&cube, x, n);
        assert!(face < 5.0, "face {face}");
    }

    /// Under the weight test, a view of a cube drops the points on its
    /// rounded edges, counted as creased, and keeps its faces; a
    /// `max_crease` of 180 and the gradient test keep every point.
    #[test]
    fn the_weight_test_leaves_out_a_cube_s_edges() {
        let c = DVec3::splat(0.5);
        let cube = solid(|p| cube(c, 0.2).sdf(p));
        let spec = crate::camera::CameraSpec {
            name: None,
            position: DVec3::new(1.6, 1.3, 1.45),
            look_at: c,
            up: DVec3::Y,
            fov_y: 35.0,
        };
        let frame = CameraFrame::new(&spec, 40, 40);
        let knobs = MarchKnobs::default();
        let view = march_view(&cube, &frame, &knobs);
        let run_with = |surface_test, max_crease, normals| {
            let rules = EnvEstimateKnobs {
                surface_test,
                max_crease,
                normals,
                ..EnvEstimateKnobs::default()
            };
            view_candidates(&cube, &frame, &view, 0, &knobs, &rules)
        };
        let run =
            |surface_test, max_crease| run_with(surface_test, max_crease, SurfaceNormals::AtPoint);
        let all = run(SurfaceTest::Weight, 180.0);
        let kept = run(SurfaceTest::Weight, 15.0);
        assert_eq!(all.creased, 0);
        assert!(all.points.len() > 200, "{}", all.points.len());
        assert!(kept.creased > 20, "{} creased", kept.creased);
        assert_eq!(kept.points.len() + kept.creased, all.points.len());
        // Faces are kept and edges left out: the distance to the nearest
        // edge of the point's closest point on the cube (the points lie
        // ahead of the faces, where this field's density starts to rise).
        let edge_distance = |x: DVec3| {
            let q = (x - c).clamp(DVec3::splat(-0.2), DVec3::splat(0.2));
            let mut d = (DVec3::splat(0.2) - q.abs()).to_array();
            d.sort_by(f64::total_cmp);
            d[1]
        };
        let h = 1.0 / 32.0;
        let near_edge = |v: &ViewPoints| {
            v.points
                .iter()
                .filter(|p| edge_distance(p.position) < h)
                .count()
        };
        let on_face = |v: &ViewPoints| {
            v.points
                .iter()
                .filter(|p| edge_distance(p.position) > 3.0 * h)
                .count()
        };
        assert_eq!(on_face(&kept), on_face(&all));
        assert!(on_face(&all) > 100);
        assert!(4 * near_edge(&kept) < near_edge(&all));
        // Read along the rays, a point within a spacing of an edge has the
        // normal of the face its ray enters, whose colour the pixel shows,
        // so the test has fewer to refuse: it still keeps every face's
        // point and leaves out most of the edges' (measured 66 of 192
        // kept).
        let along = run_with(SurfaceTest::Weight, 15.0, SurfaceNormals::AlongRay);
        assert_eq!(on_face(&along), on_face(&all));
        assert!(2 * near_edge(&along) < near_edge(&all));
        let gradient = run(SurfaceTest::Gradient, 15.0);
        assert_eq!(gradient.creased, 0);
    }

    /// `field` marched at every pixel centre of `frame`.
    fn march_view(field: &GridField, frame: &CameraFrame, knobs: &MarchKnobs) -> ViewImage {
        let (mut colour_opacity, mut depth) = (Vec::new(), Vec::new());
        for py in 0..frame.height {
            for px in 0..frame.width {
                let m =
                    crate::march::march_ray(field, &frame.pixel_ray(px, py), f64::INFINITY, knobs);
                let c = m.colour.as_vec3();
                colour_opacity.push([c.x, c.y, c.z, m.opacity as f32]);
                depth.push(m.depth as f32);
            }
        }
        ViewImage {
            width: frame.width,
            height: frame.height,
            colour_opacity,
            depth,
        }
    }

    /// A faint sheet floating in the field (optical depth 1.5 over a few
    /// scales, the haze a trainer leaves over an untextured floor) holds
    /// a pixel's weight near its expected depth as a surface does, but its
    /// density barely rises there: the weight test refuses it for its
    /// slope, and keeps a floor as soft as a trained one.
    #[test]
    fn the_weight_test_refuses_a_faint_sheet_and_keeps_a_soft_floor() {
        use crate::geometry::Aabb;
        use glam::UVec3;
        let n = 33;
        let h = 1.0 / (n - 1) as f64;
        let (width, optical_depth) = (1.5 * h, 1.5);
        let peak = optical_depth / (width * (2.0 * std::f64::consts::PI).sqrt());
        let sheet = GridField::new(
            UVec3::splat(n),
            Aabb::new(DVec3::ZERO, DVec3::ONE),
            (0..n * n * n)
                .map(|i| {
                    let y = ((i / n) % n) as f64 * h - 0.5;
                    let sigma = peak * (-0.5 * (y / width).powi(2)).exp();
                    [0.5, 0.5, 0.5, sigma as f32]
                })
                .collect(),
            4,
        );
        let floor = solid(|p| p.y - 0.5);
        let weight_test = EnvEstimateKnobs {
            surface_test: SurfaceTest::Weight,
            max_crease: 180.0,
            ..EnvEstimateKnobs::default()
        };
        let spec = crate::camera::CameraSpec {
            name: None,
            position: DVec3::new(0.5, 1.4, 0.75),
            look_at: DVec3::splat(0.5),
            up: DVec3::Z,
            fov_y: 20.0,
        };
        let frame = CameraFrame::new(&spec, 16, 16);
        let knobs = MarchKnobs::default();
        let unit = trained_surface_scale(&sheet);
        let candidates = |field: &GridField| {
            let view = march_view(field, &frame, &knobs);
            let covered = view.colour_opacity.iter().filter(|p| p[3] >= 0.5).count();
            let points = view_candidates(field, &frame, &view, 0, &knobs, &weight_test);
            (view, covered, points)
        };
        let (view, covered, points) = candidates(&sheet);
        assert_eq!(covered, 256);
        assert_eq!((points.points.len(), points.not_surface), (0, 256));
        // The sheet holds the centre pixel's weight like a surface: only
        // its slope fails.
        let centre = (8 * 16 + 8) as usize;
        let ray = frame.pixel_ray(8, 8);
        let depth = view.depth[centre] as f64 / view.colour_opacity[centre][3] as f64;
        let x = ray.at(depth);
        let (share, _) = surface_walk(
            &sheet,
            &ray,
            depth,
            SURFACE_HALF_WIDTH * unit,
            &knobs,
            false,
        );
        assert!(share >= MIN_SURFACE_SHARE, "{share}");
        let slope = surface_gradient(&sheet, x, SurfaceTest::Weight).length() * unit * unit;
        assert!(slope < 0.5 * MIN_TRAINED_GRADIENT, "{slope}");
        let (_, covered, points) = candidates(&floor);
        assert_eq!(covered, 256);
        assert_eq!(points.points.len(), 256);
    }

    /// A view of mostly dark surfaces does not make the lit ones light
    /// sources: the limit is one median over all the views; only what
    /// exceeds it is left out, and counted.
    #[test]
    fn light_sources_are_judged_against_all_the_views() {
        let dark = view(0, &[0.01, 0.01, 0.01, 0.5, 0.5]);
        let lit = view(1, &[0.4, 0.5, 0.5, 0.6, 9.0]);
        // Its own median (0.01) would leave out the dark view's lit points.
        assert!((emitter_limit([&dark], 8.0) - 0.08).abs() < 1e-6);
        let limit = emitter_limit([&dark, &lit], 8.0);
        assert!((limit - 8.0 * 0.5).abs() < 1e-6);
        let mut rng = Pcg32::new(1, 2);
        let drawn = draw_points(dark, limit, 10, &mut rng);
        assert_eq!((drawn.points.len(), drawn.emitters), (5, 0));
        let drawn = draw_points(lit.clone(), limit, 3, &mut rng);
        assert_eq!((drawn.points.len(), drawn.emitters), (3, 1));
        assert!(drawn.points.iter().all(|p| p.radiance.x < 1.0));
        assert_eq!(emitter_limit([], 8.0), 0.0);
        // Unseen points are passed over, and counted, until enough are kept.
        let seen = |p: &mut SurfacePoint| p.radiance.x != 0.5;
        let drawn = keep_seen(lit.clone(), 2, &mut rng, seen);
        assert_eq!(drawn.points.len(), 2);
        assert!(drawn.points.iter().all(|p| p.radiance.x != 0.5));
        assert!(drawn.unseen <= 2);
        let drawn = keep_seen(lit, 9, &mut rng, seen);
        assert_eq!((drawn.points.len(), drawn.unseen), (3, 2));
    }

    /// Few candidates, most on the light: the limit comes from every
    /// pixel the views saw, not from the candidates, so the light's points
    /// are still left out.
    #[test]
    fn a_light_among_few_candidates_is_still_a_light() {
        let mut view = view(0, &[30.0, 40.0, 50.0, 0.2]);
        view.covered_luminance = [0.2f32; 96].into_iter().chain([30.0, 40.0, 50.0]).collect();
        let limit = emitter_limit([&view], 8.0);
        assert!((limit - 1.6).abs() < 1e-6, "{limit}");
        let drawn = draw_points(view, limit, 10, &mut Pcg32::new(1, 3));
        assert_eq!((drawn.points.len(), drawn.emitters), (1, 3));
    }
}

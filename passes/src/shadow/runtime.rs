//! The per-frame shadow factors on the CPU, mirroring the shaders:
//! the self-shadow factors Γ_k (eq. 9; `shaders/shade/shade.wgsl`) and the
//! cast-shadow factor ρ (eq. 7–8; `shaders/shadow/cast.wgsl`).
//!
//! **ρ's weights.** Eq. 8 weighs each lobe L_k by its product with one SG
//! for the clamped cosine, L_k ⊗ cosine = (p'_k, λ'_k, μ'_k), and eq. 7's
//! denominator by the same products. That SG is 16 % above the cosine at
//! the normal, 25 % below it 56° away and 0.12 at the horizon, so the
//! weights misstate how the light divides between lobes: under ROOM's
//! ceiling bulb (overhead, 80 % of the floor's light) and its softbox (34°
//! above the floor), the softbox's share came out a third too small, and
//! the monkey's shadow of it too faint (docs/fidelity.md, fifteenth pass).
//! Each lobe is weighted by its irradiance on the point's plane as the
//! shading takes it, E_k ([`Sg64::diffuse_irradiance`], Hill's fit: within
//! 1.6 % from λ 5 up), and loses the share 1 − q(S(p'_k), λ'_k) of it that
//! f_h says the object hides (q is the visible fraction of the product
//! lobe's hemisphere energy): ρ = 1 − Σ_k E_k (1 − q_k) / Σ_k E_k, 1
//! exactly wherever the object blocks nothing. ρ is per colour channel.
//!
//! **Beyond the paper.** Each lobe's occlusion 1 − q is capped by the share
//! of its energy the object's bounding sphere can block ([`sphere_share`])
//! and, for a lobe the SSDF shadows, by its cosine-weighted light over the
//! sphere's cone ([`super::ConeQuadrature`]: far from the object, the
//! sphere's bound alone darkened CUPS' far field twice as much as Cycles),
//! and Γ_k is taken relative to the tangent plane's own visibility
//! ([`self_shadow_factors`]): measured against Blender Cycles, the plain
//! half-space model darkened the field by a few tenths of a per cent to a
//! few per cent everywhere and the object's unoccluded surfaces by ~30 %.
//! The direct lobes (too sharp for the fit) are shadowed by ray casting
//! against the mesh instead ([`super::direct`]). The object also sends
//! light back onto the field in place of what it blocks
//! ([`super::bounce`]): the paper's black occluder darkened the far field
//! by the share of its sky it covers.

use glam::DVec3;

use super::direct::{DirectOcclusion, DIRECT_RAY_OFFSET};
use super::fh::{hemisphere_integral, FhTable};
use crate::object::PlacedObject;
use crate::sg::Sg64;
use crate::ssdf::field::{OutsideMode, SsdfField};

/// S(d; x) for world-space `x` and unit `d` of the placed object.
pub fn world_ssdf(
    field: &SsdfField,
    placed: &PlacedObject,
    x: DVec3,
    d: DVec3,
    mode: OutsideMode,
) -> f64 {
    let m = placed.world_to_object();
    field.sample(
        m.transform_point3(x),
        m.transform_vector3(d).normalize(),
        mode,
    )
}

/// Γ_k for each lobe at world point `x` with unit normal `n`: the share of
/// the lobe's cosine-weighted light, L_k ⊗ cosine = (p', λ'), above its
/// own tangent plane that the object leaves visible,
/// Γ_k = clamp(q(S(p'; x), λ') / q(e, λ'), 0, 1), e = asin(n·p') the
/// elevation of p' above the tangent plane. Shading already integrates the
/// lobe against the clamped cosine, which removes the light below the
/// horizon; the half-space model's own q(e) at a point nothing else
/// occludes (S = e on a convex surface) would remove part of it again
/// (q(0, λ) ≈ 0.5–0.7 for broad lobes: a ~30 % darkening of unoccluded
/// surfaces), so Γ is the visibility relative to the tangent plane's. A
/// lobe (almost) wholly below the horizon (q(e) < 10⁻⁶) adds nothing to
/// the shading and keeps Γ = 1. The `direct` lobes (the last ones) take
/// Γ as the share of their rays above the tangent plane that leave the
/// surface clear, cast from [`DIRECT_RAY_OFFSET`] radii off it.
#[allow(clippy::too_many_arguments)]
pub fn self_shadow_factors(
    field: &SsdfField,
    placed: &PlacedObject,
    table: &FhTable,
    lobes: &[Sg64],
    x: DVec3,
    n: DVec3,
    mode: OutsideMode,
    direct: Option<DirectOcclusion<'_>>,
) -> Vec<f64> {
    let cosine = Sg64::clamped_cosine(n);
    let first = direct.map_or(lobes.len(), |d| d.first(lobes.len()));
    let lifted = x + n * (DIRECT_RAY_OFFSET * placed.sphere().1);
    lobes
        .iter()
        .enumerate()
        .map(|(k, g)| {
            if let Some(d) = direct.filter(|_| k >= first) {
                return d.clear_fraction(placed, lifted, k - first, Some(n));
            }
            let p = g.product(&cosine);
            let elevation = n.dot(p.direction).clamp(-1.0, 1.0).asin();
            let horizon = table.fraction(elevation as f32, p.sharpness as f32) as f64;
            if horizon < HORIZON_FLOOR {
                return 1.0;
            }
            let s = world_ssdf(field, placed, x, p.direction, mode);
            let q = table.fraction(s as f32, p.sharpness as f32) as f64;
            (q / horizon).clamp(0.0, 1.0)
        })
        .collect()
}

/// Below this tangent-plane visibility a lobe's light lies under the
/// horizon and is not attenuated (`SELF_SHADOW_HORIZON_FLOOR` in the
/// shader).
pub const HORIZON_FLOOR: f64 = 1e-6;

/// Below this share of a lobe's cosine-weighted energy that the object's
/// bounding sphere can block, the lobe is left unshadowed without reading
/// the SSDF (`CAST_SKIP_SHARE` in the shader).
pub const CAST_SKIP_SHARE: f64 = 1e-3;

/// Where the object can block less than this share of a point's light
/// (the sum of the lobes' bounds on what they can lose, over the
/// irradiance), the point is left unshadowed without the SSDF or any ray:
/// ρ is then off by at most this (`CAST_TOLERANCE` in the shader).
pub const CAST_TOLERANCE: f64 = 1e-3;

/// The largest share of the hemisphere energy of lobe `p` (a light lobe
/// times the cosine) that the sphere (`c`, `r`) can block seen from `x`:
/// the lobe's largest value over the sphere's cone times the cone's solid
/// angle 2π(1 − cos β), over the lobe's hemisphere integral. The half-space
/// model behind f_h takes the object for a whole half-space at the
/// SSDF's angle, however small it looks, so on its own it darkens points
/// far from the object by a few per cent; this bound lets the occlusion
/// vanish as the object's solid angle does. The cone is taken as covered
/// to `fill` + (1 − `fill`) sin²β, the mesh's mean share of its bounding
/// disc ([`super::ObjectReflectance::fill`]) far away, rising to all of
/// it at the sphere: ROOM's monkey fills 0.43 of its sphere's disc, and
/// with the whole sphere's bound ROOM's far field was 1.24 % darker where
/// Cycles' is 0.27 % brighter (the bounce on, docs/fidelity.md).
/// 1 from inside the sphere. One point's view of the sphere serves all
/// its lobes: [`SphereView`].
pub fn sphere_share(x: DVec3, p: &Sg64, c: DVec3, r: f64, fill: f64) -> f64 {
    SphereView::new(x, c, r, fill).share(p)
}

/// Whether the bounding sphere `(c, r)` seen from `x` lies at least a
/// quarter turn from `dir` (then S ≥ π/2 along it and nothing is blocked).
pub fn sphere_clear_of(x: DVec3, dir: DVec3, c: DVec3, r: f64) -> bool {
    SphereView::new(x, c, r, 0.0).clear_of(dir)
}

/// The object's bounding sphere seen from one point, what
/// [`sphere_share`] and [`sphere_clear_of`] need of it for any lobe: its
/// direction u, its angular radius β (as cos β, sin β = r/d), the cone's
/// solid angle 2π(1 − cos β) and the share of it the mesh covers. Per lobe
/// of axis p, γ = ∠(p, u) enters as cos(max(γ − β, 0)) = cos γ cos β +
/// sin γ sin β (1 where γ ≤ β): no inverse trigonometry per lobe. Mirrored
/// by `CastSphere` in `shaders/shadow/cast_body.wgsl`.
#[derive(Debug, Clone, Copy)]
pub struct SphereView {
    /// Unit direction from the point to the centre.
    pub u: DVec3,
    /// cos β.
    pub cos_beta: f64,
    /// sin β = r / distance.
    pub sin_beta: f64,
    /// Solid angle × covered share (0 inside).
    pub covered_solid: f64,
    /// Whether the point is inside the sphere.
    pub inside: bool,
}

impl SphereView {
    /// The sphere (`c`, `r`) from `x`, the mesh covering `fill` of its disc
    /// far away.
    pub fn new(x: DVec3, c: DVec3, r: f64, fill: f64) -> Self {
        let to = c - x;
        let dist = to.length();
        if dist <= r {
            return Self {
                u: DVec3::Y,
                cos_beta: 0.0,
                sin_beta: 1.0,
                covered_solid: 0.0,
                inside: true,
            };
        }
        let sin_beta = r / dist;
        let cos_beta = (1.0 - sin_beta * sin_beta).max(0.0).sqrt();
        let solid = 2.0 * std::f64::consts::PI * (1.0 - cos_beta);
        let covered = fill + (1.0 - fill) * sin_beta * sin_beta;
        Self {
            u: to / dist,
            cos_beta,
            sin_beta,
            covered_solid: solid * covered,
            inside: false,
        }
    }

    /// cos(max(γ − β, 0)) for a lobe of unit axis `dir`.
    fn cos_gap(&self, dir: DVec3) -> f64 {
        let cos_gamma = dir.dot(self.u).clamp(-1.0, 1.0);
        if cos_gamma >= self.cos_beta {
            return 1.0;
        }
        let sin_gamma = (1.0 - cos_gamma * cos_gamma).max(0.0).sqrt();
        cos_gamma * self.cos_beta + sin_gamma * self.sin_beta
    }

    /// [`sphere_share`] of lobe `p`.
    pub fn share(&self, p: &Sg64) -> f64 {
        if self.inside {
            return 1.0;
        }
        let peak = (p.sharpness * (self.cos_gap(p.direction) - 1.0)).exp();
        (peak * self.covered_solid / hemisphere_integral(p.sharpness)).min(1.0)
    }

    /// [`sphere_clear_of`] along `dir`: γ − β ≥ π/2.
    pub fn clear_of(&self, dir: DVec3) -> bool {
        !self.inside && self.cos_gap(dir) <= 0.0
    }
}

/// ρ (per channel) at world point `x` with unit normal `n` under `lobes`,
/// for a field point showing radiance `radiance`: 1 − ΔE / E, with ΔE the
/// lobes' light the object blocks and E their irradiance at `n` — but E no
/// less than π × `radiance`, what a surface of albedo ≤ 1 showing that
/// radiance must receive. The lobes are the light at the object; a point
/// far from it, lit by lights the object sees at a slant (a wall facing
/// the object under a ceiling bulb), receives more than they say, and
/// without the floor its shadow darkened ROOM's whole field by 4 %. Zero
/// `radiance` gives the paper's ratio. The `direct` lobes (the last ones)
/// are occluded by the share of their rays from `x` the mesh blocks; a
/// local light among them is weighed by its own light at `x` — its
/// sphere's lobe from `x`, times the field's transmittance towards it
/// and the share of its rays from above the plane
/// ([`DirectOcclusion::local_arrival`]) — and loses the share of those
/// the mesh blocks ([`DirectOcclusion::local_clear`]); each
/// other lobe loses no more than [`sphere_share`] of its light, nor more
/// than its light over the sphere's cone where [`super::ConeQuadrature`]
/// resolves it. The light the object sends back ([`super::bounce_parts`] with its
/// silhouette reflectance, `object`, its light from below `x`'s plane at
/// `x`'s ratio before it; zero fill and albedo give the paper's black
/// occluder) offsets the blocked light, never beyond it. Where the object
/// can block under [`CAST_TOLERANCE`] of the light, or does once the least
/// light it sends back ([`super::Bounce::least`]) is taken off, ρ = 1
/// without the SSDF or any ray.
#[allow(clippy::too_many_arguments)]
pub fn cast_shadow_factor(
    field: &SsdfField,
    placed: &PlacedObject,
    table: &FhTable,
    lobes: &[Sg64],
    x: DVec3,
    n: DVec3,
    radiance: DVec3,
    mode: OutsideMode,
    direct: Option<DirectOcclusion<'_>>,
    object: &super::ObjectReflectance,
) -> DVec3 {
    cast_shadow_factor_within(
        field,
        placed,
        table,
        lobes,
        (x, n, radiance),
        mode,
        direct,
        object,
        CAST_TOLERANCE,
    )
}

/// [`cast_shadow_factor`] at point, normal and radiance `at`, leaving a
/// point unshadowed where the object can block under `tolerance` of its
/// light (0: never).
#[allow(clippy::too_many_arguments)]
pub fn cast_shadow_factor_within(
    field: &SsdfField,
    placed: &PlacedObject,
    table: &FhTable,
    lobes: &[Sg64],
    (x, n, radiance): (DVec3, DVec3, DVec3),
    mode: OutsideMode,
    direct: Option<DirectOcclusion<'_>>,
    object: &super::ObjectReflectance,
    tolerance: f64,
) -> DVec3 {
    let cosine = Sg64::clamped_cosine(n);
    let (c, r) = placed.sphere();
    let view = SphereView::new(x, c, r, object.fill);
    let first = direct.map_or(lobes.len(), |d| d.first(lobes.len()));
    let first_local = direct.map_or(lobes.len(), |d| d.first_local(lobes.len()));
    // The lights as x sees them: a local light's lobe from x itself
    // ([`DirectOcclusion::local_lobe`]), the others as the object's
    // centre sees them.
    let seen: Vec<Sg64> = lobes
        .iter()
        .enumerate()
        .map(|(k, g)| match direct.filter(|_| k >= first_local) {
            Some(d) => d.local_lobe(k - first_local, x),
            None => *g,
        })
        .collect();
    let products: Vec<Sg64> = seen.iter().map(|g| g.product(&cosine)).collect();
    // Each lobe's light on x's plane (the module's doc: ρ's weights); a
    // local light's before the field takes any of it.
    let irradiance: Vec<DVec3> = seen.iter().map(|g| g.diffuse_irradiance(n)).collect();
    let cone = super::ConeQuadrature::new(&view, n);
    // The most lobe k can lose: E_k × the sphere's share, and for a lobe
    // shadowed through the SSDF no more than its light over the cone
    // (None where the object cannot block its light).
    let bound = |k: usize, p: &Sg64| -> Option<DVec3> {
        let share = view.share(p);
        if view.clear_of(p.direction) || share < CAST_SKIP_SHARE {
            return None;
        }
        let most = irradiance[k] * share;
        let over_cone = cone
            .as_ref()
            .filter(|_| k < first)
            .and_then(|c| c.blockable(&seen[k]));
        Some(over_cone.map_or(most, |c| most.min(c)))
    };
    // The irradiance, and the most the object can block of it: under
    // CAST_TOLERANCE of the light, ρ = 1. A local light's light at x needs
    // a ray through the field, so the test is first taken without it (a
    // lower bound of the light, floored at π × radiance) against the local
    // lights' whole spheres' bounds (an upper one), then again with it.
    let mut den: DVec3 = irradiance[..first_local].iter().sum();
    let bounds: Vec<Option<DVec3>> = products
        .iter()
        .enumerate()
        .map(|(k, p)| bound(k, p))
        .collect();
    let most: DVec3 = bounds.iter().flatten().sum();
    let floor = std::f64::consts::PI * radiance;
    let within = |most: DVec3, den: DVec3| {
        (most / den.max(floor).max(DVec3::splat(1e-300))).max_element() < tolerance
    };
    if within(most, den) {
        return DVec3::ONE;
    }
    // The light the object sends back offsets what it blocks, by at least
    // [`super::Bounce::least`] at the lowest ratio x can have: the object
    // darkens x by no more than `most` less that ([`super::Bounce::net`]).
    let back = super::bounce_parts(lobes, x, n, c, r, object.of(placed));
    let most = back.net(most, den.max(floor));
    if within(most, den) {
        return DVec3::ONE;
    }
    let mut arriving = vec![(0.0, 0.0); lobes.len()];
    if let Some(d) = direct {
        for (k, a) in arriving.iter_mut().enumerate().skip(first_local) {
            *a = d.local_arrival(k - first_local, x, n);
            den += irradiance[k] * a.0 * a.1;
        }
        if first_local < lobes.len() && within(most, den) {
            return DVec3::ONE;
        }
    }
    let mut blocked = DVec3::ZERO;
    for (k, p) in products.iter().enumerate() {
        if let Some(d) = direct.filter(|_| k >= first_local) {
            if bounds[k].is_some() {
                let (t, above) = arriving[k];
                let clear = d.local_clear(placed, k - first_local, x, n);
                blocked += irradiance[k] * t * (above - clear);
            }
            continue;
        }
        let Some(most) = bounds[k] else {
            continue;
        };
        blocked += if let Some(d) = direct.filter(|_| k >= first) {
            irradiance[k] * (1.0 - d.clear_fraction(placed, x, k - first, None))
        } else {
            let s = world_ssdf(field, placed, x, p.direction, mode);
            let q = table.fraction(s as f32, p.sharpness as f32) as f64;
            (irradiance[k] * (1.0 - q)).min(most)
        };
    }
    let total = den.max(floor);
    if blocked.max_element() > 0.0 {
        // x's own ratio before the bounce: the bounce's light from below
        // x's plane is the field around x, shadowed about as deeply
        // ([`super::bounce_parts`]).
        let ratio =
            (DVec3::ONE - blocked / total.max(DVec3::splat(1e-300))).clamp(DVec3::ZERO, DVec3::ONE);
        blocked = (blocked - back.at(ratio)).max(DVec3::ZERO);
    }
    DVec3::select(
        total.cmpgt(DVec3::ZERO),
        DVec3::ONE - blocked / total.max(DVec3::splat(1e-300)),
        DVec3::ONE,
    )
}

/// The field's surface normal at `x`: −∇σ
/// ([`GridField::density_gradient`](crate::field::GridField::density_gradient))
/// normalised (None where σ is flat).
pub fn field_normal(field: &crate::field::GridField, x: DVec3) -> Option<DVec3> {
    let g = field.density_gradient(x);
    (g.length() > 1e-12).then(|| -g.normalize())
}

/// Where the cast shadow is taken for one pixel ([`shadow_point`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowPoint {
    /// The field point.
    pub point: DVec3,
    /// The field's normal there.
    pub normal: DVec3,
    /// The share of the pixel's colour (per channel) gathered from the
    /// point on, which the shadow darkens: ρ' = 1 − (1 − ρ)·share.
    pub share: DVec3,
}

/// Where the cast shadow is taken for a pixel whose ray is `ray` and whose
/// march gave `colour` (Ĉ), `depth` (D̂) and `opacity` (Ô): at the expected
/// depth D̂/Ô, darkening all of the pixel; where that point lies off any
/// surface (the density is flat there: a table seen through glass puts
/// D̂/Ô between the two), at the depth where the ray's opacity reached 1/2
/// ([`crate::march::MarchResult::half_depth`]), darkening only the share
/// of the pixel's colour gathered from that surface on, two node spacings
/// before it (the glass's own light is not in the shadow). None: no
/// surface (ρ = 1). Mirrors `pixel_factor` in
/// `shaders/shadow/cast_body.wgsl`, which marches for the share only where
/// ρ at the point is under 1 (the pixel's ρ is 1 whatever the share).
pub fn shadow_point(
    field: &crate::field::GridField,
    ray: &crate::geometry::Ray,
    (colour, depth, opacity): (DVec3, f64, f64),
    march: &crate::march::MarchKnobs,
) -> Option<ShadowPoint> {
    if opacity <= 1e-4 {
        return None;
    }
    let p = ray.at(depth / opacity);
    if let Some(normal) = field_normal(field, p) {
        return Some(ShadowPoint {
            point: p,
            normal,
            share: DVec3::ONE,
        });
    }
    let half = crate::march::march_ray(field, ray, f64::INFINITY, march).half_depth;
    if half < 0.0 {
        return None;
    }
    let point = ray.at(half);
    let normal = field_normal(field, point)?;
    // What lies in front of the surface: up to two normal steps before it
    // (its density rises over about one).
    let h = field.spacing().min_element();
    let front = crate::march::march_ray(field, ray, (half - 2.0 * h).max(0.0), march).colour;
    let share = ((colour - front) / colour.max(DVec3::splat(1e-30))).clamp(DVec3::ZERO, DVec3::ONE);
    Some(ShadowPoint {
        point,
        normal,
        share,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::GridField;
    use crate::geometry::{Aabb, Ray};
    use crate::march::MarchKnobs;
    use glam::UVec3;

    /// The sphere's view from a point equals the inverse-trigonometric
    /// form it replaced: β = asin(r/d), γ = ∠(p, c − x), share from
    /// cos(max(γ − β, 0)), clear where γ − β ≥ π/2.
    #[test]
    fn sphere_view_matches_the_angles() {
        let mut rng = crate::rng::Pcg32::new(3, 9);
        let (c, r) = (DVec3::new(0.2, 0.5, -0.1), 0.3);
        for _ in 0..2000 {
            let x = c + crate::ssdf::tests::random_direction(&mut rng) * (4.0 * r * rng.next_f64());
            let p = Sg64 {
                direction: crate::ssdf::tests::random_direction(&mut rng),
                sharpness: 10f64.powf(4.0 * rng.next_f64() - 1.0),
                amplitude: DVec3::ONE,
            };
            let fill = rng.next_f64();
            let view = SphereView::new(x, c, r, fill);
            let to = c - x;
            let dist = to.length();
            if dist <= r {
                assert!(view.inside && view.share(&p) == 1.0 && !view.clear_of(p.direction));
                continue;
            }
            let beta = (r / dist).asin();
            let gamma = p.direction.dot(to / dist).clamp(-1.0, 1.0).acos();
            let peak = (p.sharpness * ((gamma - beta).max(0.0).cos() - 1.0)).exp();
            let solid = 4.0 * std::f64::consts::PI * (0.5 * beta).sin().powi(2);
            let covered = fill + (1.0 - fill) * (r / dist).powi(2);
            let share = (peak * solid * covered / hemisphere_integral(p.sharpness)).min(1.0);
            assert!((view.share(&p) - share).abs() <= 1e-9 * share.max(1e-300) + 1e-15);
            let clear = gamma - beta >= std::f64::consts::FRAC_PI_2;
            if (gamma - beta - std::f64::consts::FRAC_PI_2).abs() > 1e-9 {
                assert_eq!(view.clear_of(p.direction), clear);
            }
        }
    }

    /// Leaving unshadowed the points where the object can block under the
    /// tolerance of the light moves ρ by at most the tolerance, and only
    /// there: a sphere's exact SSDF (S = ∠(d, c − x) − asin(r/|c − x|)),
    /// a sun, a broad lobe and a sky, floor points out to 25 radii; and
    /// the same with the sun a local light, weighed at each point. Some
    /// points clear only once the least bounce is taken off (a black ball
    /// would not clear them).
    #[test]
    fn the_cast_tolerance_bounds_the_change() {
        use crate::probe::{DirectionMap, MapKind};
        let mesh = crate::ssdf::tests::bundled_mesh("metal-sphere.gltf");
        let placed = PlacedObject {
            name: "ball".into(),
            mesh: mesh.clone(),
            pose: Default::default(),
            material: Default::default(),
        };
        let (c, r) = placed.sphere();
        let grid = crate::ssdf::grid_for(&mesh, 8);
        let map = DirectionMap::new(MapKind::Octahedral, 16);
        let mut values = Vec::new();
        for i in 0..grid.count() {
            let x = grid.position_of(i);
            for t in 0..map.texels() as u32 {
                let d = map.direction(t % map.width, t / map.width);
                let to = c - x;
                let dist = to.length().max(1.0001 * r);
                let s = d.dot(to.normalize()).clamp(-1.0, 1.0).acos() - (r / dist).asin();
                values.push(s as f32);
            }
        }
        let samples = crate::ssdf::SsdfSamples {
            grid,
            directions: 16,
            values,
            object: mesh.geometry_key(),
            seconds: 0.0,
            blended: 0,
            kernel_seconds: Vec::new(),
        };
        let field = SsdfField::compress(&samples, 8);
        let table = FhTable::new();
        let object = super::super::ObjectReflectance::measure(&mesh);
        let lobes = [
            Sg64 {
                direction: DVec3::new(0.3, 1.0, 0.2).normalize(),
                sharpness: 120.0,
                amplitude: DVec3::splat(300.0),
            },
            Sg64 {
                direction: DVec3::new(-0.5, 0.6, 0.1).normalize(),
                sharpness: 3.0,
                amplitude: DVec3::new(2.0, 1.5, 1.0),
            },
            Sg64 {
                direction: DVec3::Y,
                sharpness: 0.5,
                amplitude: DVec3::new(0.3, 0.4, 0.6),
            },
        ];
        // The same light with the sun a local light above the ball (its
        // light weighed at each point, its shadow from rays to its disk):
        // the test is taken without it, then with it.
        let light = crate::lighting::LocalLight {
            centre: c + DVec3::new(0.9, 3.0, 0.6) * r,
            radius: 0.3 * r,
            emission: None,
        };
        let emission = crate::lighting::local::Emission {
            intensity: DVec3::splat(400.0) * r * r,
            radius: 0.3 * r,
        };
        let local = [(light, emission)];
        let object_scene = crate::ssdf::object_scene(&mesh);
        let occlusion = DirectOcclusion {
            scene: &object_scene,
            rays: &[],
            local: &local,
            local_side: 2,
            field: None,
        };
        // The same ball black: it sends nothing back, so only the bound
        // itself clears a point.
        let black = super::super::ObjectReflectance {
            albedo: DVec3::ZERO,
            ..object
        };
        let mut with_local = lobes.to_vec();
        with_local.rotate_left(1);
        for (lights, direct) in [(&lobes[..], None), (&with_local[..], Some(occlusion))] {
            let mut rng = crate::rng::Pcg32::new(5, 2);
            let (mut skipped, mut shadowed, mut by_bounce) = (0, 0, 0);
            for _ in 0..3000 {
                let [u, v] = rng.next_2d();
                let (rad, phi) = (r * (1.0 + 24.0 * u * u), 2.0 * std::f64::consts::PI * v);
                let x = DVec3::new(c.x + rad * phi.cos(), c.y - r, c.z + rad * phi.sin());
                let at = (x, DVec3::Y, DVec3::splat(0.2));
                let rho_of = |object, tol| {
                    cast_shadow_factor_within(
                        &field,
                        &placed,
                        &table,
                        lights,
                        at,
                        OutsideMode::Correct,
                        direct,
                        object,
                        tol,
                    )
                };
                let rho = |tol| rho_of(&object, tol);
                let (exact, within) = (rho(0.0), rho(CAST_TOLERANCE));
                if within == DVec3::ONE && exact != DVec3::ONE {
                    skipped += 1;
                    // Cleared only once the least bounce is taken off.
                    by_bounce += usize::from(rho_of(&black, CAST_TOLERANCE) != DVec3::ONE);
                    assert!(
                        (DVec3::ONE - exact).max_element() <= CAST_TOLERANCE,
                        "{x}: {exact}"
                    );
                } else {
                    assert_eq!(within, exact, "{x}");
                }
                if exact.max_element() < 0.9 {
                    shadowed += 1;
                }
            }
            assert!(
                skipped > 300 && shadowed > 20 && by_bounce > 20,
                "{skipped} skipped ({by_bounce} by the bounce), {shadowed} shadowed (local light: {})",
                direct.is_some()
            );
        }
    }

    /// A pane of thin glass (optical depth about 0.3 across) at y 0.6–0.64 above an
    /// opaque floor (y < 0.2), seen from above: D̂/Ô lies in the air between
    /// them, where the density is flat, so the shadow is taken where the
    /// opacity reached 1/2: on the floor. Without the pane, at D̂/Ô, on the
    /// floor too; with nothing below, on the pane or nowhere.
    #[test]
    fn a_shadow_seen_through_glass_falls_on_what_is_behind_it() {
        let n = 51u32;
        let bounds = Aabb {
            min: DVec3::ZERO,
            max: DVec3::ONE,
        };
        let field = |pane: bool, floor: bool| {
            let mut nodes = Vec::new();
            for _z in 0..n {
                for y in 0..n {
                    for _x in 0..n {
                        let y = y as f64 / (n - 1) as f64;
                        let sigma = if floor && y < 0.2 {
                            500.0
                        } else if pane && (0.6..=0.64).contains(&y) {
                            5.0
                        } else {
                            0.0
                        };
                        nodes.push([0.5, 0.5, 0.5, sigma as f32]);
                    }
                }
            }
            GridField::new(UVec3::splat(n), bounds, nodes, 4)
        };
        let knobs = MarchKnobs {
            samples_per_ray: 2048,
            termination: 1e-4,
            skip_empty: false,
        };
        let ray = Ray {
            origin: DVec3::new(0.5, 0.95, 0.5),
            dir: DVec3::NEG_Y,
        };
        let at = |f: &GridField| {
            let m = crate::march::march_ray(f, &ray, f64::INFINITY, &knobs);
            shadow_point(f, &ray, (m.colour, m.depth, m.opacity), &knobs)
                .map(|s| (s.point, s.normal, s.share))
        };
        let glass = field(true, true);
        let m = crate::march::march_ray(&glass, &ray, f64::INFINITY, &knobs);
        let expected = ray.at(m.depth / m.opacity);
        assert!(
            expected.y > 0.25 && expected.y < 0.58,
            "D̂/Ô at {expected}: not between the pane and the floor"
        );
        let (p, normal, share) = at(&glass).expect("a surface behind the glass");
        assert!((p.y - 0.2).abs() < 0.03, "{p}");
        assert!(normal.y > 0.9, "{normal}");
        // The pane's own light is not shadowed: pane and floor are the same
        // grey, so the floor's share of the pixel is the pane's
        // transmittance (about e^{−0.3}).
        let t = 1.0 - crate::march::march_ray(&glass, &ray, 0.5, &knobs).opacity;
        assert!(
            (share - DVec3::splat(t)).abs().max_element() < 0.02,
            "{share} vs {t}"
        );
        let (p, _, share) = at(&field(false, true)).expect("the bare floor");
        assert!((p.y - 0.2).abs() < 0.03, "{p}");
        assert_eq!(share, DVec3::ONE);
        // The pane alone never reaches half opacity: the shadow falls on the
        // pane where its density slopes, or nowhere.
        if let Some((p, _, _)) = at(&field(true, false)) {
            assert!((0.57..0.67).contains(&p.y), "{p}");
        }
    }
}

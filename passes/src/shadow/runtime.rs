//! The per-frame shadow factors on the CPU, mirroring the shaders:
//! the self-shadow factors Γ_k (eq. 9; `shaders/shade/shade.wgsl`) and the
//! cast-shadow factor ρ (eq. 7–8; `shaders/shadow/cast.wgsl`).
//!
//! **ρ's denominator.** Eq. 8 approximates the numerator by
//! Σ_k μ'_k f_h(S(p'_k), λ'_k) over the lobes L_k ⊗ cosine. With nothing in
//! the way (S ≥ π/2) that sum is Σ μ'_k f_h(π/2, λ'_k), the lobes'
//! hemisphere integrals, which fall short of the full irradiance
//! Σ μ'_k ∫G'_k by up to 10 % for the broadest products (λ' ≈ 2.3). Taking
//! eq. 7's denominator as the full inner product would darken every pixel
//! of the field that much; it is taken as Σ μ'_k f_h(π/2, λ'_k) instead —
//! the same normalisation as Γ_k in eq. 9 — so ρ = 1 exactly wherever the
//! object blocks nothing. ρ is per colour channel.
//!
//! **Beyond the paper.** Each lobe's occlusion 1 − q is capped by the share
//! of its energy the object's bounding sphere can block ([`sphere_share`]),
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
/// 1 from inside the sphere.
pub fn sphere_share(x: DVec3, p: &Sg64, c: DVec3, r: f64, fill: f64) -> f64 {
    let to = c - x;
    let dist = to.length();
    if dist <= r {
        return 1.0;
    }
    let sin2 = (r / dist).powi(2);
    let beta = (r / dist).asin();
    let gamma = crate::ssdf::silhouette::angle_between(p.direction, to / dist);
    let peak = (p.sharpness * ((gamma - beta).max(0.0).cos() - 1.0)).exp();
    let solid = 4.0 * std::f64::consts::PI * (0.5 * beta).sin().powi(2);
    let covered = fill + (1.0 - fill) * sin2;
    (peak * solid * covered / hemisphere_integral(p.sharpness)).min(1.0)
}

/// Whether the bounding sphere `(c, r)` seen from `x` lies at least a
/// quarter turn from `dir` (then S ≥ π/2 along it and nothing is blocked).
pub fn sphere_clear_of(x: DVec3, dir: DVec3, c: DVec3, r: f64) -> bool {
    let to = c - x;
    let dist = to.length();
    if dist <= r {
        return false;
    }
    let cone = (r / dist).asin();
    crate::ssdf::silhouette::angle_between(dir, to / dist) - cone >= std::f64::consts::FRAC_PI_2
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
/// are occluded by the share of their rays from `x` the mesh blocks. The
/// light the object sends back ([`super::bounce_irradiance`] with its
/// silhouette reflectance, `object`, its light from below `x`'s plane at
/// `x`'s ratio before it; zero fill and albedo give the paper's black
/// occluder) offsets the blocked light, never beyond it.
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
    let cosine = Sg64::clamped_cosine(n);
    let (c, r) = placed.sphere();
    let first = direct.map_or(lobes.len(), |d| d.first(lobes.len()));
    let (mut blocked, mut den) = (DVec3::ZERO, DVec3::ZERO);
    for (k, g) in lobes.iter().enumerate() {
        let p = g.product(&cosine);
        let w = p.amplitude * hemisphere_integral(p.sharpness);
        den += w;
        let share = sphere_share(x, &p, c, r, object.fill);
        let q = if sphere_clear_of(x, p.direction, c, r) || share < CAST_SKIP_SHARE {
            1.0
        } else if let Some(d) = direct.filter(|_| k >= first) {
            d.clear_fraction(placed, x, k - first, None)
        } else {
            let s = world_ssdf(field, placed, x, p.direction, mode);
            (table.fraction(s as f32, p.sharpness as f32) as f64).max(1.0 - share)
        };
        blocked += w * (1.0 - q);
    }
    let total = den.max(std::f64::consts::PI * radiance);
    if blocked.max_element() > 0.0 {
        // x's own ratio before the bounce: the bounce's light from below
        // x's plane is the field around x, shadowed about as deeply
        // ([`super::bounce_irradiance`]).
        let ratio =
            (DVec3::ONE - blocked / total.max(DVec3::splat(1e-300))).clamp(DVec3::ZERO, DVec3::ONE);
        let back = super::bounce_irradiance(lobes, x, n, c, r, object.of(placed), ratio);
        blocked = (blocked - back).max(DVec3::ZERO);
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
/// before it (the glass's own light is not in the shadow). None: no surface (ρ = 1). Mirrors `pixel_factor`
/// in `shaders/shadow/cast_body.wgsl`.
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

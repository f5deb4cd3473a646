//! The per-frame shadow factors on the CPU, mirroring the shaders:
//! the self-shadow factors Γ_k (eq. 9; `shaders/object/shade.wgsl`) and the
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

use glam::DVec3;

use super::fh::{hemisphere_integral, FhTable};
use super::field::{OutsideMode, SsdfField};
use super::gpu::world_to_object;
use crate::object::PlacedObject;
use crate::sg::Sg64;

/// S(d; x) for world-space `x` and unit `d` of the placed object.
pub fn world_ssdf(
    field: &SsdfField,
    placed: &PlacedObject,
    x: DVec3,
    d: DVec3,
    mode: OutsideMode,
) -> f64 {
    let m = world_to_object(placed);
    field.sample(
        m.transform_point3(x),
        m.transform_vector3(d).normalize(),
        mode,
    )
}

/// Γ_k = f_h(S(p_k; x), λ_k) / f_h(π/2, λ_k) for each lobe at world point `x`.
pub fn self_shadow_factors(
    field: &SsdfField,
    placed: &PlacedObject,
    table: &FhTable,
    lobes: &[Sg64],
    x: DVec3,
    mode: OutsideMode,
) -> Vec<f64> {
    lobes
        .iter()
        .map(|g| {
            let s = world_ssdf(field, placed, x, g.direction.normalize(), mode);
            table.fraction(s as f32, g.sharpness as f32) as f64
        })
        .collect()
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
    super::silhouette::angle_between(dir, to / dist) - cone >= std::f64::consts::FRAC_PI_2
}

/// ρ (per channel) at world point `x` with unit normal `n` under `lobes`.
pub fn cast_shadow_factor(
    field: &SsdfField,
    placed: &PlacedObject,
    table: &FhTable,
    lobes: &[Sg64],
    x: DVec3,
    n: DVec3,
    mode: OutsideMode,
) -> DVec3 {
    let cosine = Sg64::clamped_cosine(n);
    let (c, r) = placed.sphere();
    let (mut num, mut den) = (DVec3::ZERO, DVec3::ZERO);
    for g in lobes {
        let p = g.product(&cosine);
        let w = p.amplitude * hemisphere_integral(p.sharpness);
        den += w;
        let q = if sphere_clear_of(x, p.direction, c, r) {
            1.0
        } else {
            let s = world_ssdf(field, placed, x, p.direction, mode);
            table.fraction(s as f32, p.sharpness as f32) as f64
        };
        num += w * q;
    }
    DVec3::select(
        den.cmpgt(DVec3::ZERO),
        num / den.max(DVec3::splat(1e-300)),
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

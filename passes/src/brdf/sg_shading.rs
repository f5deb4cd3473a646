//! Shading as a sum of SG inner products (eq. 5), the f64 definition that
//! `shaders/brdf/sg_shading.wgsl` mirrors. For each light lobe k
//! (attenuated by Γ_k, the self-shadow factor; 1 until shadows exist):
//! - diffuse: (1 − m)·a/π · E_k(n), E_k the lobe's irradiance on the
//!   surface ([`Sg64::diffuse_irradiance`]: Hill's fitted curve, and the
//!   paper's ∫ G_k · S_cos(n), S_cos the clamped-cosine SG, for broad
//!   lobes; the paper's alone lit faces turned from a small light);
//! - specular: for each NDF lobe j, warped to the reflection direction
//!   r = 2(n·v)n − v with sharpness λ_j/(4 n·v), the product G_k ⊗ D_j is
//!   integrated and multiplied by Fresnel, Smith's visibility and the
//!   cosine, all evaluated at the product lobe's axis.

use glam::DVec3;

use super::disney::{fresnel, smith_visibility, SurfaceMaterial};
use super::NdfLobes;
use crate::sg::Sg64;

/// The smallest n·v the specular warp uses: at grazing views the warped
/// lobe's sharpness λ/(4 n·v) is capped instead of diverging.
pub const MIN_NV: f64 = 1e-3;

/// Diffuse and specular parts of the outgoing radiance.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ShadingTerms {
    /// The Lambertian part.
    pub diffuse: DVec3,
    /// The GGX part.
    pub specular: DVec3,
}

impl ShadingTerms {
    /// Their sum, the outgoing radiance.
    pub fn total(&self) -> DVec3 {
        self.diffuse + self.specular
    }
}

/// Outgoing radiance towards `v` (unit, towards the viewer) of a surface
/// with unit normal `n` and material `m`, lit by `light`; `attenuation`
/// holds Γ_k per lobe (empty: all 1).
pub fn shade_sg_split(
    light: &[Sg64],
    attenuation: &[f64],
    n: DVec3,
    v: DVec3,
    m: &SurfaceMaterial,
    ndf: &NdfLobes,
) -> ShadingTerms {
    let m = m.clamped();
    let alpha = m.alpha();
    let nv_true = n.dot(v);
    let nv = nv_true.max(MIN_NV);
    let r = (2.0 * nv_true * n - v).normalize_or(n);
    let ndf_sharpness = 2.0 / (alpha * alpha) / (4.0 * nv);
    let ndf_amplitude = 1.0 / (std::f64::consts::PI * alpha * alpha);
    let (f0, diffuse_colour) = (m.f0(), m.diffuse());
    let mut out = ShadingTerms::default();
    for (k, g) in light.iter().enumerate() {
        let gamma = attenuation.get(k).copied().unwrap_or(1.0);
        if gamma <= 0.0 {
            continue;
        }
        out.diffuse += gamma * diffuse_colour * g.diffuse_irradiance(n);
        for &(c, s) in &ndf.lobes {
            let d = Sg64 {
                direction: r,
                sharpness: s * ndf_sharpness,
                amplitude: DVec3::splat(c * ndf_amplitude),
            };
            let p = g.product(&d);
            let l = p.direction;
            let nl = n.dot(l);
            if nl <= 0.0 {
                continue;
            }
            let h = (l + v).normalize_or(n);
            let factor = fresnel(v.dot(h), f0) * (smith_visibility(nl, nv, alpha) * nl);
            out.specular += gamma * p.integral() * factor;
        }
    }
    out
}

/// [`shade_sg_split`]'s total with Γ_k = 1.
pub fn shade_sg(light: &[Sg64], n: DVec3, v: DVec3, m: &SurfaceMaterial, ndf: &NdfLobes) -> DVec3 {
    shade_sg_split(light, &[], n, v, m, ndf).total()
}

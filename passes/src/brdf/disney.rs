//! The simplified Disney BRDF of the paper (§4.4): a Lambertian diffuse
//! term (1 − m)·a/π plus a GGX microfacet specular term with α = r²,
//! Smith's separable masking-shadowing and Schlick's Fresnel with
//! F0 = mix(0.02, a, m). The paper fixes F0 = 0.02; we read that as the
//! dielectric F0 (Disney's `specular` parameter is dropped), so metallic
//! still tints the reflection by the base colour as glTF defines metallic.
//! `shaders/common/brdf.wgsl` mirrors every function here.

use std::f64::consts::PI;

use glam::DVec3;

/// Fresnel reflectance at normal incidence of every dielectric (paper §4.4).
pub const DIELECTRIC_F0: f64 = 0.02;

/// Roughness is clamped to at least this: α = r² = 0.01 gives an NDF lobe
/// of sharpness 2/α² = 2·10⁴, past which the SG math and an f32 G-buffer
/// gain nothing a 32×32 probe could show (and a delta-like lobe would make
/// the brute-force references meaningless).
pub const MIN_ROUGHNESS: f64 = 0.1;

/// Material parameters at one surface point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceMaterial {
    /// Base colour a (linear RGB in [0, 1]).
    pub albedo: DVec3,
    /// Perceptual roughness r in [MIN_ROUGHNESS, 1].
    pub roughness: f64,
    /// Metallic m in [0, 1].
    pub metallic: f64,
}

impl SurfaceMaterial {
    /// Clamps the parameters into their domains (NaN becomes the lower end).
    pub fn clamped(self) -> Self {
        let c = |x: f64, lo: f64, hi: f64| if x >= lo { x.min(hi) } else { lo };
        Self {
            albedo: DVec3::new(
                c(self.albedo.x, 0.0, 1.0),
                c(self.albedo.y, 0.0, 1.0),
                c(self.albedo.z, 0.0, 1.0),
            ),
            roughness: c(self.roughness, MIN_ROUGHNESS, 1.0),
            metallic: c(self.metallic, 0.0, 1.0),
        }
    }

    /// GGX α = r².
    pub fn alpha(&self) -> f64 {
        self.roughness * self.roughness
    }

    /// Fresnel reflectance at normal incidence.
    pub fn f0(&self) -> DVec3 {
        DVec3::splat(DIELECTRIC_F0).lerp(self.albedo, self.metallic)
    }

    /// The diffuse term (1 − m)·a/π.
    pub fn diffuse(&self) -> DVec3 {
        self.albedo * ((1.0 - self.metallic) / PI)
    }
}

/// GGX normal distribution D(h) for cos θ_h = `nh`.
pub fn ggx_d(nh: f64, alpha: f64) -> f64 {
    if nh <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let d = nh * nh * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// Smith's separable visibility V = G1(l)·G1(v) / (4 (n·l)(n·v)), written
/// so that grazing angles do not divide by zero.
pub fn smith_visibility(nl: f64, nv: f64, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let lambda = |x: f64| x + (a2 + (1.0 - a2) * x * x).sqrt();
    1.0 / (lambda(nl.max(0.0)) * lambda(nv.max(0.0)))
}

/// Schlick's Fresnel F0 + (1 − F0)(1 − v·h)⁵.
pub fn fresnel(vh: f64, f0: DVec3) -> DVec3 {
    let x = (1.0 - vh.clamp(0.0, 1.0)).powi(5);
    f0 + (DVec3::ONE - f0) * x
}

/// f_r(l, v) for unit normal `n`, view direction `v` (towards the viewer)
/// and light direction `l` (towards the light); zero below either horizon.
pub fn eval(m: &SurfaceMaterial, n: DVec3, v: DVec3, l: DVec3) -> DVec3 {
    let (nl, nv) = (n.dot(l), n.dot(v));
    if nl <= 0.0 || nv <= 0.0 {
        return DVec3::ZERO;
    }
    let h = (l + v).normalize();
    let alpha = m.alpha();
    let spec = ggx_d(n.dot(h), alpha) * smith_visibility(nl, nv, alpha);
    m.diffuse() + fresnel(v.dot(h), m.f0()) * spec
}

/// Probability of sampling the specular lobe rather than the cosine lobe.
fn specular_probability(m: &SurfaceMaterial) -> f64 {
    let s = m.f0().max_element();
    let d = m.diffuse().max_element() * PI;
    (s / (s + d).max(1e-12)).clamp(0.1, 0.9)
}

/// Samples a light direction ∝ a mix of the cosine lobe and GGX's
/// distribution of normals (reflected about the sampled half vector).
pub fn sample(m: &SurfaceMaterial, n: DVec3, v: DVec3, u: [f64; 3]) -> DVec3 {
    let (t, b) = n.any_orthonormal_pair();
    let phi = 2.0 * PI * u[2];
    if u[0] < specular_probability(m) {
        let a2 = m.alpha() * m.alpha();
        let cos2 = (1.0 - u[1]) / (1.0 + (a2 - 1.0) * u[1]);
        let (c, s) = (cos2.sqrt(), (1.0 - cos2).max(0.0).sqrt());
        let h = s * phi.cos() * t + s * phi.sin() * b + c * n;
        2.0 * v.dot(h) * h - v
    } else {
        let r = u[1].sqrt();
        let z = (1.0 - u[1]).max(0.0).sqrt();
        r * phi.cos() * t + r * phi.sin() * b + z * n
    }
}

/// The density of [`sample`] over solid angle.
pub fn pdf(m: &SurfaceMaterial, n: DVec3, v: DVec3, l: DVec3) -> f64 {
    let nl = n.dot(l);
    if nl <= 0.0 {
        return 0.0;
    }
    let h = (l + v).normalize_or_zero();
    let vh = v.dot(h);
    let spec = if vh > 0.0 {
        let nh = n.dot(h);
        ggx_d(nh, m.alpha()) * nh / (4.0 * vh)
    } else {
        0.0
    };
    let p = specular_probability(m);
    p * spec + (1.0 - p) * nl / PI
}

// Shading as a sum of SG inner products (eq. 5), mirroring
// passes/src/brdf/sg_shading.rs. The including shader defines where the
// lobes come from:
//   shading_light_count() -> u32, shading_light(k) -> Sg (as stored),
//   shading_fitted_count() -> u32  (the lobes from the start that are the
//     fit's; the rest are direct lobes),
//   shading_fitted_attenuation(k) -> f32  (a fitted lobe's Γ_k, the
//     self-shadow factor),
//   shading_diffuse_gain() -> vec3<f32>  (a factor on the fitted lobes'
//     diffuse light: the field's light at the point over the lobes', or 1),
//   shading_direct_attenuation(k) -> f32, shading_direct_lobe(k, g) -> Sg
//     (a direct lobe's Γ_k, and the lobe as this pixel sees it: g, or a
//     local light's lobe from the pixel's point),
//   shading_ndf_count() -> u32, shading_ndf(j) -> vec2<f32>  ((c_j, k_j)).
// The fitted and the direct lobes are summed in two loops, the same sum as
// one: on lavapipe the mere presence of the direct lobes' ray casting and
// march in the loop over every lobe cost DOG's shading 27 ms of 99 at
// 1280 × 720, though no fitted lobe takes that path (docs/benchmarks.md,
// issue 26's eighth pass).
#include "common/sg.wgsl"
#include "common/brdf.wgsl"

const SHADE_MIN_NV: f32 = 1e-3;

// What a pixel's shading needs of its surface and view, shared by its lobes.
struct ShadeSurface {
    n: vec3<f32>,
    v: vec3<f32>,
    r: vec3<f32>,
    nv: f32,
    alpha: f32,
    ndf_sharpness: f32,
    ndf_amplitude: f32,
    f0: vec3<f32>,
    diffuse_colour: vec3<f32>,
}

fn shade_surface(n: vec3<f32>, v: vec3<f32>, albedo_in: vec3<f32>, roughness_in: f32, metallic_in: f32) -> ShadeSurface {
    let albedo = clamp(albedo_in, vec3<f32>(0.0), vec3<f32>(1.0));
    let roughness = clamp(roughness_in, BRDF_MIN_ROUGHNESS, 1.0);
    let metallic = clamp(metallic_in, 0.0, 1.0);
    let alpha = roughness * roughness;
    let nv_true = dot(n, v);
    let nv = max(nv_true, SHADE_MIN_NV);
    let r_raw = 2.0 * nv_true * n - v;
    let r_len = length(r_raw);
    let r = select(n, r_raw / r_len, r_len > 0.0);
    return ShadeSurface(n, v, r, nv, alpha, 2.0 / (alpha * alpha) / (4.0 * nv), 1.0 / (BRDF_PI * alpha * alpha), brdf_f0(albedo, metallic), brdf_diffuse(albedo, metallic));
}

// Lobe g's light reflected towards s.v, times gamma (Γ_k), its diffuse
// part times `gain`.
fn shade_lobe(s: ShadeSurface, g: Sg, gamma: f32, gain: vec3<f32>) -> vec3<f32> {
    var out = gamma * s.diffuse_colour * sg_diffuse_irradiance(g, s.n) * gain;
    for (var j = 0u; j < shading_ndf_count(); j++) {
        let ck = shading_ndf(j);
        let d = Sg(s.r, ck.y * s.ndf_sharpness, vec3<f32>(ck.x * s.ndf_amplitude));
        let p = sg_product(g, d);
        let l = p.direction;
        let nl = dot(s.n, l);
        if nl <= 0.0 {
            continue;
        }
        let h_raw = l + s.v;
        let h_len = length(h_raw);
        let h = select(s.n, h_raw / h_len, h_len > 0.0);
        let factor = brdf_fresnel(dot(s.v, h), s.f0) * (brdf_smith_visibility(nl, s.nv, s.alpha) * nl);
        out += gamma * sg_integral(p) * factor;
    }
    return out;
}

fn shade_sg(n: vec3<f32>, v: vec3<f32>, albedo_in: vec3<f32>, roughness_in: f32, metallic_in: f32) -> vec3<f32> {
    let s = shade_surface(n, v, albedo_in, roughness_in, metallic_in);
    var sum = vec3<f32>(0.0);
    let fitted = shading_fitted_count();
    let gain = shading_diffuse_gain();
    for (var k = 0u; k < fitted; k++) {
        let gamma = shading_fitted_attenuation(k);
        if gamma <= 0.0 {
            continue;
        }
        sum += shade_lobe(s, shading_light(k), gamma, gain);
    }
    for (var k = fitted; k < shading_light_count(); k++) {
        let gamma = shading_direct_attenuation(k);
        if gamma <= 0.0 {
            continue;
        }
        sum += shade_lobe(s, shading_direct_lobe(k, shading_light(k)), gamma, vec3<f32>(1.0));
    }
    return sum;
}

// Shading as a sum of SG inner products (eq. 5), mirroring
// passes/src/brdf/sg_shading.rs. The including shader defines where the
// lobes come from:
//   shading_light_count() -> u32, shading_light(k) -> Sg,
//   shading_attenuation(k) -> f32   (Γ_k, the self-shadow factor),
//   shading_diffuse_gain(k) -> vec3<f32>  (a factor on lobe k's diffuse
//     light: the field's light at the point over the lobes', or 1),
//   shading_ndf_count() -> u32, shading_ndf(j) -> vec2<f32>  ((c_j, k_j)).
#include "common/sg.wgsl"
#include "common/brdf.wgsl"

const SHADE_MIN_NV: f32 = 1e-3;

fn shade_sg(n: vec3<f32>, v: vec3<f32>, albedo_in: vec3<f32>, roughness_in: f32, metallic_in: f32) -> vec3<f32> {
    let albedo = clamp(albedo_in, vec3<f32>(0.0), vec3<f32>(1.0));
    let roughness = clamp(roughness_in, BRDF_MIN_ROUGHNESS, 1.0);
    let metallic = clamp(metallic_in, 0.0, 1.0);
    let alpha = roughness * roughness;
    let nv_true = dot(n, v);
    let nv = max(nv_true, SHADE_MIN_NV);
    let r_raw = 2.0 * nv_true * n - v;
    let r_len = length(r_raw);
    let r = select(n, r_raw / r_len, r_len > 0.0);
    let ndf_sharpness = 2.0 / (alpha * alpha) / (4.0 * nv);
    let ndf_amplitude = 1.0 / (BRDF_PI * alpha * alpha);
    let f0 = brdf_f0(albedo, metallic);
    let diffuse_colour = brdf_diffuse(albedo, metallic);
    var diffuse = vec3<f32>(0.0);
    var specular = vec3<f32>(0.0);
    for (var k = 0u; k < shading_light_count(); k++) {
        let gamma = shading_attenuation(k);
        if gamma <= 0.0 {
            continue;
        }
        let g = shading_light(k);
        diffuse += gamma * diffuse_colour * sg_diffuse_irradiance(g, n) * shading_diffuse_gain(k);
        for (var j = 0u; j < shading_ndf_count(); j++) {
            let ck = shading_ndf(j);
            let d = Sg(r, ck.y * ndf_sharpness, vec3<f32>(ck.x * ndf_amplitude));
            let p = sg_product(g, d);
            let l = p.direction;
            let nl = dot(n, l);
            if nl <= 0.0 {
                continue;
            }
            let h_raw = l + v;
            let h_len = length(h_raw);
            let h = select(n, h_raw / h_len, h_len > 0.0);
            let factor = brdf_fresnel(dot(v, h), f0) * (brdf_smith_visibility(nl, nv, alpha) * nl);
            specular += gamma * sg_integral(p) * factor;
        }
    }
    return diffuse + specular;
}

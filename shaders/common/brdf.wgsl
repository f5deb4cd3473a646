// The simplified Disney BRDF's pieces, mirroring passes/src/brdf/disney.rs:
// Lambertian diffuse (1 − m)·a/π, GGX with α = r², Smith's separable
// visibility and Schlick's Fresnel with F0 = mix(0.02, a, m).

const BRDF_PI: f32 = 3.14159265358979;
const BRDF_DIELECTRIC_F0: f32 = 0.02;
const BRDF_MIN_ROUGHNESS: f32 = 0.1;

fn brdf_f0(albedo: vec3<f32>, metallic: f32) -> vec3<f32> {
    return mix(vec3<f32>(BRDF_DIELECTRIC_F0), albedo, metallic);
}

fn brdf_diffuse(albedo: vec3<f32>, metallic: f32) -> vec3<f32> {
    return albedo * ((1.0 - metallic) / BRDF_PI);
}

// V = G1(l) G1(v) / (4 (n·l)(n·v)).
fn brdf_smith_visibility(nl: f32, nv: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let l = max(nl, 0.0);
    let v = max(nv, 0.0);
    let gl = l + sqrt(a2 + (1.0 - a2) * l * l);
    let gv = v + sqrt(a2 + (1.0 - a2) * v * v);
    return 1.0 / (gl * gv);
}

fn brdf_fresnel(vh: f32, f0: vec3<f32>) -> vec3<f32> {
    let x = pow(1.0 - clamp(vh, 0.0, 1.0), 5.0);
    return f0 + (vec3<f32>(1.0) - f0) * x;
}

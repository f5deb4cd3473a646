// Spherical Gaussians G(v) = μ·exp(λ(v·p − 1)) (METHOD.md eq. 2): the f32
// mirror of passes/src/sg/math.rs (`Sg32`), formula for formula:
// v·p − 1 as −|v − p|²/2, 1 − e^{−x} and (1 − e^{−x})/x by their series
// below x = 0.25, and the product's exponent as −λ1λ2|p1 − p2|²/(λm + λ1 + λ2).
// Stored lobes are two vec4s: (p, λ), (μ, 0).

struct Sg {
    direction: vec3<f32>,
    sharpness: f32,
    amplitude: vec3<f32>,
}

const SG_PI: f32 = 3.14159265358979;
const SG_SERIES_BELOW: f32 = 0.25;
const SG_COSINE_SHARPNESS: f32 = 2.293;

// (1 − e^{−x})/x for x ≥ 0.
fn sg_one_minus_exp_neg_over_x(x: f32) -> f32 {
    if x < SG_SERIES_BELOW {
        var s = 1.0;
        for (var k = 12.0; k >= 2.0; k -= 1.0) {
            s = 1.0 - x / k * s;
        }
        return s;
    }
    return (1.0 - exp(-x)) / x;
}

// 1 − e^{−x} for x ≥ 0.
fn sg_one_minus_exp_neg(x: f32) -> f32 {
    return x * sg_one_minus_exp_neg_over_x(x);
}

// 2π(1 − e^{−2λ})/λ: the sphere integral of a unit-amplitude lobe.
fn sg_sphere_factor(sharpness: f32) -> f32 {
    return 4.0 * SG_PI * sg_one_minus_exp_neg_over_x(2.0 * sharpness);
}

// exp(λ(v·p − 1)) for unit v.
fn sg_weight(g: Sg, v: vec3<f32>) -> f32 {
    let d = v - g.direction;
    return exp(-0.5 * g.sharpness * dot(d, d));
}

fn sg_eval(g: Sg, v: vec3<f32>) -> vec3<f32> {
    return g.amplitude * sg_weight(g, v);
}

fn sg_integral(g: Sg) -> vec3<f32> {
    return g.amplitude * sg_sphere_factor(g.sharpness);
}

fn sg_product(a: Sg, b: Sg) -> Sg {
    let u = a.direction * a.sharpness + b.direction * b.sharpness;
    let lm = length(u);
    let sum = lm + a.sharpness + b.sharpness;
    var exponent = 0.0;
    if sum > 0.0 {
        let d = a.direction - b.direction;
        exponent = -a.sharpness * b.sharpness * dot(d, d) / sum;
    }
    var axis = a.direction;
    if lm > 0.0 {
        axis = u / lm;
    }
    return Sg(axis, lm, a.amplitude * b.amplitude * exp(exponent));
}

fn sg_inner_product(a: Sg, b: Sg) -> vec3<f32> {
    return sg_integral(sg_product(a, b));
}

// One lobe for max(v·n, 0) with the cosine's integral π.
fn sg_clamped_cosine(n: vec3<f32>) -> Sg {
    return Sg(n, SG_COSINE_SHARPNESS, vec3<f32>(SG_PI / sg_sphere_factor(SG_COSINE_SHARPNESS)));
}

// The irradiance ∫ G(v) max(v·n, 0) dv on a surface of unit normal n, by
// Stephen Hill's fitted curve (passes/src/sg/math.rs irradiance).
fn sg_irradiance(g: Sg, n: vec3<f32>) -> vec3<f32> {
    let mu_n = dot(g.direction, n);
    let lambda = max(g.sharpness, 1e-4);
    let c0 = 0.36;
    let c1 = 1.0 / (4.0 * c0);
    let eml = exp(-lambda);
    let em2l = eml * eml;
    let rl = 1.0 / lambda;
    let scale = 1.0 + 2.0 * em2l - rl;
    let bias = (eml - em2l) * rl - em2l;
    let x = sqrt(max(1.0 - scale, 0.0));
    let x0 = c0 * mu_n;
    let x1 = c1 * x;
    let sum = x0 + x1;
    var y = clamp(mu_n, 0.0, 1.0);
    if abs(x0) <= x1 {
        y = sum * sum / x;
    }
    let result = max(scale * y + bias, 0.0);
    return g.amplitude * (result * 2.0 * SG_PI / lambda);
}

// The irradiance as the shading takes it: the fit from λ 2 up, the
// clamped-cosine lobe's inner product below 1, blended between
// (passes/src/sg/math.rs diffuse_irradiance).
fn sg_diffuse_irradiance(g: Sg, n: vec3<f32>) -> vec3<f32> {
    let w = clamp(g.sharpness - 1.0, 0.0, 1.0);
    var lobe = vec3<f32>(0.0);
    if w < 1.0 {
        lobe = sg_inner_product(g, sg_clamped_cosine(n));
    }
    var fit = vec3<f32>(0.0);
    if w > 0.0 {
        fit = sg_irradiance(g, n);
    }
    return lobe * (1.0 - w) + fit * w;
}

// A lobe stored as (p, λ), (μ, 0).
fn sg_unpack(axis_sharpness: vec4<f32>, amplitude: vec4<f32>) -> Sg {
    return Sg(axis_sharpness.xyz, axis_sharpness.w, amplitude.xyz);
}

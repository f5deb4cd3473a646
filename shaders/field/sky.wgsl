// The four texels of a width × height sky (equirect: +Y up, φ = atan2(z, x)
// from texel 0's left edge, θ from +Y) that unit direction d reads
// bilinearly between texel centres, wrapping round in φ and held at the
// first and last rows in θ, and their weights.
// Mirrors passes/src/field/sky.rs sky_corners (and Sky::eval).
// Needs, for sky_radiance: the including shader's binding
// `sky: array<vec4<f32>>` (texel (r, g, b, _), row-major).

const SKY_PI: f32 = 3.14159265358979;

struct SkyCorners {
    index: vec4<u32>,
    weight: vec4<f32>,
}

fn sky_corners(size: vec2<u32>, d: vec3<f32>) -> SkyCorners {
    // atan2, not acos: acos(d.y) loses θ near the poles in f32.
    let theta = atan2(length(d.xz), d.y);
    // Straight up or down φ is 0 (atan2(0, 0) is not defined in WGSL).
    var phi = 0.0;
    if d.x != 0.0 || d.z != 0.0 {
        phi = atan2(d.z, d.x);
        if phi < 0.0 {
            phi += 2.0 * SKY_PI;
        }
    }
    // Held to [-0.5, width - 0.5] so that the index below is in range
    // whatever rounding gives.
    let u = clamp(phi / (2.0 * SKY_PI) * f32(size.x) - 0.5, -0.5, f32(size.x) - 0.5);
    let xf = floor(u);
    let fx = u - xf;
    let x0 = u32((i32(xf) + i32(size.x)) % i32(size.x));
    let x1 = (x0 + 1u) % size.x;
    let v = clamp(theta / SKY_PI * f32(size.y) - 0.5, 0.0, f32(size.y - 1u));
    let yf = floor(v);
    let fy = v - yf;
    let y0 = min(u32(yf), size.y - 1u);
    let y1 = min(y0 + 1u, size.y - 1u);
    var c: SkyCorners;
    c.index = vec4<u32>(y0 * size.x + x0, y0 * size.x + x1, y1 * size.x + x0, y1 * size.x + x1);
    c.weight = vec4<f32>((1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy);
    return c;
}

// Radiance from unit direction d of the size.x × size.y sky in `sky`.
fn sky_radiance(size: vec2<u32>, d: vec3<f32>) -> vec3<f32> {
    let c = sky_corners(size, d);
    return c.weight.x * sky[c.index.x].rgb + c.weight.y * sky[c.index.y].rgb
        + c.weight.z * sky[c.index.z].rgb + c.weight.w * sky[c.index.w].rgb;
}

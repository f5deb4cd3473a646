// The demo's analytic HDR sky and quad layout. Mirrored by
// tools/src/demo/pattern.rs, which the demo's GPU test checks pixels against.

// HDR sky at uv in [0,1]^2 (v down) and time t in seconds: a warm-to-blue
// gradient brightening upwards, with a small sun of radiance up to ~20.
fn demo_sky(uv: vec2<f32>, t: f32) -> vec3<f32> {
    let h = 1.0 - uv.y;
    let base = mix(vec3<f32>(0.9, 0.6, 0.4), vec3<f32>(0.2, 0.4, 1.0), h) * (1.0 + 3.0 * h);
    let sun = vec2<f32>(0.75 + 0.1 * sin(t), 0.25);
    let d = uv - sun;
    let glow = 20.0 * exp(-dot(d, d) / 0.002);
    return base + vec3<f32>(glow, glow * 0.9, glow * 0.7);
}

// Centre (clip-space x, y), half size, depth and colour of quad `i` (0: near
// warm quad, 1: far cool quad) at time t.
struct DemoQuad {
    center: vec2<f32>,
    half_size: f32,
    depth: f32,
    color: vec3<f32>,
}

fn demo_quad(i: u32, t: f32) -> DemoQuad {
    if (i == 0u) {
        return DemoQuad(vec2<f32>(-0.15 + 0.3 * sin(t), -0.1), 0.35, 0.25, vec3<f32>(4.0, 0.8, 0.2));
    }
    return DemoQuad(vec2<f32>(0.15, 0.1), 0.35, 0.75, vec3<f32>(0.2, 0.8, 3.0));
}

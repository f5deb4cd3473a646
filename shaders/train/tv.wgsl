// Total variation: each node's gradient of the squared differences to its
// six neighbours, Σ_nb (v − v_nb) per channel, weighted per channel group
// (colour, density) and added to the accumulated gradient before Adam
// (scaled by the inverse of Adam's gradient scale, so that it reaches Adam
// at its weight). Mirrors passes/src/train/tv.rs tv_gradient.

struct TvPush {
    resolution: vec3<u32>,
    count: u32,
    colour_weight: f32,
    density_weight: f32,
    unscale: f32,
    pad: u32,
}

var<immediate> pc: TvPush;
@group(0) @binding(0) var<storage, read> params: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> grad: array<vec4<f32>>;

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = id.x + 65535u * 64u * id.y;
    if n >= pc.count {
        return;
    }
    let r = pc.resolution;
    let i = vec3<u32>(n % r.x, (n / r.x) % r.y, n / (r.x * r.y));
    let v = params[n];
    var acc = vec4<f32>(0.0);
    for (var a = 0u; a < 3u; a++) {
        var e = vec3<u32>(0u);
        e[a] = 1u;
        if i[a] + 1u < r[a] {
            let m = i + e;
            acc += v - params[m.x + r.x * (m.y + r.y * m.z)];
        }
        if i[a] > 0u {
            let m = i - e;
            acc += v - params[m.x + r.x * (m.y + r.y * m.z)];
        }
    }
    let w = vec4<f32>(pc.colour_weight, pc.colour_weight, pc.colour_weight, pc.density_weight);
    grad[n] += 2.0 * w * acc * pc.unscale;
}

// Display mapping of linear HDR colour. Mirrors engine/src/tonemap.rs; the
// test `tonemap_gpu_matches_cpu` keeps the two in step.

// ACES filmic curve (Narkowicz's fit) for one channel; NaN and negatives -> 0.
fn aces_filmic(x: f32) -> f32 {
    // NaN fails every comparison, so it takes the 0 branch; clamping to the
    // f16 range keeps the rational curve from overflowing.
    var v = 0.0;
    if (x > 0.0) {
        v = min(x, 65504.0);
    }
    let num = v * (2.51 * v + 0.03);
    let den = v * (2.43 * v + 0.59) + 0.14;
    return clamp(num / den, 0.0, 1.0);
}

// The sRGB transfer function for a value in [0, 1].
fn srgb_encode(x: f32) -> f32 {
    let v = clamp(x, 0.0, 1.0);
    if (v <= 0.0031308) {
        return 12.92 * v;
    }
    return 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

fn aces_filmic3(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(aces_filmic(c.x), aces_filmic(c.y), aces_filmic(c.z));
}

fn srgb_encode3(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(srgb_encode(c.x), srgb_encode(c.y), srgb_encode(c.z));
}

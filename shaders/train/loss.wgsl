// The loss of a rendered pixel against what a photograph says of it, and its
// gradient with respect to the pixel. Mirrors passes/src/train/loss.rs:
// kind 0, a value (relative squared error, the denominator held, and never
// below RENDER_FLOOR_SHARE of the photograph's value); kind 1, a lower bound
// (the same, only below it); kind 2, a bracket (squared error of
// srgb(exposure × C) against the recorded encoded value, clipped at white
// only where the photograph recorded white; below white the sRGB curve
// continued past 1; less its rounding and weighed by bracket_scale, so that
// it reads as the linear loss would).

#include "common/tonemap.wgsl"

// A render darker than this share of its photograph is weighed as if it
// were at it (passes/src/train/loss.rs RENDER_FLOOR_SHARE).
const RENDER_FLOOR_SHARE: f32 = 0.0625;

// The least a bracket's code residual is divided by: two 8-bit levels
// (passes/src/train/loss.rs BRACKET_CODE_FLOOR).
const BRACKET_CODE_FLOOR: f32 = 0.00784313725;

struct PixelLoss {
    loss: f32,
    grad: vec3<f32>,
}

// srgb_encode (common/tonemap.wgsl) of v ≥ 0, its curve continued past
// 1, and its derivative.
fn train_srgb_encode(v: f32) -> vec2<f32> {
    if v <= 0.0031308 {
        return vec2<f32>(srgb_encode(v), 12.92);
    }
    return vec2<f32>(1.055 * pow(v, 1.0 / 2.4) - 0.055, 1.055 / 2.4 * pow(v, 1.0 / 2.4 - 1.0));
}

// Half an 8-bit level (passes/src/train/loss.rs BRACKET_HALF_LEVEL).
const BRACKET_HALF_LEVEL: f32 = 0.00196078431;

// A bracket's code residual less the rounding it may hold: 0 within half a
// level of the recorded code, beyond it the excess (passes/src/train/loss.rs
// quantised_residual).
fn quantised_residual(r: f32) -> f32 {
    return sign(r) * max(abs(r) - BRACKET_HALF_LEVEL, 0.0);
}

// sRGB-encoded [0, 1] to linear (passes/src/dataset/pixels.rs srgb_to_linear).
fn train_srgb_decode(c: f32) -> f32 {
    if c <= 0.04045 {
        return c / 12.92;
    }
    return pow((c + 0.055) / 1.055, 2.4);
}

// The held weight of a bracket's squared code residual: 1/σ², σ the code
// difference an error of the linear loss's denominator makes at the
// pixel's level, plus the code floor (passes/src/train/loss.rs
// bracket_scale).
fn bracket_scale(c: f32, encoded: f32, exposure: f32, epsilon: f32) -> f32 {
    let y = train_srgb_decode(min(encoded, 1.0)) / exposure;
    let level = max(max(c, RENDER_FLOOR_SHARE * y), 0.0);
    let sigma = train_srgb_encode(exposure * level).y * exposure * (level + epsilon) + BRACKET_CODE_FLOOR;
    return 1.0 / (sigma * sigma);
}

fn pixel_loss(c: vec3<f32>, kind: u32, target_value: vec3<f32>, exposure: f32, epsilon: f32) -> PixelLoss {
    var out = PixelLoss(0.0, vec3<f32>(0.0));
    for (var k = 0u; k < 3u; k++) {
        if kind == 2u {
            let v = exposure * c[k];
            // Recorded white: the render is clipped as the sensor was.
            let white = target_value[k] >= 1.0;
            let e = train_srgb_encode(select(max(v, 0.0), clamp(v, 0.0, 1.0), white));
            let r = quantised_residual(e.x - target_value[k]);
            let scale = bracket_scale(c[k], target_value[k], exposure, epsilon);
            out.loss += r * r * scale;
            if v > 0.0 && (v < 1.0 || !white) {
                out.grad[k] = 2.0 * r * e.y * exposure * scale;
            }
        } else {
            var r = c[k] - target_value[k];
            if kind == 1u {
                r = min(r, 0.0);
            }
            let d = max(max(c[k], RENDER_FLOOR_SHARE * target_value[k]), 0.0) + epsilon;
            let scale = 1.0 / (d * d);
            out.loss += r * r * scale;
            out.grad[k] = 2.0 * r * scale;
        }
    }
    return out;
}

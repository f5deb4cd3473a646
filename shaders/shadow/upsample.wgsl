// The cast shadow taken at one pixel of each s × s block brought to a
// finer image, of one pixel of each pc.out_scale × pc.out_scale block (1:
// full resolution; mirrors passes/src/shadow/upsample.rs upsample_level):
// each output pixel takes, at its block's source pixel, the blend of
// shadow/upsample_blend.wgsl, and `main_listed` appends each pixel it
// flags for shadow-refine (its index y·w + x of the output image) to the
// refinement's list (shadow/refine_append.wgsl). Each block's depth is
// read from the alpha of `low_shadow`, where cast-shadow (and this pass,
// for an output above full resolution) keeps its source pixel's. The
// last level may instead be blended as the image is composited
// (composite/composite.wgsl `main_upsampled`).

struct UpsamplePush {
    width: u32,
    height: u32,
    scale: u32,
    // Largest spread of the blocks' ρ a pixel blends (≥ 1: refine none).
    refine_spread: f32,
    // The output's scale (1: full resolution), below pc.scale.
    out_scale: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

var<immediate> pc: UpsamplePush;
@group(0) @binding(0) var field_colour: texture_2d<f32>;
@group(0) @binding(1) var field_depth: texture_2d<f32>;
@group(0) @binding(2) var low_shadow: texture_2d<f32>;
@group(0) @binding(3) var out_shadow: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var<storage, read_write> refine_count: atomic<u32>;
@group(0) @binding(5) var<storage, read_write> refine_list: array<u32>;
@group(0) @binding(6) var<storage, read_write> refine_args: array<atomic<u32>, 3>;

#include "shadow/upsample_blend.wgsl"
#include "shadow/refine_append.wgsl"

// The output image's width (upsample.rs low_size at pc.out_scale).
fn upsample_out_width() -> u32 {
    return (pc.width + pc.out_scale - 1u) / pc.out_scale;
}

// Whether output pixel `id` lies off the output image.
fn upsample_outside(id: vec2<u32>) -> bool {
    return id.x >= upsample_out_width() || id.y >= (pc.height + pc.out_scale - 1u) / pc.out_scale;
}

// Output pixel `id`'s value at its source pixel (upsample.rs
// source_pixel): ρ, and in alpha 1 at full resolution, else the source
// pixel's depth, which the next finer image weighs this one's blocks by.
fn upsample_out(id: vec2<u32>) -> Upsampled {
    let p = min(id * pc.out_scale + vec2<u32>(pc.out_scale / 2u), vec2<u32>(pc.width - 1u, pc.height - 1u));
    let u = upsample_pixel(p);
    textureStore(out_shadow, vec2<i32>(id), vec4<f32>(u.rho, select(u.depth, 1.0, pc.out_scale == 1u)));
    return u;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if upsample_outside(id.xy) {
        return;
    }
    upsample_out(id.xy);
}

@compute @workgroup_size(8, 8, 1)
fn main_listed(@builtin(global_invocation_id) id: vec3<u32>) {
    if upsample_outside(id.xy) {
        return;
    }
    let u = upsample_out(id.xy);
    if u.refine {
        refine_append(id.y * upsample_out_width() + id.x);
    }
}

// The cast shadow taken at one pixel of each s × s block brought to a
// finer image, of one pixel of each pc.out_scale × pc.out_scale block (1:
// full resolution; mirrors passes/src/shadow/upsample.rs upsample_level):
// each output pixel, at its block's source pixel, blends the four nearest
// blocks bilinearly, each weighted down as the depth at its source pixel
// departs from the pixel's (to zero at UPSAMPLE_DEPTH_FALLOFF relative),
// or takes the block nearest in depth where none lies on its surface;
// ρ = 1 where the field is empty. A pixel is flagged for shadow-refine (ρ
// taken exactly) where fewer than two of the corners it blends lie on its
// surface or their ρ spread by more than pc.refine_spread in some channel;
// `main_listed` also appends each flagged pixel's index (y·w + x of the
// output image) to refine_list, counting them in refine_count and their
// workgroups of REFINE_WORKGROUP in refine_args (shadow-refine's indirect
// dispatch, which so runs over those pixels alone). Each block's depth is
// read from the alpha of `low_shadow`, where cast-shadow (and this pass,
// for an output above full resolution) keeps its source pixel's.

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

#include "shadow/refine_list.wgsl"

const UPSAMPLE_DEPTH_FALLOFF: f32 = 0.05;

// Depth along the ray at full-resolution pixel p, or −1 where empty.
fn upsample_depth(p: vec2<u32>) -> f32 {
    let o = textureLoad(field_colour, vec2<i32>(p), 0).a;
    if o <= 1e-4 {
        return -1.0;
    }
    return textureLoad(field_depth, vec2<i32>(p), 0).r / o;
}

// ρ at full-resolution pixel p, whether shadow-refine takes it again, and
// p's depth (upsample_depth).
struct Upsampled {
    rho: vec3<f32>,
    refine: bool,
    depth: f32,
}

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
        let i = atomicAdd(&refine_count, 1u);
        refine_list[i] = id.y * upsample_out_width() + id.x;
        if i % REFINE_WORKGROUP == 0u {
            atomicAdd(&refine_args[0], 1u);
        }
    }
}

fn upsample_pixel(p: vec2<u32>) -> Upsampled {
    let id = vec3<u32>(p, 0u);
    let z = upsample_depth(id.xy);
    if z < 0.0 {
        return Upsampled(vec3<f32>(1.0), false, z);
    }
    let low = vec2<u32>((pc.width + pc.scale - 1u) / pc.scale, (pc.height + pc.scale - 1u) / pc.scale);
    let t = max((vec2<f32>(id.xy) + vec2<f32>(0.5)) / f32(pc.scale) - vec2<f32>(0.5), vec2<f32>(0.0));
    let i0 = min(vec2<u32>(floor(t)), low - vec2<u32>(1u));
    let i1 = min(i0 + vec2<u32>(1u), low - vec2<u32>(1u));
    let f = clamp(t - vec2<f32>(i0), vec2<f32>(0.0), vec2<f32>(1.0));
    var sum = vec3<f32>(0.0);
    var weight = 0.0;
    var nearest = vec3<f32>(1.0);
    var nearest_gap = 3.0e38;
    var lo = vec3<f32>(1.0);
    var hi = vec3<f32>(0.0);
    var on_surface = 0u;
    for (var k = 0u; k < 4u; k++) {
        let c = vec2<u32>(select(i0.x, i1.x, (k & 1u) != 0u), select(i0.y, i1.y, (k & 2u) != 0u));
        let wx = select(1.0 - f.x, f.x, (k & 1u) != 0u);
        let wy = select(1.0 - f.y, f.y, (k & 2u) != 0u);
        // ρ, and the depth at the block's source pixel (its upsample_depth,
        // which cast-shadow keeps in alpha: cast_body.wgsl
        // cast_source_depth).
        let block = textureLoad(low_shadow, vec2<i32>(c), 0);
        let zq = block.a;
        if zq < 0.0 {
            continue;
        }
        let rho = block.rgb;
        let gap = abs(zq - z) / max(z, 1e-30);
        if gap < nearest_gap {
            nearest = rho;
            nearest_gap = gap;
        }
        if gap < UPSAMPLE_DEPTH_FALLOFF {
            on_surface += 1u;
            lo = min(lo, rho);
            hi = max(hi, rho);
        }
        let w = wx * wy * max(1.0 - gap / UPSAMPLE_DEPTH_FALLOFF, 0.0);
        sum += w * rho;
        weight += w;
    }
    var rho = nearest;
    if weight > 1e-6 {
        rho = sum / weight;
    }
    let d = hi - lo;
    let refine = pc.refine_spread < 1.0 && (on_surface < 2u || max(d.x, max(d.y, d.z)) > pc.refine_spread);
    return Upsampled(rho, refine, z);
}

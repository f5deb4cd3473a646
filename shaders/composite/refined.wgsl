// composite-refined: the pixels composite's `main_upsampled` (or
// `main_field_upsampled`) listed for shadow-refine composited again with
// the ρ the refinement took exactly there (`refined`), in place in the
// composited image; every other pixel keeps what composite wrote. `main`
// has an object layer, `main_field` the shadowed field alone.
#include "composite/over.wgsl"
#include "composite/push.wgsl"
#include "shadow/refine_list.wgsl"

var<immediate> pc: CompositePush;
@group(0) @binding(0) var field_colour: texture_2d<f32>;
@group(0) @binding(1) var object_colour: texture_2d<f32>;
@group(0) @binding(2) var refined: texture_2d<f32>;
@group(0) @binding(3) var<storage, read> refine_count: u32;
@group(0) @binding(4) var<storage, read> refine_list: array<u32>;
@group(0) @binding(5) var recomposited: texture_storage_2d<rgba32float, read_write>;

#include "composite/object_layer.wgsl"

// The listed pixel of invocation `i`, or (−1, −1) past the list.
fn refined_pixel(i: u32) -> vec2<i32> {
    if i >= refine_count {
        return vec2<i32>(-1);
    }
    let index = refine_list[i];
    return vec2<i32>(i32(index % pc.width), i32(index / pc.width));
}

@compute @workgroup_size(REFINE_WORKGROUP, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = refined_pixel(id.x);
    if p.x < 0 {
        return;
    }
    let field = composite_shade_field(textureLoad(field_colour, p, 0), textureLoad(refined, p, 0).rgb);
    textureStore(recomposited, p, composite_layer(field, composite_object(p), pc.object_front != 0u));
}

@compute @workgroup_size(REFINE_WORKGROUP, 1, 1)
fn main_field(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = refined_pixel(id.x);
    if p.x < 0 {
        return;
    }
    textureStore(recomposited, p, composite_shade_field(textureLoad(field_colour, p, 0), textureLoad(refined, p, 0).rgb));
}

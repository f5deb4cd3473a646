// Compositing (eq. 6): I = I_c + (1 − I_α)·I_v, the field (clipped at the
// object, premultiplied) over the object's radiance; `main_shadowed` first
// multiplies the field's colour by the cast-shadow factor ρ (eq. 7), which
// darkens only the field's part of the pixel. With `object_front` set the
// object is drawn over the unclipped field instead (occlusion turned off);
// `main_field_shadowed` is the shadowed field alone (no object on screen).
// `main_upsampled` and `main_field_upsampled` take ρ from the last level
// of the cast shadow's upsampling instead (`low_shadow`, blocks of
// pc.scale pixels), blended here as shadow-upsample would blend it
// (shadow/upsample_blend.wgsl), so that ρ at full resolution is never
// written out; a pixel the blend flags is appended to the refinement's
// list and its blended ρ kept in `refined`, where shadow-refine takes it
// exactly and composite-refined (composite/refined.wgsl) composites it
// again.
#include "composite/over.wgsl"
#include "composite/push.wgsl"

var<immediate> pc: CompositePush;
@group(0) @binding(0) var field_colour: texture_2d<f32>;
@group(0) @binding(1) var object_colour: texture_2d<f32>;
@group(0) @binding(2) var out_colour: texture_storage_2d<rgba32float, write>;
@group(0) @binding(3) var shadow: texture_2d<f32>;
@group(0) @binding(4) var field_depth: texture_2d<f32>;
@group(0) @binding(5) var low_shadow: texture_2d<f32>;
@group(0) @binding(6) var<storage, read_write> refine_count: atomic<u32>;
@group(0) @binding(7) var<storage, read_write> refine_list: array<u32>;
@group(0) @binding(8) var<storage, read_write> refine_args: array<atomic<u32>, 3>;
@group(0) @binding(9) var refined: texture_storage_2d<rgba32float, write>;

#include "composite/object_layer.wgsl"

#include "shadow/upsample_blend.wgsl"
#include "shadow/refine_append.wgsl"

fn layer(field: vec4<f32>, object: vec4<f32>) -> vec4<f32> {
    return composite_layer(field, object, pc.object_front != 0u);
}

// Whether invocation `id` lies off the image.
fn composite_outside(id: vec3<u32>) -> bool {
    return id.x >= pc.width || id.y >= pc.height;
}

// ρ at pixel `p`, whose field colour is `field`, blended from
// `low_shadow`, and whether the blend flags it for shadow-refine.
fn composite_blended(p: vec2<u32>, field: vec4<f32>) -> Upsampled {
    return upsample_blend(p, upsample_depth_of(field.a, textureLoad(field_depth, vec2<i32>(p), 0).r));
}

// `u` (composite_blended at p), the pixel listed for shadow-refine with
// its blended ρ kept in `refined` where the blend flags it.
fn composite_listed(p: vec2<u32>, u: Upsampled) -> vec3<f32> {
    if u.refine {
        refine_append(p.y * pc.width + p.x);
        textureStore(refined, vec2<i32>(p), vec4<f32>(u.rho, 1.0));
    }
    return u.rho;
}

// The field's colour at invocation `id`'s pixel.
fn composite_field(id: vec3<u32>) -> vec4<f32> {
    return textureLoad(field_colour, vec2<i32>(id.xy), 0);
}

// Writes invocation `id`'s pixel: `field` darkened by ρ, over the object
// layer (as `layer` orders them).
fn composite_store(id: vec3<u32>, field: vec4<f32>, rho: vec3<f32>) {
    let p = vec2<i32>(id.xy);
    textureStore(out_colour, p, layer(composite_shade_field(field, rho), composite_object(p)));
}

// Writes invocation `id`'s pixel: `field` darkened by ρ, no object layer.
fn composite_store_field(id: vec3<u32>, field: vec4<f32>, rho: vec3<f32>) {
    textureStore(out_colour, vec2<i32>(id.xy), composite_shade_field(field, rho));
}

// ρ at invocation `id`'s pixel from the full-resolution `shadow`.
fn composite_shadow(id: vec3<u32>) -> vec3<f32> {
    return textureLoad(shadow, vec2<i32>(id.xy), 0).rgb;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if !composite_outside(id) {
        composite_store(id, composite_field(id), vec3<f32>(1.0));
    }
}

@compute @workgroup_size(8, 8, 1)
fn main_shadowed(@builtin(global_invocation_id) id: vec3<u32>) {
    if !composite_outside(id) {
        composite_store(id, composite_field(id), composite_shadow(id));
    }
}

@compute @workgroup_size(8, 8, 1)
fn main_field_shadowed(@builtin(global_invocation_id) id: vec3<u32>) {
    if !composite_outside(id) {
        composite_store_field(id, composite_field(id), composite_shadow(id));
    }
}

// The four entry points blending the last level: with an object layer
// or the field alone, and without or with a refinement list (`_listed`).
@compute @workgroup_size(8, 8, 1)
fn main_upsampled(@builtin(global_invocation_id) id: vec3<u32>) {
    if !composite_outside(id) {
        let field = composite_field(id);
        composite_store(id, field, composite_blended(id.xy, field).rho);
    }
}

@compute @workgroup_size(8, 8, 1)
fn main_upsampled_listed(@builtin(global_invocation_id) id: vec3<u32>) {
    if !composite_outside(id) {
        let field = composite_field(id);
        composite_store(id, field, composite_listed(id.xy, composite_blended(id.xy, field)));
    }
}

@compute @workgroup_size(8, 8, 1)
fn main_field_upsampled(@builtin(global_invocation_id) id: vec3<u32>) {
    if !composite_outside(id) {
        let field = composite_field(id);
        composite_store_field(id, field, composite_blended(id.xy, field).rho);
    }
}

@compute @workgroup_size(8, 8, 1)
fn main_field_upsampled_listed(@builtin(global_invocation_id) id: vec3<u32>) {
    if !composite_outside(id) {
        let field = composite_field(id);
        composite_store_field(id, field, composite_listed(id.xy, composite_blended(id.xy, field)));
    }
}

// Compositing (eq. 6): I = I_c + (1 − I_α)·I_v, the field (clipped at the
// object, premultiplied) over the object's radiance; `main_shadowed` first
// multiplies the field's colour by the cast-shadow factor ρ (eq. 7), which
// darkens only the field's part of the pixel. With `object_front` set the
// object is drawn over the unclipped field instead (occlusion turned off);
// `main_field_shadowed` is the shadowed field alone (no object on screen).
#include "composite/over.wgsl"

struct CompositePush {
    width: u32,
    height: u32,
    object_front: u32,
}

fn layer(field: vec4<f32>, object: vec4<f32>) -> vec4<f32> {
    if pc.object_front != 0u {
        return composite_over(object, field);
    }
    return composite_over(field, object);
}

var<immediate> pc: CompositePush;
@group(0) @binding(0) var field_colour: texture_2d<f32>;
@group(0) @binding(1) var object_colour: texture_2d<f32>;
@group(0) @binding(2) var out_colour: texture_storage_2d<rgba32float, write>;
@group(0) @binding(3) var shadow: texture_2d<f32>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= pc.width || id.y >= pc.height {
        return;
    }
    let p = vec2<i32>(id.xy);
    textureStore(out_colour, p, layer(textureLoad(field_colour, p, 0), textureLoad(object_colour, p, 0)));
}

@compute @workgroup_size(8, 8, 1)
fn main_shadowed(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= pc.width || id.y >= pc.height {
        return;
    }
    let p = vec2<i32>(id.xy);
    let field = composite_shade_field(textureLoad(field_colour, p, 0), textureLoad(shadow, p, 0).rgb);
    textureStore(out_colour, p, layer(field, textureLoad(object_colour, p, 0)));
}

@compute @workgroup_size(8, 8, 1)
fn main_field_shadowed(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= pc.width || id.y >= pc.height {
        return;
    }
    let p = vec2<i32>(id.xy);
    textureStore(out_colour, p, composite_shade_field(textureLoad(field_colour, p, 0), textureLoad(shadow, p, 0).rgb));
}

// The body of the object's SG shading pass (eq. 5) over the G-buffer: one
// dispatch per object, shading the pixels holding that object with its
// fitted lobes.
// Output: the object's radiance I_v with coverage in alpha. The including
// shader (shade/shade.wgsl, shade/shade_self_shadow.wgsl,
// shade/shade_self_shadow_direct.wgsl) defines the entry point, calling
// shade_pixel, shading_prepare(x, n) (called with the pixel's world-space
// surface point and normal before shading), and the hooks of
// brdf/sg_shading.wgsl but the light and NDF lobes, which this file reads.
// A dispatch covers the 8 × 8 tiles from pc.tile_origin on
// (shade_dispatched_pixel): the tiles the object's bounding sphere can
// cover, or the whole image; the image is cleared first (shade.wgsl
// `clear`), so pixels no dispatch covers read zero.
// Bindings 0-2 are left to the field (field/grid.wgsl) for the variant
// that marches it.
#include "common/camera.wgsl"
#include "brdf/sg_shading.wgsl"

struct ShadePush {
    camera: CameraRays,
    // The object's index as the G-buffer's distance_id holds it.
    object_index: f32,
    write_empty: u32,
    // Lobes of `light_lobes` that light the object (from its start).
    light_count: u32,
    // How many of them, at the end, are direct lobes (too sharp for the
    // fit), and rays per lobe (read by shade_self_shadow_direct.wgsl).
    direct_lobes: u32,
    direct_rays: u32,
    // How many of the direct lobes, at the end, are local lights, the side
    // of their visibility rays, and the field's march step and termination
    // (read by shade_self_shadow_direct.wgsl).
    local_count: u32,
    local_side: u32,
    march_step: f32,
    march_termination: f32,
    // Side of the field-light rays per tile (0: off) and the lobes of L_env
    // they see past the field (read by shade/field_light.wgsl).
    field_side: u32,
    env_count: u32,
    // The first 8 × 8 tile a dispatch covers, x | y << 16: a self-shadowed
    // object's dispatches (and its field light's gain) cover the tiles its
    // bounding sphere can cover; 0 where a dispatch covers the image. The
    // field light's gain pass counts it in its own tiles of 8 ·
    // field_scale pixels.
    tile_origin: u32,
    // The field light's tiles are this many times 8 pixels a side, each
    // invocation of the gain pass taking its square of pixels (read by
    // shade/field_light.wgsl).
    field_scale: u32,
    // The object's field light tiles: the first (x | y << 16, in those
    // tiles) and how many (columns | rows << 16; read by
    // shade/field_light.wgsl).
    field_origin: u32,
    field_tiles: u32,
    pad0: u32,
}

var<immediate> pc: ShadePush;
@group(0) @binding(16) var normal_roughness: texture_2d<f32>;
@group(0) @binding(17) var albedo_metallic: texture_2d<f32>;
@group(0) @binding(18) var distance_id: texture_2d<f32>;
// The object's lobes as (p, λ), (μ, 0): the fit's current M (then its
// candidates, unread) or the fitted and the direct lobes
// (passes/src/lighting: LightLobes); the first pc.light_count are the light.
@group(0) @binding(19) var<storage, read> light_lobes: array<vec4<f32>>;
// (c_j, k_j) of the NDF mixture (passes/src/brdf/ndf_lobes.rs).
@group(0) @binding(20) var<storage, read> ndf_lobes: array<vec2<f32>>;
@group(0) @binding(21) var out_object: texture_storage_2d<rgba32float, write>;

fn shading_light_count() -> u32 {
    return pc.light_count;
}

fn shading_light(k: u32) -> Sg {
    return sg_unpack(light_lobes[2u * k], light_lobes[2u * k + 1u]);
}

fn shading_ndf_count() -> u32 {
    return arrayLength(&ndf_lobes);
}

fn shading_ndf(j: u32) -> vec2<f32> {
    return ndf_lobes[j];
}

// The pixel invocation `id` of a dispatch takes: the dispatch covers the
// tiles from pc.tile_origin on (an object's own, or from the first).
fn shade_dispatched_pixel(id: vec3<u32>) -> vec3<u32> {
    return id + vec3<u32>(pc.tile_origin & 0xffffu, pc.tile_origin >> 16u, 0u) * 8u;
}

// Whether pixel `id` holds this dispatch's object; where no object is, the
// first dispatch writes zero.
fn shade_owns(id: vec3<u32>) -> bool {
    if camera_outside(pc.camera, id.xy) {
        return false;
    }
    let pixel = vec2<i32>(id.xy);
    let object = textureLoad(distance_id, pixel, 0).g;
    if object != pc.object_index {
        if object < 0.0 && pc.write_empty != 0u {
            textureStore(out_object, pixel, vec4<f32>(0.0));
        }
        return false;
    }
    return true;
}

fn shade_pixel(id: vec3<u32>) {
    if !shade_owns(id) {
        return;
    }
    let pixel = vec2<i32>(id.xy);
    let hit = textureLoad(distance_id, pixel, 0);
    let nr = textureLoad(normal_roughness, pixel, 0);
    let am = textureLoad(albedo_metallic, pixel, 0);
    let dir = camera_ray_dir(pc.camera, vec2<f32>(id.xy) + vec2<f32>(0.5));
    let n = normalize(nr.xyz);
    shading_prepare(pc.camera.origin + dir * hit.r, n);
    let radiance = shade_sg(n, -dir, am.rgb, nr.w, am.a);
    textureStore(out_object, pixel, vec4<f32>(max(radiance, vec3<f32>(0.0)), 1.0));
}

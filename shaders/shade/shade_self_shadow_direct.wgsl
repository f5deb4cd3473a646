// The object's SG shading pass (eq. 5) with self-shadows (eq. 9) where the
// light ends in direct lobes: the lobes of L_env too sharp for the fit
// take Γ as the share of their rays above the tangent plane that leave the
// surface clear, cast against the object's mesh from DIRECT_RAY_OFFSET
// radii off it (shadow/direct_rays.wgsl); the local lights, last, are
// lobes from the pixel's own point towards their spheres
// (lighting/local_light.wgsl), with Γ from their rays (local_visibility);
// the other lobes take Γ from the SSDF. With pc.field_side > 0 the fitted
// lobes' diffuse light is scaled by the field's light at the point
// (shade/field_light.wgsl): the entry point `field_light_tables` writes
// each tile's table (pass `object-field-light`, before this one), and
// `main` blends the tables around each pixel. They are two passes because
// the tile's rays are shared through workgroup memory, and a shader with
// workgroup barriers runs every invocation as a coroutine on lavapipe:
// with the gather in `main`, DOG's shading took 60 ms at 320 × 180, and
// 20 ms with the gain apart (plus 1.5 ms for it, over the ball's tiles
// alone; docs/benchmarks.md, issue 26's fourth pass). Mirrors
// passes/src/shadow/runtime.rs self_shadow_factors and
// passes/src/lighting/local.rs.
#include "common/ray_box.wgsl"
#include "field/grid.wgsl"
#include "march/volume_march.wgsl"
#include "shade/shade_body.wgsl"
#include "shade/self_shadow_ssdf.wgsl"
#include "lighting/local_light.wgsl"

@group(0) @binding(10) var<storage, read> bvh_nodes: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read> bvh_triangles: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read> sharp_rays: array<vec4<f32>>;
// Each local light as (centre, radius), (intensity, radius of the disk it
// shines from; 0 while inactive), written by the direct-light pass
// (lighting/direct.wgsl).
@group(0) @binding(22) var<storage, read> local_lights: array<vec4<f32>>;

#include "geometry/mesh_bvh.wgsl"
#include "shadow/direct_rays.wgsl"
#include "shade/field_light.wgsl"

fn first_local() -> u32 {
    return pc.light_count - min(pc.local_count, pc.light_count);
}

fn shading_fitted_count() -> u32 {
    return pc.light_count - min(pc.direct_lobes, pc.light_count);
}

fn shading_fitted_attenuation(k: u32) -> f32 {
    return ssdf_attenuation(k);
}

fn shading_direct_lobe(k: u32, g: Sg) -> Sg {
    if k < first_local() {
        return g;
    }
    let l = k - first_local();
    let info = local_lights[2u * l + 1u];
    if info.w == 0.0 {
        return g;
    }
    let sphere = local_lights[2u * l];
    let to = sphere.xyz - shade_point;
    return local_sphere_lobe(normalize(to), length(to), info.w, info.xyz);
}

// Γ of local light l at the pixel: the share of its rays that arrive,
// each the field's transmittance where the mesh leaves the ray clear and
// it comes from above the tangent plane (a ray from below carries no
// light: a light wholly below the horizon gets Γ = 0, where the SG
// clamped cosine's tail, 0.12 at the horizon and 0.07 at 100°, would
// light a rim on faces turned from it).
fn local_visibility(l: u32) -> f32 {
    let sphere = local_lights[2u * l];
    let radius = local_lights[2u * l + 1u].w;
    let lifted = shade_point + shade_normal * (DIRECT_RAY_OFFSET * ssdf_world_sphere().w);
    let o = ssdf_to_object_point(lifted);
    let n = pc.local_side * pc.local_side;
    var sum = 0.0;
    for (var r = 0u; r < n; r++) {
        let d = normalize(local_disk_point_towards(sphere, lifted, r, pc.local_side, radius) - lifted);
        if dot(d, shade_normal) <= 0.0 || bvh_occluded(o, ssdf_to_object_dir(d)) {
            continue;
        }
        sum += local_transmittance_to(sphere, lifted, r, pc.local_side, radius, pc.march_step, pc.march_termination);
    }
    return sum / f32(max(n, 1u));
}

fn shading_direct_attenuation(k: u32) -> f32 {
    let first = shading_fitted_count();
    if k >= first_local() {
        let l = k - first_local();
        if local_lights[2u * l + 1u].w == 0.0 {
            return 0.0;
        }
        return local_visibility(l);
    }
    let lifted = shade_point + shade_normal * (DIRECT_RAY_OFFSET * ssdf_world_sphere().w);
    return direct_clear_fraction(lifted, k - first, pc.direct_rays, shade_normal, true);
}

var<private> field_pixel: vec2<u32>;

fn shading_diffuse_gain() -> vec3<f32> {
    return field_light_blended_gain(field_pixel, shade_point, shade_normal);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) dispatched: vec3<u32>) {
    let id = shade_dispatched_pixel(dispatched);
    field_pixel = id.xy;
    shade_pixel(id);
}

// Each field light tile's table (pass `object-field-light`), over the
// tiles of 8 · pc.field_scale pixels from pc.tile_origin (in those tiles)
// on, each invocation taking pc.field_scale² pixels for the pick.
@compute @workgroup_size(8, 8, 1)
fn field_light_tables(
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
    @builtin(workgroup_id) dispatched_group: vec3<u32>,
) {
    let first = vec3<u32>(pc.tile_origin & 0xffffu, pc.tile_origin >> 16u, 0u);
    let group = dispatched_group + first;
    field_light_gather(local.xy, local_index, group);
    field_light_write_table(local_index, group);
}

// The gain alone, as `main` takes it from the tables: (g, 1) at the
// object's pixels and 0 where no object is (with pc.write_empty), over the
// 8 × 8 tiles from pc.tile_origin on; for the test against the mirror and
// for inspection (ShadePass::new_field_gain).
@compute @workgroup_size(8, 8, 1)
fn field_gain_only(@builtin(global_invocation_id) dispatched: vec3<u32>) {
    let id = shade_dispatched_pixel(dispatched);
    if !shade_owns(id) {
        return;
    }
    let pixel = vec2<i32>(id.xy);
    let hit = textureLoad(distance_id, pixel, 0);
    let n = normalize(textureLoad(normal_roughness, pixel, 0).xyz);
    let x = pc.camera.origin + camera_ray_dir(pc.camera, vec2<f32>(id.xy) + vec2<f32>(0.5)) * hit.r;
    textureStore(out_object, pixel, vec4<f32>(field_light_blended_gain(id.xy, x, n), 1.0));
}

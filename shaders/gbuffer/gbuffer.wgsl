// The object G-buffer (raster, dynamic rendering): vertices are pulled
// from storage buffers through the index buffer; each draw is one mesh
// part with its material in `draws[pc.draw]` and its object's pose in
// `objects[draws[pc.draw].record]`. Writes the world
// normal and roughness, base colour and metallic, and the distance along
// the camera ray with the object's index (the march clips rays there).
#include "common/brdf.wgsl"
#include "object/record.wgsl"

struct Camera {
    view_proj: mat4x4<f32>,
    origin: vec4<f32>,
}

// One mesh part: its material factors, the index its object writes to
// the G-buffer, and its object's record.
struct Draw {
    base_colour: vec4<f32>,
    roughness: f32,
    metallic: f32,
    object_index: f32,
    record: u32,
}

struct Vertex {
    position_u: vec4<f32>,
    normal_v: vec4<f32>,
}

struct DrawPush {
    draw: u32,
    first_index: u32,
}

var<immediate> pc: DrawPush;
@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<storage, read> draws: array<Draw>;
@group(0) @binding(2) var<storage, read> vertices: array<Vertex>;
@group(0) @binding(3) var<storage, read> indices: array<u32>;
@group(0) @binding(4) var base_colour_texture: texture_2d<f32>;
@group(0) @binding(5) var metallic_roughness_texture: texture_2d<f32>;
@group(0) @binding(6) var material_sampler: sampler;
@group(0) @binding(7) var<storage, read> objects: array<ObjectRecord>;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> VsOut {
    let vert = vertices[indices[pc.first_index + i]];
    let o = objects[draws[pc.draw].record];
    let p = vec4<f32>(vert.position_u.xyz, 1.0);
    let world = vec3<f32>(dot(o.to_world[0], p), dot(o.to_world[1], p), dot(o.to_world[2], p));
    let n = vert.normal_v.xyz;
    let normal = vec3<f32>(dot(o.normal[0].xyz, n), dot(o.normal[1].xyz, n), dot(o.normal[2].xyz, n));
    var out: VsOut;
    out.clip = camera.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    out.normal = normal;
    out.uv = vec2<f32>(vert.position_u.w, vert.normal_v.w);
    return out;
}

struct GBufferOut {
    @location(0) normal_roughness: vec4<f32>,
    @location(1) albedo_metallic: vec4<f32>,
    @location(2) distance_id: vec2<f32>,
}

@fragment
fn fs_main(in: VsOut) -> GBufferOut {
    let d = draws[pc.draw];
    let len = length(in.normal);
    let n = select(vec3<f32>(0.0, 1.0, 0.0), in.normal / len, len > 0.0);
    let base = d.base_colour.rgb * textureSample(base_colour_texture, material_sampler, in.uv).rgb;
    let mr = textureSample(metallic_roughness_texture, material_sampler, in.uv);
    let roughness = clamp(d.roughness * mr.g, BRDF_MIN_ROUGHNESS, 1.0);
    let metallic = clamp(d.metallic * mr.b, 0.0, 1.0);
    var out: GBufferOut;
    out.normal_roughness = vec4<f32>(n, roughness);
    out.albedo_metallic = vec4<f32>(clamp(base, vec3<f32>(0.0), vec3<f32>(1.0)), metallic);
    out.distance_id = vec2<f32>(length(in.world - camera.origin.xyz), d.object_index);
    return out;
}

// The direct lobes' visibility (the lobes of L_env too sharp for the fit,
// shaded as they are): the share of a lobe's rays that the object's mesh
// leaves clear, cast in the object's frame through its bounding-volume
// hierarchy. Mirrors passes/src/shadow/direct.rs DirectOcclusion.
// Needs: ssdf/ssdf.wgsl (the `ssdf` block: world → object),
// geometry/mesh_bvh.wgsl with its `bvh_nodes` and `bvh_triangles`, and a
// read-only storage buffer `sharp_rays: array<vec4<f32>>` (per direct
// lobe, `rays` world directions; passes/src/lighting/sharp.rs lobe_rays).

// A self-shadow ray starts this many bounding radii off the surface
// (direct.rs DIRECT_RAY_OFFSET).
const DIRECT_RAY_OFFSET: f32 = 1e-3;

// The share of direct lobe `lobe`'s `rays` rays from world point `x` that
// the object leaves clear; with `above`, only rays above the plane of
// normal `n` count (1 when none does).
fn direct_clear_fraction(x: vec3<f32>, lobe: u32, rays: u32, n: vec3<f32>, above: bool) -> f32 {
    let o = ssdf_to_object_point(x);
    var clear = 0u;
    var counted = 0u;
    for (var r = 0u; r < rays; r++) {
        let d = sharp_rays[lobe * rays + r].xyz;
        if above && dot(d, n) <= 0.0 {
            continue;
        }
        counted += 1u;
        if !bvh_occluded(o, ssdf_to_object_dir(d)) {
            clear += 1u;
        }
    }
    if counted == 0u {
        return 1.0;
    }
    return f32(clear) / f32(counted);
}

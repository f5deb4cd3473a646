// A local light's visibility past the object's mesh, for its cast shadow:
// the share of the rays from a world point to the light's disk points
// (lighting/local_light_disk.wgsl) that the mesh leaves clear. Mirrors
// passes/src/lighting/local.rs mesh_clear_fraction.
// Needs: shadow/direct_rays.wgsl (and what it needs),
// lighting/local_light_disk.wgsl.

// `emission`: the light's (intensity, radius of the disk it shines from).
fn local_clear_fraction(x: vec3<f32>, sphere: vec4<f32>, emission: vec4<f32>, side: u32) -> f32 {
    let o = ssdf_to_object_point(x);
    let n = side * side;
    var clear = 0u;
    for (var r = 0u; r < n; r++) {
        let d = normalize(local_disk_point_towards(sphere, x, r, side, emission.w) - x);
        if !bvh_occluded(o, ssdf_to_object_dir(d)) {
            clear += 1u;
        }
    }
    return f32(clear) / f32(max(n, 1u));
}

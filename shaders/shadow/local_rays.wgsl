// A local light's light at a point of the cast shadow: how much of it
// reaches the point, and how much past the object. Mirrors
// passes/src/shadow/direct.rs DirectOcclusion::local_arrival and
// local_clear.
// Needs: shadow/direct_rays.wgsl (and what it needs),
// lighting/local_light.wgsl (and what it needs).

// (the field's transmittance towards the light, the share of its side²
// rays to its disk, of radius `emission.w`, that leave `x` from above the
// plane of normal `n`): the transmittance along one ray, from `x` lifted
// `lift` along `n` (off the surface's own density) to the disk's centre.
fn local_cast_arrival(x: vec3<f32>, n: vec3<f32>, sphere: vec4<f32>, emission: vec4<f32>, side: u32, lift: f32, step: f32, termination: f32) -> vec2<f32> {
    let count = side * side;
    var above = 0u;
    for (var r = 0u; r < count; r++) {
        if dot(local_disk_point_towards(sphere, x, r, side, emission.w) - x, n) > 0.0 {
            above += 1u;
        }
    }
    let t = local_transmittance_to(sphere, x + n * lift, 0u, 1u, emission.w, step, termination);
    return vec2<f32>(t, f32(above) / f32(max(count, 1u)));
}

// The share of those rays that leave from above the plane and pass the
// object's mesh.
fn local_cast_clear(x: vec3<f32>, n: vec3<f32>, sphere: vec4<f32>, emission: vec4<f32>, side: u32) -> f32 {
    let o = ssdf_to_object_point(x);
    let count = side * side;
    var clear = 0u;
    for (var r = 0u; r < count; r++) {
        let d = normalize(local_disk_point_towards(sphere, x, r, side, emission.w) - x);
        if dot(d, n) > 0.0 && !bvh_occluded(o, ssdf_to_object_dir(d)) {
            clear += 1u;
        }
    }
    return f32(clear) / f32(max(count, 1u));
}

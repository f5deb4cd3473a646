// Entry and exit of the ray origin + t·dir through an axis-aligned box,
// clamped to t ≥ 0: returns (t_near, t_far), with t_near > t_far on a miss.
// Mirrors `ray_box` in passes/src/geometry/mod.rs; zero direction components are
// replaced by ±1e-30 (division by zero is undefined in Vulkan), which gives
// the same result as the CPU's IEEE infinities for boxes of sane size.
fn ray_box(origin: vec3<f32>, dir: vec3<f32>, box_min: vec3<f32>, box_max: vec3<f32>) -> vec2<f32> {
    let tiny = vec3<f32>(1e-30);
    let safe = select(dir, select(-tiny, tiny, dir >= vec3<f32>(0.0)), abs(dir) < tiny);
    let inv = 1.0 / safe;
    let t0 = (box_min - origin) * inv;
    let t1 = (box_max - origin) * inv;
    let near = min(t0, t1);
    let far = max(t0, t1);
    let t_near = max(max(near.x, near.y), max(near.z, 0.0));
    let t_far = min(min(far.x, far.y), far.z);
    return vec2<f32>(t_near, t_far);
}

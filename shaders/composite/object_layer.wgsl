// The object layer's colour at a pixel: `object_colour` inside the
// pixels it can cover (pc.object_x0..x1 × pc.object_y0..y1, the union of
// the shown objects' bounding spheres' rectangles), transparent black
// beyond them, where object-shade writes nothing. The including shader
// declares `object_colour` and a push block `pc` of CompositePush
// (composite/push.wgsl).

fn composite_object(p: vec2<i32>) -> vec4<f32> {
    let q = vec2<u32>(p);
    if q.x < pc.object_x0 || q.y < pc.object_y0 || q.x >= pc.object_x1 || q.y >= pc.object_y1 {
        return vec4<f32>(0.0);
    }
    return textureLoad(object_colour, p, 0);
}

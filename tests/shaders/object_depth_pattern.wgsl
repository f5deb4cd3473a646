// Test pattern for the march's clipping: an object-depth image whose left
// third holds `near`, middle third `mid`, and right third "no object".
struct Pattern {
    width: u32,
    height: u32,
    near: f32,
    mid: f32,
}

var<immediate> pc: Pattern;

@group(0) @binding(0) var out_depth: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= pc.width || id.y >= pc.height {
        return;
    }
    var d = 3.0e38;
    if 3u * id.x < pc.width {
        d = pc.near;
    } else if 3u * id.x < 2u * pc.width {
        d = pc.mid;
    }
    textureStore(out_depth, id.xy, vec4<f32>(d, 0.0, 0.0, 0.0));
}

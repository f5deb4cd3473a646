// One placed object's pose as every pass that needs it reads it: uploaded
// once per frame, one record per object of the frame (ObjectRecord in
// passes/src/object/record.rs). The including shader declares the binding
// `objects: array<ObjectRecord>` (read-only storage).
struct ObjectRecord {
    // Rows of the affine object → world map.
    to_world: array<vec4<f32>, 3>,
    // Rows of the affine world → object map (directions use .xyz).
    to_object: array<vec4<f32>, 3>,
    // Rows of the normal matrix (object → world normals; w unused).
    normal: array<vec4<f32>, 3>,
    // The world-space bounding sphere (centre, radius).
    sphere: vec4<f32>,
}

// Pinhole camera rays. Mirrors `CameraFrame::ray` in passes/src/camera.rs:
// `right` and `up` are scaled by tan(fov/2) (and the aspect ratio), pixel
// centres sit at +0.5 and y grows downwards.
fn camera_ray_dir(
    right: vec3<f32>,
    up: vec3<f32>,
    forward: vec3<f32>,
    size: vec2<f32>,
    pixel: vec2<f32>,
) -> vec3<f32> {
    let nx = 2.0 * pixel.x / size.x - 1.0;
    let ny = 1.0 - 2.0 * pixel.y / size.y;
    return normalize(forward + nx * right + ny * up);
}

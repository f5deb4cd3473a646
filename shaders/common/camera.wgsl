// A pinhole camera as the per-pixel passes' push blocks carry it, and its
// rays. Mirrors `CameraRays` and `CameraFrame::ray` in passes/src/camera.rs:
// `right` and `up` are scaled by tan(fov/2) (and the aspect ratio), pixel
// centres sit at +0.5 and y grows downwards.
struct CameraRays {
    // The eye.
    origin: vec3<f32>,
    width: u32,
    // Right and up, scaled to the half-width and half-height at unit
    // distance; forward, unit.
    right: vec3<f32>,
    height: u32,
    up: vec3<f32>,
    forward: vec3<f32>,
}

// Whether `id` lies outside the camera's image.
fn camera_outside(cam: CameraRays, id: vec2<u32>) -> bool {
    return id.x >= cam.width || id.y >= cam.height;
}

// The unit direction of the ray through image position `pixel` (pixel
// units; a pixel's centre is its index + 0.5).
fn camera_ray_dir(cam: CameraRays, pixel: vec2<f32>) -> vec3<f32> {
    let size = vec2<f32>(f32(cam.width), f32(cam.height));
    let nx = 2.0 * pixel.x / size.x - 1.0;
    let ny = 1.0 - 2.0 * pixel.y / size.y;
    return normalize(cam.forward + nx * cam.right + ny * cam.up);
}

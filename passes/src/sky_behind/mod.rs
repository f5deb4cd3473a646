//! The sky behind the frame (`sky-behind`, compute): what a trained field's
//! photographs saw past its bounds ([`Sky`], learnt with `inlay train
//! --sky`), drawn where the field and the objects leave a pixel uncovered:
//! c + (1 − c.a)·sky(d) along the pixel's ray d, coverage 1. It is the
//! trainer's T_N·b, so a held-out view renders as the trainer scored it.
//! The sky lies beyond everything, so an object hides it whole and a cast
//! shadow (which darkens the field's part of a pixel) never reaches it.
//! The lights the photographs saw past the bounds ([`SeenLight`]) are
//! drawn here too: one past the bounds as the sky is, one before them
//! over the whole frame ([`light_over_pixel`]). A field with neither runs
//! no such pass. [`sky_behind_reference`] (over
//! [`light_over_pixel`]) is the CPU mirror of
//! `shaders/sky_behind/sky_behind.wgsl`.

use std::sync::Arc;

use glam::DVec3;
use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, Buffer, ComputePipeline, Context, ImageDesc};

use crate::camera::{CameraFrame, CameraRays};
use crate::field::seen_lights::light_over_pixel;
use crate::field::{SeenLight, Sky};
use crate::frame::meta::{PassInfo, Table1Module};
use crate::geometry::Aabb;

inlay_engine::gpu_struct! {
    /// `SkyBehindPush` of `shaders/sky_behind/sky_behind.wgsl`.
    pub struct SkyBehindPush = "sky_behind/sky_behind.wgsl" : "SkyBehindPush" {
        /// The camera.
        pub camera: CameraRays,
        /// The sky's texels across (0: black behind the frame).
        pub sky_width: u32,
        /// The sky's texels down.
        pub sky_height: u32,
        /// The lights seen past the bounds.
        pub light_count: u32,
        /// Padding to the block's 16-byte size.
        pub _pad0: u32,
    }
}

/// The sky-behind pass: its name and Table 1 module (rendering the field:
/// the sky is the field's own background). No switch turns it off.
pub const SKY_BEHIND_INFO: PassInfo = PassInfo {
    name: "sky-behind",
    module: Table1Module::NerfRendering,
    switch: None,
};

/// The pass's name in the frame graph (and in timings and traces).
pub const SKY_BEHIND: &str = SKY_BEHIND_INFO.name;

/// Format of the image it writes (the frame's).
pub const SKY_BEHIND_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// What lies outside a field: its learnt sky, and the lights its
/// photographs saw past its `bounds`.
#[derive(Debug, Clone, Copy)]
pub struct Beyond<'a> {
    /// The sky (None: black).
    pub sky: Option<&'a Sky>,
    /// The lights seen past the bounds.
    pub lights: &'a [SeenLight],
    /// The field's bounds.
    pub bounds: Aabb,
}

/// The angle one pixel spans at pixel (`x`, `y`) of `camera`: the chord
/// between its centre's ray and the next pixel's along the row (f32 keeps
/// a chord of 10⁻⁴, where an arc cosine of their dot product does not).
pub fn pixel_angle(camera: &CameraFrame, x: u32, y: u32) -> f64 {
    let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
    (camera.ray(cx + 1.0, cy).dir - camera.ray(cx, cy).dir).length()
}

/// A whole `camera`-sized image (row-major) with what lies `beyond` the
/// field drawn behind (and, for lights before the bounds, over) it.
pub fn sky_behind_reference(
    image: &[[f64; 4]],
    camera: &CameraFrame,
    beyond: &Beyond,
) -> Vec<[f64; 4]> {
    image
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            let (x, y) = (i as u32 % camera.width, i as u32 / camera.width);
            let ray = camera.pixel_ray(x, y);
            let back = beyond.sky.map_or(DVec3::ZERO, |s| s.eval(ray.dir));
            light_over_pixel(
                c,
                back,
                beyond.lights,
                &beyond.bounds,
                ray.origin,
                ray.dir,
                pixel_angle(camera, x, y),
            )
        })
        .collect()
}

/// Whether any of `lights` can cover a pixel of `camera`'s image (its
/// disc's edge spread over a pixel included): a field without a sky needs
/// no `sky-behind` pass where none can.
pub fn lights_in_view(lights: &[SeenLight], camera: &CameraFrame) -> bool {
    lights.iter().any(|l| {
        camera.sphere_visible(l.centre, l.radius)
            && camera
                .sphere_pixels(l.centre, l.radius)
                .is_none_or(|[x0, y0, x1, y1]| x0 < x1 && y0 < y1)
    })
}

/// The pass: its pipeline, the sky and the lights on the device.
pub struct SkyBehindPass {
    pipeline: Arc<ComputePipeline>,
    texels: Arc<Buffer>,
    lights: Arc<Buffer>,
    width: u32,
    height: u32,
    light_count: u32,
    /// The lights, to tell whether a frame sees any.
    seen: Vec<SeenLight>,
}

impl SkyBehindPass {
    /// Compiles the pass and uploads what lies `beyond` the field; None
    /// where there is neither a sky nor a light (no pass runs).
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        beyond: &Beyond,
    ) -> anyhow::Result<Option<Self>> {
        if beyond.sky.is_none() && beyond.lights.is_empty() {
            return Ok(None);
        }
        let values: Vec<f32> = match beyond.sky {
            Some(sky) => sky
                .texels
                .iter()
                .flat_map(|t| [t.x as f32, t.y as f32, t.z as f32, 0.0])
                .collect(),
            None => vec![0.0; 4],
        };
        // The bounds, then each light's (centre, radius) and (radiance, 0).
        let b = &beyond.bounds;
        let mut lights: Vec<f32> = [b.min, b.max]
            .iter()
            .flat_map(|v| [v.x as f32, v.y as f32, v.z as f32, 0.0])
            .collect();
        for l in beyond.lights {
            let (c, e) = (l.centre, l.radiance);
            lights.extend([c.x, c.y, c.z, l.radius].map(|v| v as f32));
            lights.extend([e.x, e.y, e.z, 0.0].map(|v| v as f32));
        }
        let (width, height) = beyond.sky.map_or((0, 0), |s| (s.width, s.height));
        Ok(Some(Self {
            pipeline: lib.compute_pipeline(ctx, "sky_behind/sky_behind.wgsl", "main", &[])?,
            texels: crate::shadow::gpu::storage(ctx, "sky", &values)?,
            lights: crate::shadow::gpu::storage(ctx, "seen-lights", &lights)?,
            width,
            height,
            light_count: beyond.lights.len() as u32,
            seen: beyond.lights.to_vec(),
        }))
    }

    /// Whether a frame seen through `camera` needs the pass: its field has
    /// a sky, or one of its lights can be in view ([`lights_in_view`]).
    pub fn draws(&self, camera: &CameraFrame) -> bool {
        self.width > 0 || lights_in_view(&self.seen, camera)
    }

    /// Adds `sky-behind` over `frame` (an RGBA32F image the size of
    /// `camera`'s); returns the new image.
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        frame: ImageHandle,
        camera: &CameraFrame,
    ) -> ImageHandle {
        let desc = ImageDesc {
            width: camera.width,
            height: camera.height,
            format: SKY_BEHIND_FORMAT,
        };
        let mut out = graph.create_image("sky-behind", desc);
        let sky = graph.import_buffer(&self.texels, None);
        let lights = graph.import_buffer(&self.lights, None);
        graph
            .compute(SKY_BEHIND, &self.pipeline)
            .read("frame_colour", frame)
            .read("sky", sky)
            .read("lights", lights)
            .write("out_colour", &mut out)
            .push(&SkyBehindPush {
                camera: camera.rays(),
                sky_width: self.width,
                sky_height: self.height,
                light_count: self.light_count,
                _pad0: 0,
            })
            .threads([camera.width, camera.height, 1]);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A light ahead of the camera is in view, one behind it or off to
    /// the side is not, and one the image plane cuts may be anywhere.
    #[test]
    fn a_light_is_in_view_only_where_its_disc_can_cover_a_pixel() {
        let spec = crate::camera::CameraSpec {
            name: None,
            position: DVec3::ZERO,
            look_at: -DVec3::Z,
            up: DVec3::Y,
            fov_y: 40.0,
        };
        let camera = CameraFrame::new(&spec, 64, 48);
        let at = |c: DVec3, radius: f64| SeenLight {
            centre: c,
            radius,
            radiance: DVec3::ONE,
            views: 3,
            residual: 0.0,
        };
        assert!(lights_in_view(
            &[at(DVec3::new(0.0, 0.0, -3.0), 0.01)],
            &camera
        ));
        assert!(!lights_in_view(
            &[at(DVec3::new(0.0, 0.0, 3.0), 0.01)],
            &camera
        ));
        assert!(!lights_in_view(
            &[at(DVec3::new(5.0, 0.0, -3.0), 0.01)],
            &camera
        ));
        assert!(lights_in_view(
            &[at(DVec3::new(0.0, 0.0, 0.5), 1.0)],
            &camera
        ));
        assert!(!lights_in_view(&[], &camera));
    }

    /// A covered pixel keeps its colour, an empty one reads the sky, a
    /// half-covered one half of it; the coverage is 1 after.
    #[test]
    fn the_sky_fills_what_the_frame_leaves_uncovered() {
        let sky = Sky::uniform(4, DVec3::new(2.0, 4.0, 8.0));
        let d = DVec3::new(0.3, 0.5, -0.8).normalize();
        let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        let pixel =
            |c: [f64; 4]| light_over_pixel(c, sky.eval(d), &[], &bounds, DVec3::ZERO, d, 0.01);
        assert_eq!(pixel([0.1, 0.2, 0.3, 1.0]), [0.1, 0.2, 0.3, 1.0]);
        assert_eq!(pixel([0.0; 4]), [2.0, 4.0, 8.0, 1.0]);
        assert_eq!(pixel([0.5, 0.5, 0.5, 0.5]), [1.5, 2.5, 4.5, 1.0]);
        // Coverage a hair past 1 (f32 sums) reads no sky, never a negative one.
        assert_eq!(pixel([0.1, 0.2, 0.3, 1.000001]), [0.1, 0.2, 0.3, 1.0]);
    }
}

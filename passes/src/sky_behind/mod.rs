//! The sky behind the frame (`sky-behind`, compute): what a trained field's
//! photographs saw past its bounds ([`Sky`], learnt with `inlay train
//! --sky`), drawn where the field and the objects leave a pixel uncovered:
//! c + (1 − c.a)·sky(d) along the pixel's ray d, coverage 1. It is the
//! trainer's T_N·b, so a held-out view renders as the trainer scored it.
//! The sky lies beyond everything, so an object hides it whole and a cast
//! shadow (which darkens the field's part of a pixel) never reaches it.
//! A field without a sky runs no such pass. [`sky_behind_pixel`] is the
//! CPU mirror of `shaders/sky_behind/sky_behind.wgsl`.

use std::sync::Arc;

use glam::DVec3;
use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, Buffer, ComputePipeline, Context, ImageDesc};

use crate::camera::{CameraFrame, CameraRays};
use crate::field::Sky;
use crate::frame::meta::{PassInfo, Table1Module};

inlay_engine::gpu_struct! {
    /// `SkyBehindPush` of `shaders/sky_behind/sky_behind.wgsl`.
    pub struct SkyBehindPush = "sky_behind/sky_behind.wgsl" : "SkyBehindPush" {
        /// The camera.
        pub camera: CameraRays,
        /// The sky's texels across.
        pub sky_width: u32,
        /// The sky's texels down.
        pub sky_height: u32,
        /// Padding to the block's 16-byte size.
        pub _pad0: u32,
        /// Padding.
        pub _pad1: u32,
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

/// One pixel: `colour` (premultiplied, coverage in alpha) over the sky seen
/// along unit direction `d`; its coverage becomes 1.
pub fn sky_behind_pixel(colour: [f64; 4], d: DVec3, sky: &Sky) -> [f64; 4] {
    let left = (1.0 - colour[3]).max(0.0);
    if left <= 0.0 {
        return [colour[0], colour[1], colour[2], 1.0];
    }
    let b = sky.eval(d);
    [
        colour[0] + left * b.x,
        colour[1] + left * b.y,
        colour[2] + left * b.z,
        1.0,
    ]
}

/// A whole `camera`-sized image (row-major) with the sky behind it.
pub fn sky_behind_reference(image: &[[f64; 4]], camera: &CameraFrame, sky: &Sky) -> Vec<[f64; 4]> {
    image
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            let (x, y) = (i as u32 % camera.width, i as u32 / camera.width);
            sky_behind_pixel(c, camera.pixel_ray(x, y).dir, sky)
        })
        .collect()
}

/// The pass: its pipeline and the sky on the device.
pub struct SkyBehindPass {
    pipeline: Arc<ComputePipeline>,
    texels: Arc<Buffer>,
    width: u32,
    height: u32,
}

impl SkyBehindPass {
    /// Compiles the pass and uploads `sky`.
    pub fn new(ctx: &Arc<Context>, lib: &ShaderLibrary, sky: &Sky) -> anyhow::Result<Self> {
        let values: Vec<f32> = sky
            .texels
            .iter()
            .flat_map(|t| [t.x as f32, t.y as f32, t.z as f32, 0.0])
            .collect();
        Ok(Self {
            pipeline: lib.compute_pipeline(ctx, "sky_behind/sky_behind.wgsl", "main", &[])?,
            texels: crate::shadow::gpu::storage(ctx, "sky", &values)?,
            width: sky.width,
            height: sky.height,
        })
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
        graph
            .compute(SKY_BEHIND, &self.pipeline)
            .read("frame_colour", frame)
            .read("sky", sky)
            .write("out_colour", &mut out)
            .push(&SkyBehindPush {
                camera: camera.rays(),
                sky_width: self.width,
                sky_height: self.height,
                _pad0: 0,
                _pad1: 0,
            })
            .threads([camera.width, camera.height, 1]);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A covered pixel keeps its colour, an empty one reads the sky, a
    /// half-covered one half of it; the coverage is 1 after.
    #[test]
    fn the_sky_fills_what_the_frame_leaves_uncovered() {
        let sky = Sky::uniform(4, DVec3::new(2.0, 4.0, 8.0));
        let d = DVec3::new(0.3, 0.5, -0.8).normalize();
        assert_eq!(
            sky_behind_pixel([0.1, 0.2, 0.3, 1.0], d, &sky),
            [0.1, 0.2, 0.3, 1.0]
        );
        assert_eq!(sky_behind_pixel([0.0; 4], d, &sky), [2.0, 4.0, 8.0, 1.0]);
        assert_eq!(
            sky_behind_pixel([0.5, 0.5, 0.5, 0.5], d, &sky),
            [1.5, 2.5, 4.5, 1.0]
        );
        // Coverage a hair past 1 (f32 sums) reads no sky, never a negative one.
        assert_eq!(
            sky_behind_pixel([0.1, 0.2, 0.3, 1.000001], d, &sky),
            [0.1, 0.2, 0.3, 1.0]
        );
    }
}

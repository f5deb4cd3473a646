//! The headless target: render N frames of a scene offscreen, read the last
//! HDR frame back, and return it with the frames' timings.

use std::sync::Arc;

use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::timing::FrameTimings;
use inlay_engine::{
    vk, Context, DeviceInfo, HdrImage, ImageDesc, Readback, Renderer, SubmitSync,
    DEFAULT_FRAMES_IN_FLIGHT,
};

use crate::outputs::Outputs;

/// Something that renders an HDR image through a frame graph (object-safe:
/// the targets take `&mut dyn Scene`).
pub trait Scene {
    /// Adds passes that render a `width`×`height` linear HDR image
    /// at time `time` (seconds) and returns it (a scene may keep state
    /// from frame to frame, such as when its lighting was last fitted).
    fn build(
        &mut self,
        graph: &mut FrameGraph,
        width: u32,
        height: u32,
        time: f32,
    ) -> anyhow::Result<ImageHandle>;

    /// Format of the image [`Scene::build`] returns (RGBA16F unless the
    /// scene says otherwise; RGBA32F is the other readable one).
    fn output_format(&self) -> vk::Format {
        vk::Format::R16G16B16A16_SFLOAT
    }
}

/// The outcome of a headless run.
pub struct HeadlessRun {
    /// The last frame, read back.
    pub image: HdrImage,
    /// Timings of every frame, oldest first.
    pub timings: Vec<FrameTimings>,
    /// Names of the passes culled in the last frame.
    pub culled: Vec<String>,
    /// Transient resources created over the run (reuse keeps this flat).
    pub transients_created: u64,
}

/// Fails, before any work, unless `info`'s device can render a `width` ×
/// `height` frame (each side 1 up to its largest 2D image).
pub fn check_frame_size(info: &DeviceInfo, width: u32, height: u32) -> anyhow::Result<()> {
    let max = info.max_image_dimension_2d;
    anyhow::ensure!(
        width > 0 && height > 0 && width <= max && height <= max,
        "image size {width}x{height} is out of range: {} renders 1..={max} pixels a side \
         (--width, --height)",
        info.name
    );
    Ok(())
}

/// Renders `frames` frames (at least 1) of `scene` offscreen with frames in
/// flight, at times `time + i/60`, and reads the last one back.
pub fn run_headless(
    ctx: &Arc<Context>,
    scene: &mut dyn Scene,
    width: u32,
    height: u32,
    frames: u32,
    time: f32,
) -> anyhow::Result<HeadlessRun> {
    check_frame_size(ctx.info(), width, height)?;
    let mut renderer = Renderer::new(ctx, DEFAULT_FRAMES_IN_FLIGHT)?;
    let readback = Readback::new(
        ctx,
        ImageDesc {
            width,
            height,
            format: scene.output_format(),
        },
    )?;
    let mut culled = Vec::new();
    for i in 0..frames.max(1) {
        renderer.begin_frame()?;
        let mut graph = FrameGraph::new();
        let hdr = scene.build(&mut graph, width, height, time + i as f32 / 60.0)?;
        readback.add_to_graph(&mut graph, hdr);
        let report = renderer.submit(graph, &SubmitSync::none())?;
        culled = report.culled;
    }
    renderer.finish()?;
    ctx.check_validation()?;
    Ok(HeadlessRun {
        image: readback.read()?,
        timings: renderer.timings().to_vec(),
        culled,
        transients_created: renderer.transients_created(),
    })
}

impl HeadlessRun {
    /// Writes the image to each of `outs` (.exr linear, .png tonemapped at
    /// `exposure`) and prints the per-pass timing table for `ctx`'s device.
    pub fn report(
        &self,
        ctx: &Context,
        outs: &[std::path::PathBuf],
        exposure: f32,
    ) -> anyhow::Result<()> {
        let mut outputs = Outputs::new();
        for out in outs {
            outputs.image(out, &self.image, exposure)?;
        }
        outputs.commit(Some(ctx))?;
        print!(
            "{}",
            crate::timings_table::format_table(
                &self.timings,
                &format!("{} ({:?})", ctx.info().name, ctx.info().kind)
            )
        );
        Ok(())
    }
}

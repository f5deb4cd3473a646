//! The present pass: tonemaps an HDR image onto the swapchain image.

use std::sync::Arc;

use inlay_engine::graph::{FrameGraph, ImageHandle, LoadOp};
use inlay_engine::shader::{compile, ShaderLibrary, ShaderStage};
use inlay_engine::{vk, Context, GraphicsDesc, GraphicsPipeline};

inlay_engine::gpu_struct! {
    /// `Params` of `shaders/present.wgsl`.
    pub struct PresentPush = "present.wgsl" : "Params" {
        /// Exposure multiplier.
        pub exposure: f32,
        /// 1: the shader encodes sRGB (the swapchain format does not).
        pub encode_srgb: u32,
    }
}

/// The tonemapping pipeline for one swapchain format.
pub struct PresentPipeline {
    pipeline: Arc<GraphicsPipeline>,
    format: vk::Format,
    encode_srgb: bool,
}

impl PresentPipeline {
    /// Builds the pipeline for `format`; `srgb_format` says whether the
    /// hardware encodes sRGB on write (else the shader does).
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        format: vk::Format,
        srgb_format: bool,
    ) -> anyhow::Result<Self> {
        let v = compile(lib, "present.wgsl", "vs_main", ShaderStage::Vertex, &[])?;
        let f = compile(lib, "present.wgsl", "fs_main", ShaderStage::Fragment, &[])?;
        let desc = GraphicsDesc {
            color_formats: vec![format],
            depth_format: None,
            depth_test: false,
            depth_write: false,
            blend: false,
            cull_back: false,
        };
        Ok(Self {
            pipeline: Arc::new(GraphicsPipeline::new(ctx, &v, &f, &desc)?),
            format,
            encode_srgb: !srgb_format,
        })
    }

    /// The swapchain format it renders to.
    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// Adds the `present` pass: `hdr` (sampled) → `target` (colour attachment).
    pub fn add_pass(
        &self,
        graph: &mut FrameGraph,
        hdr: ImageHandle,
        target: ImageHandle,
        exposure: f32,
    ) -> ImageHandle {
        let push = PresentPush {
            exposure,
            encode_srgb: self.encode_srgb as u32,
        };
        let mut out = target;
        let mut pass = graph.raster_pass("present");
        pass.color(&mut out, LoadOp::DontCare);
        pass.draw(&self.pipeline)
            .read("hdr", hdr)
            .push(&push)
            .vertices(3, 1);
        pass.finish();
        out
    }
}

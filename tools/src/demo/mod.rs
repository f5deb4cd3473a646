//! `inlay demo`: a small graph that exercises the engine before the method
//! exists — two compute passes (an HDR sky image, a buffer of quad vertices)
//! feeding one raster pass with a depth buffer, plus a debug heat-map pass
//! that the graph culls unless its output is asked for.

pub mod pattern;

use std::sync::Arc;

use inlay_engine::graph::{FrameGraph, ImageHandle, LoadOp, SamplerKind};
use inlay_engine::shader::{compile, ShaderLibrary, ShaderStage};
use inlay_engine::{vk, ComputePipeline, Context, GraphicsDesc, GraphicsPipeline, ImageDesc};

inlay_engine::gpu_struct! {
    /// `Params` of `shaders/demo/sky.wgsl`.
    pub struct SkyPush = "demo/sky.wgsl" : "Params" {
        /// Image size.
        pub size: [u32; 2],
        /// Seconds.
        pub time: f32,
        /// Padding.
        pub _pad: f32,
    }
}

inlay_engine::gpu_struct! {
    /// `Params` of `shaders/demo/quads.wgsl`.
    pub struct QuadsPush = "demo/quads.wgsl" : "Params" {
        /// Seconds.
        pub time: f32,
        /// Width over height.
        pub aspect: f32,
    }
}

/// Format of the demo's HDR colour target.
pub const HDR_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// Format of its depth buffer.
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
/// Vertices the quads pass writes (two quads of two triangles).
pub const QUAD_VERTICES: u32 = 12;
const VERTEX_BYTES: u64 = 32;

/// The demo's pipelines, built once.
pub struct DemoPipelines {
    sky: Arc<ComputePipeline>,
    quads: Arc<ComputePipeline>,
    heatmap: Arc<ComputePipeline>,
    background: Arc<GraphicsPipeline>,
    quad: Arc<GraphicsPipeline>,
}

impl DemoPipelines {
    /// Compiles the demo's shaders and builds its pipelines.
    pub fn new(ctx: &Arc<Context>, lib: &ShaderLibrary) -> anyhow::Result<Self> {
        let cs = |file: &str| lib.compute_pipeline(ctx, file, "main", &[]);
        let raster =
            |vs: &str, fs: &str, depth_test: bool| -> anyhow::Result<Arc<GraphicsPipeline>> {
                let v = compile(lib, "demo/scene.wgsl", vs, ShaderStage::Vertex, &[])?;
                let f = compile(lib, "demo/scene.wgsl", fs, ShaderStage::Fragment, &[])?;
                let desc = GraphicsDesc {
                    color_formats: vec![HDR_FORMAT],
                    depth_format: Some(DEPTH_FORMAT),
                    depth_test,
                    depth_write: depth_test,
                    blend: false,
                    cull_back: false,
                };
                Ok(Arc::new(GraphicsPipeline::new(ctx, &v, &f, &desc)?))
            };
        Ok(Self {
            sky: cs("demo/sky.wgsl")?,
            quads: cs("demo/quads.wgsl")?,
            heatmap: cs("demo/heatmap.wgsl")?,
            background: raster("vs_background", "fs_background", false)?,
            quad: raster("vs_quad", "fs_quad", true)?,
        })
    }
}

/// What the demo graph produced.
#[derive(Debug, Clone, Copy)]
pub struct DemoOutputs {
    /// The HDR image (sky with quads).
    pub hdr: ImageHandle,
    /// The heat-map debug image (its pass is culled unless this is consumed).
    pub heatmap: ImageHandle,
}

/// Adds the demo's passes for a `width`×`height` frame at time `time` (s).
pub fn add_demo_passes(
    graph: &mut FrameGraph,
    p: &DemoPipelines,
    width: u32,
    height: u32,
    time: f32,
) -> DemoOutputs {
    let hdr_desc = ImageDesc {
        width,
        height,
        format: HDR_FORMAT,
    };
    let sky = graph.create_image("sky", hdr_desc);
    let vertices = graph.create_buffer("quad-vertices", QUAD_VERTICES as u64 * VERTEX_BYTES);
    let color = graph.create_image("hdr", hdr_desc);
    let depth = graph.create_image(
        "depth",
        ImageDesc {
            width,
            height,
            format: DEPTH_FORMAT,
        },
    );
    let heat = graph.create_image("heatmap", hdr_desc);

    let (mut sky, mut vertices, mut hdr, mut depth, mut heatmap) =
        (sky, vertices, color, depth, heat);
    graph
        .compute("sky", &p.sky)
        .write("sky", &mut sky)
        .push(&SkyPush {
            size: [width, height],
            time,
            _pad: 0.0,
        })
        .threads([width, height, 1]);
    graph
        .compute("quads", &p.quads)
        .write("vertices", &mut vertices)
        .push(&QuadsPush {
            time,
            aspect: width as f32 / height as f32,
        })
        .groups([1, 1, 1]);
    let mut pass = graph.raster_pass("scene");
    pass.color(&mut hdr, LoadOp::DontCare)
        .depth(&mut depth, LoadOp::Clear(1.0));
    pass.draw(&p.background)
        .read("sky", sky)
        .sampler("sky_sampler", SamplerKind::NearestClamp)
        .vertices(3, 1);
    pass.draw(&p.quad)
        .read("vertices", vertices)
        .vertices(QUAD_VERTICES, 1);
    pass.finish();
    graph
        .compute("heatmap", &p.heatmap)
        .read("sky", sky)
        .write("heat", &mut heatmap)
        .push(&[width, height])
        .threads([width, height, 1]);
    DemoOutputs { hdr, heatmap }
}

/// The demo as a [`Scene`](crate::headless::Scene) for the headless and
/// windowed targets.
pub struct DemoScene {
    /// Its pipelines.
    pub pipelines: DemoPipelines,
    /// Consume the heat-map debug image (so its pass is not culled).
    pub keep_heatmap: bool,
}

impl crate::headless::Scene for DemoScene {
    fn build(
        &mut self,
        graph: &mut FrameGraph,
        width: u32,
        height: u32,
        time: f32,
    ) -> anyhow::Result<ImageHandle> {
        let out = add_demo_passes(graph, &self.pipelines, width, height, time);
        if self.keep_heatmap {
            graph.mark_output_image(out.heatmap);
        }
        Ok(out.hdr)
    }
}

//! The NeRF ray-march pass on the GPU (`shaders/march/march.wgsl`).

use crate::frame::meta::{Effect, EffectSwitch, PassInfo, Table1Module};
use std::sync::Arc;

use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{vk, ComputePipeline, Context, ImageDesc};

use super::knobs::MarchKnobs;
use crate::camera::{CameraFrame, CameraRays};
use crate::field::GpuGridField;

inlay_engine::gpu_struct! {
    /// `MarchPush` of `shaders/march/march.wgsl`.
    pub struct MarchPush = "march/march.wgsl" : "MarchPush" {
        /// The camera.
        pub camera: CameraRays,
        /// March step (world units).
        pub step: f32,
        /// Early-termination transmittance.
        pub termination: f32,
        /// The first pixel the dispatch marches (invocation (x, y)
        /// marches pixel origin + (x, y)).
        pub origin: [u32; 2],
    }
}

/// The nerf-march pass: its name, Table 1 module and effect switch.
pub const NERF_MARCH_INFO: PassInfo = PassInfo {
    name: "nerf-march",
    module: Table1Module::NerfRendering,
    switch: Some(OCCLUSION_SWITCH),
};

/// The march pass's name in the frame graph (and in timings and traces).
pub const NERF_MARCH: &str = NERF_MARCH_INFO.name;

/// The switch that draws the objects over the field instead of clipping
/// the march at them (eq. 6); the compositing pass shares it.
pub const OCCLUSION_SWITCH: EffectSwitch = EffectSwitch {
    effect: Effect::Occlusion,
    name: "occlusion",
    key: "F4",
};

/// Format of the (Ĉ, Ô) image.
pub const MARCH_COLOUR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// Format of the D̂ image and of the object-depth image the pass reads.
pub const MARCH_DEPTH_FORMAT: vk::Format = vk::Format::R32_SFLOAT;

/// The march's pipelines for one set of knobs.
pub struct MarchPass {
    unclipped: Arc<ComputePipeline>,
    clipped: Arc<ComputePipeline>,
    knobs: MarchKnobs,
}

/// What the march writes.
#[derive(Debug, Clone, Copy)]
pub struct MarchOutputs {
    /// Premultiplied colour Ĉ in rgb, opacity Ô in alpha.
    pub colour_opacity: ImageHandle,
    /// Opacity-weighted depth D̂ (distance along the ray).
    pub depth: ImageHandle,
}

impl MarchPass {
    /// Compiles the pass for `knobs` (skipping is compiled in or out).
    pub fn new(ctx: &Arc<Context>, lib: &ShaderLibrary, knobs: MarchKnobs) -> anyhow::Result<Self> {
        knobs
            .check()
            .map_err(|(k, m)| anyhow::anyhow!("march knob `{k}`: {m}"))?;
        // One ray an invocation: its view-dependent samples take their
        // corners in a loop (faster on llvmpipe), eight iterations more.
        let view_dependent = crate::field::library_marches_view_dependent(lib);
        let per_sample = 1 + if view_dependent {
            super::VIEW_DEPENDENT_SAMPLE_LOOPS
        } else {
            0
        };
        super::loop_budget::check_loop_budget(
            ctx,
            NERF_MARCH,
            knobs.loop_iterations() * per_sample,
            || {
                format!(
                    "`[march] samples_per_ray` {} on a field {} view-dependent colour",
                    knobs.samples_per_ray,
                    if view_dependent {
                        "that may have"
                    } else {
                        "without"
                    }
                )
            },
        )?;
        let defines = [
            Define::Bool("SKIP_EMPTY", knobs.skip_empty),
            Define::Bool(super::SH_CORNER_LOOP_DEFINE, true),
        ];
        let build = |entry: &str| -> anyhow::Result<Arc<ComputePipeline>> {
            Ok(lib.compute_pipeline(ctx, "march/march.wgsl", entry, &defines)?)
        };
        Ok(Self {
            unclipped: build("main_unclipped")?,
            clipped: build("main_clipped")?,
            knobs,
        })
    }

    /// The knobs it was built for.
    pub fn knobs(&self) -> &MarchKnobs {
        &self.knobs
    }

    /// Adds the `nerf-march` pass rendering `field` from `camera`; with
    /// `object_depth` (an R32F image of distances along each pixel's ray),
    /// every ray is cut where the object begins.
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        camera: &CameraFrame,
        object_depth: Option<ImageHandle>,
    ) -> MarchOutputs {
        let mut out = MarchOutputs::create(graph, camera.width, camera.height);
        let whole = [0, 0, camera.width, camera.height];
        self.record(graph, field, camera, object_depth, whole, &mut out, false);
        out
    }

    /// Records one `nerf-march` dispatch over the pixels `region` (x0, y0,
    /// x1, y1, ends exclusive) into `out`; with `keep`, the pixels outside
    /// the region keep what `out` held.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn record(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        camera: &CameraFrame,
        object_depth: Option<ImageHandle>,
        region: [u32; 4],
        out: &mut MarchOutputs,
        keep: bool,
    ) {
        let grid = field.import(graph);
        let push = MarchPush {
            camera: camera.rays(),
            step: self.knobs.step(field.diagonal) as f32,
            termination: self.knobs.termination as f32,
            origin: [region[0], region[1]],
        };
        let pipeline = match object_depth {
            Some(_) => &self.clipped,
            None => &self.unclipped,
        };
        let pass = grid.bind(graph.compute(NERF_MARCH, pipeline));
        let pass = if keep {
            pass.read_write("out_colour", &mut out.colour_opacity)
                .read_write("out_depth", &mut out.depth)
        } else {
            pass.write("out_colour", &mut out.colour_opacity)
                .write("out_depth", &mut out.depth)
        };
        pass.read_opt("object_depth", object_depth)
            .push(&push)
            .threads([region[2] - region[0], region[3] - region[1], 1]);
    }
}

impl MarchOutputs {
    /// The frame's transient march images for a `width`×`height` image.
    pub(crate) fn create(graph: &mut FrameGraph, width: u32, height: u32) -> Self {
        let image = |graph: &mut FrameGraph, name: &str, format| {
            graph.create_image(
                name,
                ImageDesc {
                    width,
                    height,
                    format,
                },
            )
        };
        Self {
            colour_opacity: image(graph, "nerf-colour", MARCH_COLOUR_FORMAT),
            depth: image(graph, "nerf-depth", MARCH_DEPTH_FORMAT),
        }
    }
}

//! The NeRF ray-march pass on the GPU (`shaders/nerf/march.wgsl`).

use std::sync::Arc;

use inlay_engine::graph::{Binding, FrameGraph, ImageAccess, ImageHandle, PassKind};
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{vk, ComputePipeline, Context, ImageDesc};

use super::knobs::MarchKnobs;
use crate::camera::CameraFrame;
use crate::field::GpuGridField;

/// The march pass's name in the frame graph (and in timings and traces).
pub const NERF_MARCH: &str = "nerf-march";

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
        let defines = [Define::Bool("SKIP_EMPTY", knobs.skip_empty)];
        let build = |entry: &str| -> anyhow::Result<Arc<ComputePipeline>> {
            Ok(lib.compute_pipeline(ctx, "nerf/march.wgsl", entry, &defines)?)
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
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        field: &GpuGridField,
        camera: &CameraFrame,
        object_depth: Option<ImageHandle>,
    ) -> MarchOutputs {
        let (width, height) = (camera.width, camera.height);
        let grid = field.import(graph);
        let colour = graph.create_image(
            "nerf-colour",
            ImageDesc {
                width,
                height,
                format: MARCH_COLOUR_FORMAT,
            },
        );
        let depth = graph.create_image(
            "nerf-depth",
            ImageDesc {
                width,
                height,
                format: MARCH_DEPTH_FORMAT,
            },
        );
        let step = self.knobs.step(field.diagonal) as f32;
        let termination = self.knobs.termination as f32;
        let push = camera.push_prefix(step).f32(termination);
        let mut pass = graph.add_pass(NERF_MARCH, PassKind::Compute);
        grid.declare_reads(&mut pass);
        let colour = pass.image(colour, ImageAccess::StorageWrite);
        let depth = pass.image(depth, ImageAccess::StorageWrite);
        if let Some(d) = object_depth {
            pass.image(d, ImageAccess::Sampled);
        }
        let pipeline = match object_depth {
            Some(_) => &self.clipped,
            None => &self.unclipped,
        };
        pass.exec(move |ctx| {
            let mut bindings = vec![
                Binding::UniformBuffer(grid.info),
                Binding::StorageBuffer(grid.nodes),
                Binding::StorageBuffer(grid.occupancy),
                Binding::StorageImage(colour),
                Binding::StorageImage(depth),
            ];
            if let Some(d) = object_depth {
                bindings.push(Binding::SampledImage(d));
            }
            ctx.dispatch(
                pipeline,
                &bindings,
                push.bytes(),
                pipeline.groups_for([width, height, 1]),
            )
        });
        MarchOutputs {
            colour_opacity: colour,
            depth,
        }
    }
}

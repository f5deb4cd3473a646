//! The compositing pass (`composite`, compute; METHOD.md eq. 6): the field
//! rendered with object clipping (premultiplied colour I_c, opacity I_α)
//! over the object's radiance I_v, I = I_c + (1 − I_α)·I_v, so the field
//! hides the object fully or partly. [`composite_over`] is the CPU mirror
//! of `shaders/composite/over.wgsl`.

use std::sync::Arc;

use inlay_engine::graph::{Binding, FrameGraph, ImageAccess, ImageHandle, PassKind};
use inlay_engine::shader::{compile, ShaderLibrary, ShaderStage};
use inlay_engine::{vk, ComputePipeline, Context, ImageDesc, Push};

/// Format of the composited image.
pub const COMPOSITE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// Premultiplied "over": `front + (1 − front.a)·back` (colour and coverage).
pub fn composite_over(front: [f32; 4], back: [f32; 4]) -> [f32; 4] {
    std::array::from_fn(|i| front[i] + (1.0 - front[3]) * back[i])
}

/// The compositing pipeline.
pub struct CompositePass {
    pipeline: ComputePipeline,
}

impl CompositePass {
    /// Compiles the pass.
    pub fn new(ctx: &Arc<Context>, lib: &ShaderLibrary) -> anyhow::Result<Self> {
        let shader = compile(
            lib,
            "composite/composite.wgsl",
            "main",
            ShaderStage::Compute,
            &[],
        )?;
        Ok(Self {
            pipeline: ComputePipeline::new(ctx, &shader)?,
        })
    }

    /// Adds `composite`: `field` (Ĉ, Ô) over `object` (I_v, coverage).
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        field: ImageHandle,
        object: ImageHandle,
    ) -> ImageHandle {
        let desc = graph.image_desc(field).unwrap_or(ImageDesc {
            width: 1,
            height: 1,
            format: COMPOSITE_FORMAT,
        });
        let (width, height) = (desc.width, desc.height);
        let out = graph.create_image(
            "composite",
            ImageDesc {
                width,
                height,
                format: COMPOSITE_FORMAT,
            },
        );
        let mut pass = graph.add_pass("composite", PassKind::Compute);
        pass.image(field, ImageAccess::Sampled);
        pass.image(object, ImageAccess::Sampled);
        let out = pass.image(out, ImageAccess::StorageWrite);
        let push = Push::new().u32(width).u32(height);
        pass.exec(move |ctx| {
            ctx.dispatch(
                &self.pipeline,
                &[
                    Binding::SampledImage(field),
                    Binding::SampledImage(object),
                    Binding::StorageImage(out),
                ],
                push.bytes(),
                self.pipeline.groups_for([width, height, 1]),
            )
        });
        out
    }
}

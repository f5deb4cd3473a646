//! The compositing pass (`composite`, compute; METHOD.md eq. 6): the field
//! rendered with object clipping (premultiplied colour I_c, opacity I_α)
//! over the object's radiance I_v, I = I_c + (1 − I_α)·I_v, so the field
//! hides the object fully or partly, the field's colour first darkened by
//! the cast shadow ρ when there is one. With occlusion off the object goes
//! over the unclipped field; with no object on screen only the shadow is
//! applied. [`composite_over`] and
//! [`composite_shade_field`] are the CPU mirrors of
//! `shaders/composite/over.wgsl`.

use crate::frame::meta::{PassInfo, Table1Module};
use std::sync::Arc;

use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, ComputePipeline, Context, ImageDesc};

inlay_engine::gpu_struct! {
    /// `CompositePush` of `shaders/composite/composite.wgsl`.
    pub struct CompositePush = "composite/composite.wgsl" : "CompositePush" {
        /// Image width.
        pub width: u32,
        /// Image height.
        pub height: u32,
        /// 1: the object over the unclipped field (occlusion off).
        pub object_front: u32,
    }
}

/// The composite pass: its name, Table 1 module and effect switch.
pub const COMPOSITE_INFO: PassInfo = PassInfo {
    name: "composite",
    module: Table1Module::Compositing,
    switch: Some(crate::march::OCCLUSION_SWITCH),
};

/// The compositing pass's name in the frame graph (and in timings and
/// traces).
pub const COMPOSITE: &str = COMPOSITE_INFO.name;

/// Format of the composited image.
pub const COMPOSITE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// Premultiplied "over": `front + (1 − front.a)·back` (colour and coverage).
pub fn composite_over(front: [f32; 4], back: [f32; 4]) -> [f32; 4] {
    std::array::from_fn(|i| front[i] + (1.0 - front[3]) * back[i])
}

/// The field's colour darkened by the cast-shadow factor `rho` (eq. 7),
/// its opacity kept: only the field's part of the pixel is shadowed.
pub fn composite_shade_field(field: [f32; 4], rho: [f32; 3]) -> [f32; 4] {
    [
        field[0] * rho[0],
        field[1] * rho[1],
        field[2] * rho[2],
        field[3],
    ]
}

/// The composited image, the size of `field`, with its width and height.
fn output_image(graph: &mut FrameGraph, field: ImageHandle) -> (ImageHandle, u32, u32) {
    let (width, height) = graph
        .image_desc(field)
        .map_or((1, 1), |d| (d.width, d.height));
    let desc = ImageDesc {
        width,
        height,
        format: COMPOSITE_FORMAT,
    };
    (graph.create_image("composite", desc), width, height)
}

/// The compositing pipelines (without and with a cast shadow, and the
/// shadowed field alone).
pub struct CompositePass {
    pipeline: Arc<ComputePipeline>,
    shadowed: Arc<ComputePipeline>,
    field_shadowed: Arc<ComputePipeline>,
}

/// Which layer is in front when the object is composited.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layering {
    /// The field, clipped at the object, over the object (eq. 6): the
    /// field occludes the object.
    FieldOverObject,
    /// The object over the unclipped field (occlusion turned off).
    ObjectOverField,
}

impl CompositePass {
    /// Compiles the pass.
    pub fn new(ctx: &Arc<Context>, lib: &ShaderLibrary) -> anyhow::Result<Self> {
        let build = |entry: &str| -> anyhow::Result<Arc<ComputePipeline>> {
            Ok(lib.compute_pipeline(ctx, "composite/composite.wgsl", entry, &[])?)
        };
        Ok(Self {
            pipeline: build("main")?,
            shadowed: build("main_shadowed")?,
            field_shadowed: build("main_field_shadowed")?,
        })
    }

    /// Adds `composite`: `field` (Ĉ, Ô), its colour multiplied by the
    /// cast-shadow factor image `shadow` when given, over `object` (I_v,
    /// coverage).
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        field: ImageHandle,
        object: ImageHandle,
        shadow: Option<ImageHandle>,
    ) -> ImageHandle {
        self.add_layered(graph, field, object, shadow, Layering::FieldOverObject)
    }

    /// Adds `composite` with the layers in the order `layering` says.
    pub fn add_layered(
        &self,
        graph: &mut FrameGraph,
        field: ImageHandle,
        object: ImageHandle,
        shadow: Option<ImageHandle>,
        layering: Layering,
    ) -> ImageHandle {
        let (mut out, width, height) = output_image(graph, field);
        let push = CompositePush {
            width,
            height,
            object_front: (layering == Layering::ObjectOverField) as u32,
        };
        let pipeline = match shadow {
            Some(_) => &self.shadowed,
            None => &self.pipeline,
        };
        graph
            .compute(COMPOSITE, pipeline)
            .read("field_colour", field)
            .read("object_colour", object)
            .read_opt("shadow", shadow)
            .write("out_colour", &mut out)
            .push(&push)
            .threads([width, height, 1]);
        out
    }

    /// Adds `composite` for a frame without an object on screen: the
    /// field's colour darkened by `shadow` (an object off screen can still
    /// shadow what is on it).
    pub fn add_field_shadowed(
        &self,
        graph: &mut FrameGraph,
        field: ImageHandle,
        shadow: ImageHandle,
    ) -> ImageHandle {
        let (mut out, width, height) = output_image(graph, field);
        graph
            .compute(COMPOSITE, &self.field_shadowed)
            .read("field_colour", field)
            .read("shadow", shadow)
            .write("out_colour", &mut out)
            .push(&CompositePush {
                width,
                height,
                object_front: 0,
            })
            .threads([width, height, 1]);
        out
    }
}

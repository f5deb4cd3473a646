//! The compositing pass (`composite`, compute; METHOD.md eq. 6): the field
//! rendered with object clipping (premultiplied colour I_c, opacity I_α)
//! over the object's radiance I_v, I = I_c + (1 − I_α)·I_v, so the field
//! hides the object fully or partly, the field's colour first darkened by
//! the cast shadow ρ when there is one. With occlusion off the object goes
//! over the unclipped field; with no object on screen only the shadow is
//! applied. The cast shadow's last level may be blended here as the
//! image is composited ([`CompositePass::add_blended`], the pixels it
//! flags composited again by `composite-refined`), and the object layer is
//! read over its own pixels alone ([`ObjectLayer`]). [`composite_over`] and
//! [`composite_shade_field`] are the CPU mirrors of
//! `shaders/composite/over.wgsl`.

use crate::frame::meta::{PassInfo, Table1Module};
use std::sync::Arc;

use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, ComputePipeline, Context, ImageDesc};

inlay_engine::gpu_struct! {
    /// `CompositePush` of `shaders/composite/push.wgsl` (the push block of
    /// `composite.wgsl` and `refined.wgsl`).
    pub struct CompositePush = "composite/push.wgsl" : "CompositePush" {
        /// Image width.
        pub width: u32,
        /// Image height.
        pub height: u32,
        /// 1: the object over the unclipped field (occlusion off).
        pub object_front: u32,
        /// The scale of the cast shadow's blocks blended as the image is
        /// composited ([`ShadowBlocks`]; 0 otherwise).
        pub scale: u32,
        /// Largest spread of the blocks' ρ a pixel blends before it is
        /// refined (≥ 1: none).
        pub refine_spread: f32,
        /// The object layer's pixels ([`ObjectLayer::region`]): first
        /// column.
        pub object_x0: u32,
        /// First row.
        pub object_y0: u32,
        /// Column past the last.
        pub object_x1: u32,
        /// Row past the last.
        pub object_y1: u32,
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

/// The pass compositing again the pixels `shadow-refine` took exactly
/// after [`CompositePass::add_blended`]: its name, Table 1 module and
/// effect switch.
pub const COMPOSITE_REFINED_INFO: PassInfo = PassInfo {
    name: "composite-refined",
    module: Table1Module::Compositing,
    switch: Some(crate::shadow::CAST_SHADOW_SWITCH),
};

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
/// shadowed field alone; the shadow at full resolution or blended from
/// its last level's blocks, and the refined pixels composited again).
pub struct CompositePass {
    pipeline: Arc<ComputePipeline>,
    shadowed: Arc<ComputePipeline>,
    field_shadowed: Arc<ComputePipeline>,
    /// Blending the last level: [with an object, the field alone] ×
    /// [without, with a refinement list].
    upsampled: [[Arc<ComputePipeline>; 2]; 2],
    refined: Arc<ComputePipeline>,
    field_refined: Arc<ComputePipeline>,
}

/// The cast shadow's last level as [`CompositePass::add_blended`] takes
/// it: ρ at one pixel of each `scale` × `scale` block (its source pixel's
/// depth in alpha, as `shadow-upsample` writes it), blended at each pixel
/// as `shadow-upsample` would bring it to full resolution
/// ([`crate::shadow::upsample::upsample_level`]), with the march's depth
/// to weigh the blocks by.
#[derive(Debug, Clone, Copy)]
pub struct ShadowBlocks {
    /// ρ at the blocks.
    pub image: ImageHandle,
    /// The blocks' size in pixels (> 1).
    pub scale: u32,
    /// The march's depth image (D̂).
    pub field_depth: ImageHandle,
    /// Largest spread of the blocks' ρ a pixel blends before it is listed
    /// for refinement (≥ 1: none).
    pub refine_spread: f32,
}

/// The pixels [`CompositePass::add_blended`] flagged for refinement: the
/// list it appended them to (`shadow-refine`'s) and the full-resolution
/// image holding, at those pixels only, their blended ρ, which the
/// refinement replaces before [`CompositePass::add_refined`].
#[derive(Debug, Clone, Copy)]
pub struct FlaggedPixels {
    /// The list (count, indices y · width + x, indirect arguments).
    pub list: crate::shadow::cast::PixelList,
    /// ρ at the listed pixels.
    pub rho: ImageHandle,
}

/// The objects' radiance and coverage as `object-shade` leaves it
/// ([`crate::shade::ShadePass::add`]): defined over `region` alone (x0,
/// y0, x1, y1, the ends exclusive; None: the whole image), the union of
/// the shown objects' bounding spheres' pixels, and transparent beyond
/// it.
#[derive(Debug, Clone, Copy)]
pub struct ObjectLayer {
    /// The objects' colour (premultiplied) and coverage.
    pub image: ImageHandle,
    /// The pixels it can cover.
    pub region: Option<[u32; 4]>,
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
            upsampled: [
                [build("main_upsampled")?, build("main_upsampled_listed")?],
                [
                    build("main_field_upsampled")?,
                    build("main_field_upsampled_listed")?,
                ],
            ],
            refined: lib.compute_pipeline(ctx, "composite/refined.wgsl", "main", &[])?,
            field_refined: lib.compute_pipeline(
                ctx,
                "composite/refined.wgsl",
                "main_field",
                &[],
            )?,
        })
    }

    /// Adds `composite`: `field` (Ĉ, Ô), its colour multiplied by the
    /// cast-shadow factor image `shadow` when given, over `object` (I_v,
    /// coverage).
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        field: ImageHandle,
        object: ObjectLayer,
        shadow: Option<ImageHandle>,
    ) -> ImageHandle {
        self.add_layered(graph, field, object, shadow, Layering::FieldOverObject)
    }

    /// Adds `composite` with the layers in the order `layering` says.
    pub fn add_layered(
        &self,
        graph: &mut FrameGraph,
        field: ImageHandle,
        object: ObjectLayer,
        shadow: Option<ImageHandle>,
        layering: Layering,
    ) -> ImageHandle {
        let (mut out, width, height) = output_image(graph, field);
        let push = CompositePush::new(width, height, layering, Some(object));
        let pipeline = match shadow {
            Some(_) => &self.shadowed,
            None => &self.pipeline,
        };
        graph
            .compute(COMPOSITE, pipeline)
            .read("field_colour", field)
            .read("object_colour", object.image)
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
            .push(&CompositePush::new(
                width,
                height,
                Layering::FieldOverObject,
                None,
            ))
            .threads([width, height, 1]);
        out
    }

    /// Adds `composite` with the cast shadow taken from its last level's
    /// blocks (`shadow`), blended at each pixel as it is composited, over
    /// `object` when given (layered as `layering` says) or the shadowed
    /// field alone. Where the blocks' spread asks for refinement
    /// (`shadow.refine_spread` < 1), the pixels the blend flags are
    /// returned: refine them, then composite them again with
    /// [`Self::add_refined`].
    pub fn add_blended(
        &self,
        graph: &mut FrameGraph,
        field: ImageHandle,
        object: Option<ObjectLayer>,
        shadow: ShadowBlocks,
        layering: Layering,
    ) -> (ImageHandle, Option<FlaggedPixels>) {
        let (mut out, width, height) = output_image(graph, field);
        let push = CompositePush {
            scale: shadow.scale,
            refine_spread: shadow.refine_spread.min(1.0),
            ..CompositePush::new(width, height, layering, object)
        };
        let refines = shadow.refine_spread < 1.0;
        let mut flagged = refines.then(|| FlaggedPixels {
            list: crate::shadow::cast::PixelList::new(
                graph,
                "shadow-refine",
                width as u64 * height as u64,
            ),
            rho: graph.create_image(
                "shadow-refined",
                ImageDesc {
                    width,
                    height,
                    format: crate::shadow::SHADOW_FORMAT,
                },
            ),
        });
        let pipeline = &self.upsampled[object.is_none() as usize][refines as usize];
        let mut pass = graph
            .compute(COMPOSITE, pipeline)
            .read("field_colour", field)
            .read("field_depth", shadow.field_depth)
            .read("low_shadow", shadow.image)
            .read_opt("object_colour", object.map(|o| o.image))
            .write("out_colour", &mut out)
            .push(&push);
        if let Some(f) = flagged.as_mut() {
            pass = pass
                .read_write("refine_count", &mut f.list.count)
                .write("refine_list", &mut f.list.pixels)
                .read_write("refine_args", &mut f.list.args)
                .write("refined", &mut f.rho);
        }
        pass.threads([width, height, 1]);
        (out, flagged)
    }

    /// Adds `composite-refined`: the pixels of `flagged` composited again
    /// into `out` (what [`Self::add_blended`] returned, with the same
    /// `field`, `object` and `layering`), with the ρ the refinement took
    /// there.
    pub fn add_refined(
        &self,
        graph: &mut FrameGraph,
        out: &mut ImageHandle,
        field: ImageHandle,
        object: Option<ObjectLayer>,
        flagged: FlaggedPixels,
        layering: Layering,
    ) {
        let (width, height) = graph
            .image_desc(field)
            .map_or((1, 1), |d| (d.width, d.height));
        let pipeline = match object {
            Some(_) => &self.refined,
            None => &self.field_refined,
        };
        graph
            .compute(COMPOSITE_REFINED_INFO.name, pipeline)
            .read("field_colour", field)
            .read_opt("object_colour", object.map(|o| o.image))
            .read("refined", flagged.rho)
            .read("refine_count", flagged.list.count)
            .read("refine_list", flagged.list.pixels)
            .read_write("recomposited", out)
            .push(&CompositePush::new(width, height, layering, object))
            .indirect(flagged.list.args, 0);
    }
}

impl CompositePush {
    /// The push block of a `width` × `height` composite layered as
    /// `layering` says, over `object` if any, with no blocks to blend.
    pub fn new(width: u32, height: u32, layering: Layering, object: Option<ObjectLayer>) -> Self {
        let region = object
            .and_then(|o| o.region)
            .unwrap_or([0, 0, width, height]);
        Self {
            width,
            height,
            object_front: (layering == Layering::ObjectOverField) as u32,
            scale: 0,
            refine_spread: 1.0,
            object_x0: region[0],
            object_y0: region[1],
            object_x1: region[2],
            object_y1: region[3],
        }
    }
}

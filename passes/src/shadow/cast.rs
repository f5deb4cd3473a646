//! The cast-shadow pass (`cast-shadow`, compute; METHOD.md §4.4 step 5):
//! ρ per pixel from the field's depth and density gradient, the object's
//! fitted lighting and its SSDF field (`shaders/shadow/cast.wgsl`, mirrored
//! by [`super::cast_shadow_factor`]). Per object, in two stages under the
//! one name: `main_classify` over the image at the cast scale writes ρ = 1
//! where the object can block under the tolerance of a point's light
//! without the local lights', and lists the other pixels; `main_listed`
//! takes ρ in full at the listed pixels alone (an indirect dispatch).
//! Lavapipe gives every invocation of the full shader a fixed cost, even
//! one that returns at once, so it runs only where a shadow may fall. Each
//! object after the first multiplies the previous object's ρ. Where the
//! object's light ends in direct lobes (too sharp for the fit),
//! `shaders/shadow/cast_direct.wgsl` ray-casts their shadows against the
//! object's mesh ([`super::direct`]).

use crate::frame::meta::{Effect, EffectSwitch, PassInfo, Table1Module};
use std::sync::Arc;

use inlay_engine::graph::{BufferHandle, FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, ComputePipeline, Context, ImageDesc};

use super::gpu::{shadow_defines, SsdfBindings};
use crate::camera::{CameraFrame, CameraRays};
use crate::composite::{CompositePass, Layering, ObjectLayer, ShadowBlocks};
use crate::field::GpuGridField;
use crate::lighting::LightLobes;
use crate::march::{MarchKnobs, MarchOutputs};

/// The fitted lobes `shaders/shadow/cast_body.wgsl` can take: it keeps the
/// ones a point's SSDF must be read for as the bits of two u32s.
pub const MAX_CAST_FITTED_LOBES: u32 = 64;

// Every fit the knobs allow fits those bits.
const _: () = assert!(crate::sgfit::MAX_LOBES <= MAX_CAST_FITTED_LOBES);

inlay_engine::gpu_struct! {
    /// `CastPush` of `shaders/shadow/cast_body.wgsl`.
    pub struct CastPush = "shadow/cast.wgsl" : "CastPush" {
        /// The camera.
        pub camera: CameraRays,
        /// Step of the field's density-gradient normal (world units).
        pub normal_step: f32,
        /// Lobes that light the object.
        pub light_count: u32,
        /// Direct lobes at the end of those.
        pub direct_lobes: u32,
        /// Rays per direct lobe.
        pub direct_rays: u32,
        /// Local lights at the end of the direct lobes.
        pub local_count: u32,
        /// Side of each local light's rays.
        pub local_side: u32,
        /// The field's march step, for a pixel whose point at D̂/Ô lies
        /// off any surface (behind glass) and is marched again.
        pub march_step: f32,
        /// The march's early-termination transmittance.
        pub march_termination: f32,
        /// ρ is taken at one pixel of each scale × scale block.
        pub scale: u32,
        /// Padding.
        pub pad0: u32,
        /// Padding.
        pub pad1: u32,
        /// Padding.
        pub pad2: u32,
    }
}

inlay_engine::gpu_struct! {
    /// `UpsamplePush` of `shaders/shadow/upsample.wgsl`.
    pub struct UpsamplePush = "shadow/upsample.wgsl" : "UpsamplePush" {
        /// Full-resolution width.
        pub width: u32,
        /// Full-resolution height.
        pub height: u32,
        /// The cast shadow's scale.
        pub scale: u32,
        /// Largest spread of the blocks' ρ a pixel blends before
        /// `shadow-refine` takes it exactly (≥ 1: none).
        pub refine_spread: f32,
        /// The output's scale (1: full resolution), below `scale`.
        pub out_scale: u32,
        /// Padding.
        pub pad0: u32,
        /// Padding.
        pub pad1: u32,
        /// Padding.
        pub pad2: u32,
    }
}

/// The pass bringing a cast shadow taken at a fraction of the resolution
/// to a finer one: full resolution, or half its scale when the pass
/// refines ([`super::upsample`]).
pub const SHADOW_UPSAMPLE_INFO: PassInfo = PassInfo {
    name: "shadow-upsample",
    module: Table1Module::Shadow,
    switch: Some(CAST_SHADOW_SWITCH),
};

/// The upsampling pass's name in the frame graph.
pub const SHADOW_UPSAMPLE: &str = SHADOW_UPSAMPLE_INFO.name;

/// The pass taking ρ exactly where `shadow-upsample` flagged a pixel of
/// the image it wrote ([`super::upsample::upsample_level`]).
pub const SHADOW_REFINE_INFO: PassInfo = PassInfo {
    name: "shadow-refine",
    module: Table1Module::Shadow,
    switch: Some(CAST_SHADOW_SWITCH),
};

/// The refining pass's name in the frame graph.
pub const SHADOW_REFINE: &str = SHADOW_REFINE_INFO.name;

/// The cast-shadow pass: its name, Table 1 module and effect switch.
pub const CAST_SHADOW_INFO: PassInfo = PassInfo {
    name: "cast-shadow",
    module: Table1Module::Shadow,
    switch: Some(CAST_SHADOW_SWITCH),
};

/// The cast-shadow pass's name in the frame graph (and in timings).
pub const CAST_SHADOW: &str = CAST_SHADOW_INFO.name;

/// The switch that leaves the shadows cast onto the field out (eq. 7-8).
pub const CAST_SHADOW_SWITCH: EffectSwitch = EffectSwitch {
    effect: Effect::CastShadow,
    name: "cast",
    key: "F3",
};

/// Format of the ρ image (rgb: per-channel factor).
pub const SHADOW_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// The cast-shadow pipelines of one kind: first or chained, without or
/// with direct lobes.
struct CastPipelines {
    first: Arc<ComputePipeline>,
    chained: Arc<ComputePipeline>,
    first_direct: Arc<ComputePipeline>,
    chained_direct: Arc<ComputePipeline>,
}

impl CastPipelines {
    fn pick(&self, chained: bool, direct: bool) -> &Arc<ComputePipeline> {
        match (chained, direct) {
            (false, false) => &self.first,
            (true, false) => &self.chained,
            (false, true) => &self.first_direct,
            (true, true) => &self.chained_direct,
        }
    }
}

/// What one object's cast shadow reads (its light, the f_h table, its
/// SSDF).
#[derive(Debug, Clone, Copy)]
pub struct CastInputs {
    /// The lobes that light the object.
    pub lobes: LightLobes,
    /// The f_h table.
    pub fh_table: BufferHandle,
    /// The object's SSDF.
    pub ssdf: SsdfBindings,
}

/// The cast-shadow pipelines: the classification at the cast scale and
/// the full ρ at listed pixels (first or chained, without or with direct
/// lobes), and the upsampling.
pub struct CastShadowPass {
    classify: CastPipelines,
    listed: CastPipelines,
    upsample: Arc<ComputePipeline>,
    upsample_listed: Arc<ComputePipeline>,
    march: MarchKnobs,
    scale: super::CastScale,
    refine_spread: f64,
}

/// A list of pixels ρ is taken at in full (those `main_classify` listed,
/// or those `shadow-upsample` or `composite` flagged for `shadow-refine`):
/// their count, their indices (y · width + x of the image they index), and
/// the indirect dispatch's arguments (one workgroup per 64 of them).
#[derive(Debug, Clone, Copy)]
pub struct PixelList {
    /// The number of pixels listed (one u32).
    pub count: BufferHandle,
    /// Their indices.
    pub pixels: BufferHandle,
    /// The indirect dispatch's workgroup counts (three u32).
    pub args: BufferHandle,
}

impl PixelList {
    /// An empty list of up to `capacity` pixels, `name` its buffers'
    /// prefix.
    pub fn new(graph: &mut FrameGraph, name: &str, capacity: u64) -> Self {
        Self {
            count: graph.upload_buffer(&format!("{name}-count"), vec![0; 4]),
            pixels: graph.create_buffer(&format!("{name}-list"), 4 * capacity),
            args: graph.upload_buffer(
                &format!("{name}-args"),
                [0u32, 1, 1].iter().flat_map(|v| v.to_le_bytes()).collect(),
            ),
        }
    }
}

impl CastShadowPass {
    /// Compiles the pass; a pixel whose point lies off any surface is
    /// marched again with `march` ([`super::shadow_point`]); ρ is taken at
    /// one pixel of each s × s block, s as `scale` says for the frame's
    /// image ([`super::CastScale::at`]; 1: every pixel), and
    /// brought back by [`Self::finish`], which takes it exactly where the
    /// blocks a pixel blends spread by more than `refine_spread` (≥ 1:
    /// nowhere).
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        march: MarchKnobs,
        scale: super::CastScale,
        refine_spread: f64,
    ) -> anyhow::Result<Self> {
        if let super::CastScale::Fixed(s) = scale {
            anyhow::ensure!(
                (1..=super::MAX_CAST_SCALE).contains(&s),
                "cast-shadow scale {s}: must be in 1..={}",
                super::MAX_CAST_SCALE
            );
        }
        let mut defines = shadow_defines();
        defines.push(inlay_engine::shader::Define::Bool(
            "SKIP_EMPTY",
            march.skip_empty,
        ));
        let build = |file: &str, entry: &str| -> anyhow::Result<Arc<ComputePipeline>> {
            Ok(lib.compute_pipeline(ctx, file, entry, &defines)?)
        };
        let pipelines = |first: &str, chained: &str| -> anyhow::Result<CastPipelines> {
            Ok(CastPipelines {
                first: build("shadow/cast.wgsl", first)?,
                chained: build("shadow/cast.wgsl", chained)?,
                first_direct: build("shadow/cast_direct.wgsl", first)?,
                chained_direct: build("shadow/cast_direct.wgsl", chained)?,
            })
        };
        Ok(Self {
            march,
            classify: pipelines("main_classify", "main_classify_chained")?,
            listed: pipelines("main_listed", "main_listed_chained")?,
            upsample: build("shadow/upsample.wgsl", "main")?,
            upsample_listed: build("shadow/upsample.wgsl", "main_listed")?,
            scale,
            refine_spread,
        })
    }

    /// The scale ρ is taken at for a `width` × `height` image.
    pub fn scale_at(&self, width: u32, height: u32) -> u32 {
        self.scale.at(width, height)
    }

    /// Whether [`Self::finish`] refines.
    pub fn refines(&self) -> bool {
        !self.scale.is_full() && self.refine_spread < 1.0
    }

    /// The full-resolution ρ from the last [`Self::add`]'s `low` image: as
    /// it is at scale 1, else through `shadow-upsample` and, when the pass
    /// refines, one `shadow-refine` per object of `objects` (those `low`
    /// chained, in order), at each scale [`super::upsample::next_level`]
    /// gives in turn (the f64 mirror: [`super::upsample::refine_levels`]).
    pub fn finish(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        camera: &CameraFrame,
        march: &MarchOutputs,
        low: ImageHandle,
        objects: &[CastInputs],
    ) -> ImageHandle {
        let levels = Levels { low, objects };
        self.levels_down_to(graph, field, camera, march, levels, 1)
            .0
    }

    /// The frame composited with the ρ of the last [`Self::add`]'s `low`
    /// image, as [`Self::finish`] would bring it to full resolution but
    /// for its last level: that level's blocks are blended as the image
    /// is composited ([`CompositePass::add_blended`]), and the pixels the
    /// blend flags refined (one `shadow-refine` per object of `objects`)
    /// and composited again ([`CompositePass::add_refined`]), so ρ at full
    /// resolution is never written out. The march's `field` over `object`
    /// (as `layering` says), or the shadowed field alone without one.
    #[allow(clippy::too_many_arguments)]
    pub fn composite(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        camera: &CameraFrame,
        march: &MarchOutputs,
        (low, objects): (ImageHandle, &[CastInputs]),
        composite: &CompositePass,
        (object, layering): (Option<ObjectLayer>, Layering),
    ) -> ImageHandle {
        let levels = Levels { low, objects };
        let (image, scale) = self.levels_down_to(graph, field, camera, march, levels, 2);
        if scale == 1 {
            return match object {
                Some(o) => {
                    composite.add_layered(graph, march.colour_opacity, o, Some(image), layering)
                }
                None => composite.add_field_shadowed(graph, march.colour_opacity, image),
            };
        }
        let blocks = ShadowBlocks {
            image,
            scale,
            field_depth: march.depth,
            refine_spread: if self.refines() {
                self.refine_spread.min(1.0) as f32
            } else {
                1.0
            },
        };
        let (mut out, flagged) =
            composite.add_blended(graph, march.colour_opacity, object, blocks, layering);
        if let Some(mut flagged) = flagged {
            for (i, o) in objects.iter().enumerate() {
                let mut target = Target::Listed {
                    image: flagged.rho,
                    list: flagged.list,
                    chained: i > 0,
                    scale: 1,
                };
                flagged.rho = self.dispatch(graph, field, camera, march, *o, &mut target);
            }
            composite.add_refined(
                graph,
                &mut out,
                march.colour_opacity,
                object,
                flagged,
                layering,
            );
        }
        out
    }

    /// `levels.low` brought down a level at a time ([`Self::finish`]) as
    /// long as the next level's scale is at least `last`: the image
    /// reached and its scale (1 at full resolution; the scale `low` was
    /// taken at, when the next level lies below `last`).
    fn levels_down_to(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        camera: &CameraFrame,
        march: &MarchOutputs,
        levels: Levels<'_>,
        last: u32,
    ) -> (ImageHandle, u32) {
        let (width, height) = (camera.width, camera.height);
        let mut scale = self.scale_at(width, height);
        let mut image = levels.low;
        while scale > 1 {
            // With refinement, each image is brought to one of half its
            // scale and refined there, so that the next's blends span
            // fewer pixels; without, to full resolution at once.
            let out_scale = super::upsample::next_level(scale, self.refines());
            if out_scale < last {
                break;
            }
            image = self.upsample_level(
                graph,
                field,
                camera,
                march,
                (image, scale),
                out_scale,
                levels.objects,
            );
            scale = out_scale;
        }
        (image, scale)
    }

    /// One level of [`Self::finish`]: `low` (ρ at its scale) brought to
    /// `out_scale` by `shadow-upsample` and, when the pass refines, taken
    /// exactly by one `shadow-refine` per object of `objects` at the
    /// pixels it flagged.
    #[allow(clippy::too_many_arguments)]
    fn upsample_level(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        camera: &CameraFrame,
        march: &MarchOutputs,
        (low, scale): (ImageHandle, u32),
        out_scale: u32,
        objects: &[CastInputs],
    ) -> ImageHandle {
        let (width, height) = (camera.width, camera.height);
        let (out_width, out_height) = super::upsample::low_size(width, height, out_scale);
        let mut up = graph.create_image(
            if out_scale == 1 {
                "shadow-full"
            } else {
                "shadow-level"
            },
            ImageDesc {
                width: out_width,
                height: out_height,
                format: SHADOW_FORMAT,
            },
        );
        let push = UpsamplePush {
            width,
            height,
            scale,
            refine_spread: self.refine_spread.min(1.0) as f32,
            out_scale,
            pad0: 0,
            pad1: 0,
            pad2: 0,
        };
        // The list shadow-refine runs over.
        let mut list = self
            .refines()
            .then(|| PixelList::new(graph, "shadow-refine", out_width as u64 * out_height as u64));
        let pipeline = match list {
            Some(_) => &self.upsample_listed,
            None => &self.upsample,
        };
        let mut upsample = graph
            .compute(SHADOW_UPSAMPLE, pipeline)
            .read("field_colour", march.colour_opacity)
            .read("field_depth", march.depth)
            .read("low_shadow", low)
            .write("out_shadow", &mut up)
            .push(&push);
        if let Some(l) = list.as_mut() {
            upsample = upsample
                .read_write("refine_count", &mut l.count)
                .write("refine_list", &mut l.pixels)
                .read_write("refine_args", &mut l.args);
        }
        upsample.threads([out_width, out_height, 1]);
        let Some(list) = list else {
            return up;
        };
        for (i, o) in objects.iter().enumerate() {
            let mut target = Target::Listed {
                image: up,
                list,
                chained: i > 0,
                scale: out_scale,
            };
            up = self.dispatch(graph, field, camera, march, *o, &mut target);
        }
        up
    }

    /// Adds `cast-shadow` for one object lit by `lobes`, multiplying
    /// `previous` (another object's ρ) when given; returns the ρ image.
    #[allow(clippy::too_many_arguments)]
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        camera: &CameraFrame,
        march: &MarchOutputs,
        lobes: LightLobes,
        fh_table: BufferHandle,
        ssdf: SsdfBindings,
        previous: Option<ImageHandle>,
    ) -> ImageHandle {
        let inputs = CastInputs {
            lobes,
            fh_table,
            ssdf,
        };
        let scale = self.scale_at(camera.width, camera.height);
        let (width, height) = super::upsample::low_size(camera.width, camera.height, scale);
        let list = PixelList::new(graph, "cast-shadow", width as u64 * height as u64);
        let mut classify = Target::Classify { previous, list };
        let image = self.dispatch(graph, field, camera, march, inputs, &mut classify);
        let Target::Classify { list, .. } = classify else {
            unreachable!("a classification stays one");
        };
        let mut listed = Target::Listed {
            image,
            list,
            chained: previous.is_some(),
            scale,
        };
        self.dispatch(graph, field, camera, march, inputs, &mut listed)
    }

    /// One object's `cast-shadow` stage (at the cast scale) or
    /// `shadow-refine` (at full resolution, in place), as `target` says; a
    /// classification's list is left in `target` as the pass wrote it.
    fn dispatch(
        &self,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        camera: &CameraFrame,
        march: &MarchOutputs,
        inputs: CastInputs,
        target: &mut Target,
    ) -> ImageHandle {
        let frame_scale = self.scale_at(camera.width, camera.height);
        let scale = match *target {
            Target::Classify { .. } => frame_scale,
            Target::Listed { scale, .. } => scale,
        };
        let (width, height) = super::upsample::low_size(camera.width, camera.height, scale);
        let grid = field.import(graph);
        let created = match *target {
            Target::Classify { .. } => Some(graph.create_image(
                "shadow",
                ImageDesc {
                    width,
                    height,
                    format: SHADOW_FORMAT,
                },
            )),
            Target::Listed { .. } => None,
        };
        let step = (field.bounds.size() / (field.resolution.as_dvec3() - 1.0)).min_element() as f32;
        let CastInputs {
            lobes,
            fh_table,
            ssdf,
        } = inputs;
        let direct = lobes.direct;
        let fitted = lobes.count - direct.map_or(0, |d| d.lobes).min(lobes.count);
        assert!(
            fitted <= MAX_CAST_FITTED_LOBES,
            "the cast shadow takes at most {MAX_CAST_FITTED_LOBES} fitted lobes, given {fitted}"
        );
        let push = CastPush {
            camera: camera.rays(),
            normal_step: step,
            light_count: lobes.count,
            direct_lobes: direct.map_or(0, |d| d.lobes),
            direct_rays: direct.map_or(0, |d| d.rays_per_lobe),
            local_count: direct.map_or(0, |d| d.local.count),
            local_side: direct.map_or(1, |d| d.local.side),
            march_step: self.march.step(field.diagonal) as f32,
            march_termination: self.march.termination as f32,
            scale,
            pad0: 0,
            pad1: 0,
            pad2: 0,
        };
        let (name, pipeline) = match *target {
            Target::Classify { previous, .. } => (
                CAST_SHADOW,
                self.classify.pick(previous.is_some(), direct.is_some()),
            ),
            Target::Listed { chained, scale, .. } => (
                if scale < frame_scale {
                    SHADOW_REFINE
                } else {
                    CAST_SHADOW
                },
                self.listed.pick(chained, direct.is_some()),
            ),
        };
        let pass = grid
            .bind(graph.compute(name, pipeline))
            .read("field_colour", march.colour_opacity)
            .read("field_depth", march.depth)
            .read("light_lobes", lobes.buffer)
            .read("fh_table", fh_table)
            .read("ssdf", ssdf.object)
            .read("objects", ssdf.records)
            .read("ssdf_rows", ssdf.rows)
            .read("ssdf_coefs", ssdf.coefs)
            .read("bvh_nodes", ssdf.bvh_nodes)
            .read("bvh_triangles", ssdf.bvh_triangles)
            .read_opt("sharp_rays", direct.map(|d| d.rays))
            .read_opt("local_lights", direct.map(|d| d.local.lights))
            .push(&push);
        match target {
            Target::Classify { previous, list } => {
                let mut out = created.expect("created above for a classification");
                pass.read_opt("previous", *previous)
                    .write("out_shadow", &mut out)
                    .read_write("cast_count", &mut list.count)
                    .write("cast_list", &mut list.pixels)
                    .read_write("cast_args", &mut list.args)
                    .threads([width, height, 1]);
                out
            }
            Target::Listed { image, list, .. } => {
                pass.read("refine_count", list.count)
                    .read("refine_list", list.pixels)
                    .read_write("refined", image)
                    .indirect(list.args, 0);
                *image
            }
        }
    }
}

/// A cast shadow to bring to full resolution: its image at the frame's
/// cast scale and the objects chained into it.
#[derive(Clone, Copy)]
struct Levels<'a> {
    low: ImageHandle,
    objects: &'a [CastInputs],
}

/// What [`CastShadowPass::dispatch`] writes.
#[derive(Debug, Clone, Copy)]
enum Target {
    /// ρ = 1 at the cast scale where the first test leaves a pixel
    /// unshadowed, times `previous` (another object's) if given, and the
    /// other pixels appended to `list`.
    Classify {
        previous: Option<ImageHandle>,
        list: PixelList,
    },
    /// ρ taken in full at the pixels of `list`, in place in `image` (of
    /// the image at `scale`: the classified one, or the upsampled one at
    /// 1), times what is there when `chained`.
    Listed {
        image: ImageHandle,
        list: PixelList,
        chained: bool,
        scale: u32,
    },
}

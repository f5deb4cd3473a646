//! The cast-shadow pass (`cast-shadow`, compute; METHOD.md §4.4 step 5):
//! ρ per pixel from the field's depth and density gradient, the object's
//! fitted lighting and its SSDF field (`shaders/shadow/cast.wgsl`, mirrored
//! by [`super::cast_shadow_factor`]). One pass per object; each after the
//! first multiplies the previous object's ρ. Where the object's light ends
//! in direct lobes (too sharp for the fit), `shaders/shadow/cast_direct.wgsl`
//! ray-casts their shadows against the object's mesh ([`super::direct`]).

use crate::frame::meta::{Effect, EffectSwitch, PassInfo, Table1Module};
use std::sync::Arc;

use inlay_engine::graph::{BufferHandle, FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, ComputePipeline, Context, ImageDesc};

use super::gpu::{shadow_defines, SsdfBindings};
use crate::camera::{CameraFrame, CameraRays};
use crate::field::GpuGridField;
use crate::lighting::LightLobes;
use crate::march::{MarchKnobs, MarchOutputs};

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
        /// Padding.
        pub pad: u32,
    }
}

/// The pass bringing a cast shadow taken at a fraction of the resolution
/// back to full resolution ([`super::upsample`]).
pub const SHADOW_UPSAMPLE_INFO: PassInfo = PassInfo {
    name: "shadow-upsample",
    module: Table1Module::Shadow,
    switch: Some(CAST_SHADOW_SWITCH),
};

/// The upsampling pass's name in the frame graph.
pub const SHADOW_UPSAMPLE: &str = SHADOW_UPSAMPLE_INFO.name;

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

/// The cast-shadow pipelines: first or chained, without or with direct
/// lobes.
pub struct CastShadowPass {
    first: Arc<ComputePipeline>,
    chained: Arc<ComputePipeline>,
    first_direct: Arc<ComputePipeline>,
    chained_direct: Arc<ComputePipeline>,
    upsample: Arc<ComputePipeline>,
    march: MarchKnobs,
    scale: u32,
}

impl CastShadowPass {
    /// Compiles the pass; a pixel whose point lies off any surface is
    /// marched again with `march` ([`super::shadow_point`]); ρ is taken at
    /// one pixel of each `scale` × `scale` block (1: every pixel) and
    /// brought back by [`Self::finish`].
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        march: MarchKnobs,
        scale: u32,
    ) -> anyhow::Result<Self> {
        anyhow::ensure!(
            (1..=super::MAX_CAST_SCALE).contains(&scale),
            "cast-shadow scale {scale}: must be in 1..={}",
            super::MAX_CAST_SCALE
        );
        let mut defines = shadow_defines();
        defines.push(inlay_engine::shader::Define::Bool(
            "SKIP_EMPTY",
            march.skip_empty,
        ));
        let build = |file: &str, entry: &str| -> anyhow::Result<Arc<ComputePipeline>> {
            Ok(lib.compute_pipeline(ctx, file, entry, &defines)?)
        };
        Ok(Self {
            march,
            first: build("shadow/cast.wgsl", "main")?,
            chained: build("shadow/cast.wgsl", "main_chained")?,
            first_direct: build("shadow/cast_direct.wgsl", "main")?,
            chained_direct: build("shadow/cast_direct.wgsl", "main_chained")?,
            upsample: build("shadow/upsample.wgsl", "main")?,
            scale,
        })
    }

    /// The scale ρ is taken at.
    pub fn scale(&self) -> u32 {
        self.scale
    }

    /// The full-resolution ρ from the last [`Self::add`]'s `low` image: as
    /// it is at scale 1, else through `shadow-upsample`.
    pub fn finish(
        &self,
        graph: &mut FrameGraph,
        camera: &CameraFrame,
        march: &MarchOutputs,
        low: ImageHandle,
    ) -> ImageHandle {
        if self.scale == 1 {
            return low;
        }
        let (width, height) = (camera.width, camera.height);
        let mut out = graph.create_image(
            "shadow-full",
            ImageDesc {
                width,
                height,
                format: SHADOW_FORMAT,
            },
        );
        let push = UpsamplePush {
            width,
            height,
            scale: self.scale,
            pad: 0,
        };
        graph
            .compute(SHADOW_UPSAMPLE, &self.upsample)
            .read("field_colour", march.colour_opacity)
            .read("field_depth", march.depth)
            .read("low_shadow", low)
            .write("out_shadow", &mut out)
            .push(&push)
            .threads([width, height, 1]);
        out
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
        let (width, height) = super::upsample::low_size(camera.width, camera.height, self.scale);
        let grid = field.import(graph);
        let out = graph.create_image(
            "shadow",
            ImageDesc {
                width,
                height,
                format: SHADOW_FORMAT,
            },
        );
        let step = (field.bounds.size() / (field.resolution.as_dvec3() - 1.0)).min_element() as f32;
        let direct = lobes.direct;
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
            scale: self.scale,
            pad0: 0,
            pad1: 0,
            pad2: 0,
        };
        let pipeline = match (previous.is_some(), direct.is_some()) {
            (false, false) => &self.first,
            (true, false) => &self.chained,
            (false, true) => &self.first_direct,
            (true, true) => &self.chained_direct,
        };
        let mut out = out;
        grid.bind(graph.compute(CAST_SHADOW, pipeline))
            .read("field_colour", march.colour_opacity)
            .read("field_depth", march.depth)
            .read("light_lobes", lobes.buffer)
            .read("fh_table", fh_table)
            .read("ssdf", ssdf.object)
            .read("objects", ssdf.records)
            .read("ssdf_rows", ssdf.rows)
            .read("ssdf_coefs", ssdf.coefs)
            .read_opt("previous", previous)
            .read("bvh_nodes", ssdf.bvh_nodes)
            .read("bvh_triangles", ssdf.bvh_triangles)
            .read_opt("sharp_rays", direct.map(|d| d.rays))
            .read_opt("local_lights", direct.map(|d| d.local.lights))
            .write("out_shadow", &mut out)
            .push(&push)
            .threads([width, height, 1]);
        out
    }
}

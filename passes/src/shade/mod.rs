//! The object's SG shading pass (`object-shade`, compute; METHOD.md eq. 5)
//! over the G-buffer, with the brute-force CPU reference it is judged by
//! ([`shade_probe_reference`]). One dispatch per object shades that
//! object's pixels with its own fitted lobes; the output is the object's
//! radiance I_v with coverage in alpha, before any shadow. With
//! `[shading] field_light` the fitted lobes' diffuse light at each point
//! is scaled by the field's light there ([`field_light`]).

pub mod field_light;
mod reference;

pub use reference::{shade_probe_reference, shade_reference_with};

use crate::frame::meta::{Effect, EffectSwitch, PassInfo, Table1Module};
use std::sync::Arc;

use inlay_engine::graph::{BufferHandle, FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, Buffer, ComputePipeline, Context, ImageDesc};

use crate::brdf::NdfLobes;
use crate::camera::{CameraFrame, CameraRays};
use crate::field::GpuGridField;
use crate::gbuffer::GBuffer;
use crate::lighting::LightLobes;
use crate::march::MarchKnobs;
use crate::shadow::{shadow_defines, SsdfBindings};
use inlay_engine::shader::Define;

inlay_engine::gpu_struct! {
    /// `ShadePush` of `shaders/shade/shade_body.wgsl`.
    pub struct ShadePush = "shade/shade.wgsl" : "ShadePush" {
        /// The camera.
        pub camera: CameraRays,
        /// The object shaded by this dispatch (its G-buffer index).
        pub object_index: f32,
        /// Whether this dispatch clears the pixels no object covers.
        pub write_empty: u32,
        /// Lobes that light the object.
        pub light_count: u32,
        /// Direct lobes at the end of those.
        pub direct_lobes: u32,
        /// Rays per direct lobe.
        pub direct_rays: u32,
        /// Local lights at the end of the direct lobes.
        pub local_count: u32,
        /// Side of each local light's visibility rays.
        pub local_side: u32,
        /// The field's march step (world units).
        pub march_step: f32,
        /// The march's early-termination transmittance.
        pub march_termination: f32,
        /// Side of the field-light rays per tile (0: off).
        pub field_side: u32,
        /// Lobes of L_env in `env_lobes` (what the field-light rays see
        /// past the field).
        pub env_count: u32,
        /// Padding (the struct's size rounds up to 16 bytes).
        pub _pad: u32,
    }
}

/// The object-shade pass: its name, Table 1 module and effect switch.
pub const OBJECT_SHADE_INFO: PassInfo = PassInfo {
    name: "object-shade",
    module: Table1Module::Rendering,
    switch: Some(SELF_SHADOW_SWITCH),
};

/// The shading pass's name in the frame graph (and in timings).
pub const OBJECT_SHADE: &str = OBJECT_SHADE_INFO.name;

/// The switch that leaves the objects' self-shadows out (eq. 9).
pub const SELF_SHADOW_SWITCH: EffectSwitch = EffectSwitch {
    effect: Effect::SelfShadow,
    name: "self-shadow",
    key: "F2",
};

/// Format of the object radiance image.
pub const OBJECT_COLOUR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// One object's self-shadow inputs for [`ShadePass::add`]: the f_h table
/// and its SSDF field's bindings.
#[derive(Debug, Clone, Copy)]
pub struct SelfShadow {
    /// The f_h table.
    pub fh_table: BufferHandle,
    /// The object's SSDF field and per-frame block.
    pub ssdf: SsdfBindings,
}

/// The shading pipelines (without self-shadows; with them from the SSDF;
/// with them from the SSDF and, for direct lobes or the field's light at
/// the point, from rays) and the NDF mixture they use.
pub struct ShadePass {
    pipeline: Arc<ComputePipeline>,
    self_shadowed: Arc<ComputePipeline>,
    self_shadowed_direct: Arc<ComputePipeline>,
    ndf: Arc<Buffer>,
    ndf_lobes: NdfLobes,
    march: MarchKnobs,
    /// Side of the field-light rays per tile (0: the paper's shading).
    field_side: u32,
    /// Bound as the direct lobes' rays, local lights and environment lobes
    /// where an object's light has none but the rays' variant runs.
    no_direct: Arc<Buffer>,
}

impl ShadePass {
    /// Compiles the pass for an `ndf_lobes`-lobe GGX mixture; local lights'
    /// visibility marches the field with `march`.
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        ndf_lobes: u32,
        march: MarchKnobs,
    ) -> anyhow::Result<Self> {
        Self::build(ctx, lib, ndf_lobes, march, "main")
    }

    /// A pass whose output, at the pixels of self-shadowed objects, is the
    /// gain [`field_light`] puts on the fitted lobes' diffuse light with
    /// `side`² rays per tile, in rgb with 1 in alpha (for its test against
    /// the CPU mirror, and for inspection).
    pub fn new_field_gain(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        march: MarchKnobs,
        side: u32,
    ) -> anyhow::Result<Self> {
        Ok(Self::build(ctx, lib, 1, march, "field_gain_only")?.with_field_light(side))
    }

    /// Scales the fitted lobes' diffuse light at each point of a
    /// self-shadowed object by the field's light there, from `side`² rays
    /// per tile ([`field_light`]; 0: off, the paper's shading). It rides
    /// with the self-shadowed variant (its rays start off the surface by
    /// the SSDF's radius): an object drawn without self-shadows is lit by
    /// its lobes alone.
    pub fn with_field_light(mut self, side: u32) -> Self {
        self.field_side = side.min(field_light::MAX_SIDE);
        self
    }

    fn build(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        ndf_lobes: u32,
        march: MarchKnobs,
        direct_entry: &str,
    ) -> anyhow::Result<Self> {
        let ndf = NdfLobes::new(ndf_lobes).map_err(|m| anyhow::anyhow!("ndf_lobes: {m}"))?;
        let bytes: Vec<u8> = ndf.packed().iter().flat_map(|x| x.to_le_bytes()).collect();
        let mut defines = shadow_defines();
        defines.push(Define::Bool("SKIP_EMPTY", march.skip_empty));
        let shadowed = |file: &str, entry: &str| lib.compute_pipeline(ctx, file, entry, &defines);
        Ok(Self {
            pipeline: lib.compute_pipeline(ctx, "shade/shade.wgsl", "main", &[])?,
            self_shadowed: shadowed("shade/shade_self_shadow.wgsl", "main")?,
            self_shadowed_direct: shadowed("shade/shade_self_shadow_direct.wgsl", direct_entry)?,
            ndf: Arc::new(Buffer::with_data(
                ctx,
                "ndf lobes",
                &bytes,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?),
            ndf_lobes: ndf,
            march,
            field_side: 0,
            no_direct: Arc::new(Buffer::with_data(
                ctx,
                "no direct lobes",
                &[0u8; 32],
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?),
        })
    }

    /// The NDF mixture it shades with.
    pub fn ndf_lobes(&self) -> &NdfLobes {
        &self.ndf_lobes
    }

    /// Adds `object-shade`: object i's pixels (index i in the G-buffer) are
    /// shaded with `lobes[i]` (an SG fit's lobe buffer), self-shadowed
    /// (eq. 9) where `self_shadow[i]` is given; local lights are seen
    /// through `field`.
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        camera: &CameraFrame,
        gbuffer: &GBuffer,
        field: &GpuGridField,
        lobes: &[LightLobes],
        self_shadow: &[Option<SelfShadow>],
    ) -> ImageHandle {
        let (width, height) = (camera.width, camera.height);
        let out = graph.create_image(
            "object-colour",
            ImageDesc {
                width,
                height,
                format: OBJECT_COLOUR_FORMAT,
            },
        );
        let ndf = graph.import_buffer(&self.ndf, None);
        let mut out = out;
        let grid = field.import(graph);
        let no_direct = graph.import_buffer(&self.no_direct, None);
        let mut pass = graph.compute_pass(OBJECT_SHADE);
        for (i, l) in lobes.iter().enumerate() {
            let local = l.direct.map(|d| d.local);
            let shadow = self_shadow.get(i).copied().flatten();
            let field_light = self.field_side > 0 && shadow.is_some();
            let push = ShadePush {
                camera: camera.rays(),
                object_index: i as f32,
                write_empty: (i == 0) as u32,
                light_count: l.count,
                direct_lobes: l.direct.map_or(0, |d| d.lobes),
                direct_rays: l.direct.map_or(0, |d| d.rays_per_lobe),
                local_count: local.map_or(0, |x| x.count),
                local_side: local.map_or(1, |x| x.side),
                march_step: self.march.step(field.diagonal) as f32,
                march_termination: self.march.termination as f32,
                field_side: if field_light { self.field_side } else { 0 },
                env_count: l.environment.filter(|_| field_light).map_or(0, |e| e.count),
                _pad: 0,
            };
            let rays = l.direct.is_some() || field_light;
            let pipeline = match (shadow, rays) {
                (Some(_), true) => &self.self_shadowed_direct,
                (Some(_), false) => &self.self_shadowed,
                (None, _) => &self.pipeline,
            };
            // The rays' variant binds the direct lobes' buffers, which an
            // object lit by its fitted lobes alone does not have.
            let filler = (shadow.is_some() && rays && l.direct.is_none()).then_some(no_direct);
            let mut d = grid
                .bind(pass.dispatch(pipeline))
                .read("normal_roughness", gbuffer.normal_roughness)
                .read("albedo_metallic", gbuffer.albedo_metallic)
                .read("distance_id", gbuffer.distance_id)
                .read("light_lobes", l.buffer)
                .read("ndf_lobes", ndf)
                .write("out_object", &mut out)
                .push(&push);
            if let Some(s) = shadow {
                d = d
                    .read("fh_table", s.fh_table)
                    .read("ssdf", s.ssdf.object)
                    .read("objects", s.ssdf.records)
                    .read("ssdf_rows", s.ssdf.rows)
                    .read("ssdf_coefs", s.ssdf.coefs)
                    .read("bvh_nodes", s.ssdf.bvh_nodes)
                    .read("bvh_triangles", s.ssdf.bvh_triangles);
            }
            let env = (shadow.is_some() && rays).then(|| {
                l.environment
                    .filter(|_| field_light)
                    .map_or(no_direct, |e| e.buffer)
            });
            d.read_opt("sharp_rays", l.direct.map(|r| r.rays).or(filler))
                .read_opt("local_lights", local.map(|x| x.lights).or(filler))
                .read_opt("env_lobes", env)
                .threads([width, height, 1]);
        }
        pass.finish();
        out
    }
}

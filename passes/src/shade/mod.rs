//! The object's SG shading pass (`object-shade`, compute; METHOD.md eq. 5)
//! over the G-buffer, with the brute-force CPU reference it is judged by
//! ([`shade_probe_reference`]). One dispatch per object shades that
//! object's pixels with its own fitted lobes; the output is the object's
//! radiance I_v with coverage in alpha, before any shadow.

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
        /// Padding (the struct's size rounds up to 16 bytes).
        pub _pad: [u32; 3],
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
/// with them from the SSDF and, for direct lobes, from rays cast against
/// the mesh) and the NDF mixture they use.
pub struct ShadePass {
    pipeline: Arc<ComputePipeline>,
    self_shadowed: Arc<ComputePipeline>,
    self_shadowed_direct: Arc<ComputePipeline>,
    ndf: Arc<Buffer>,
    ndf_lobes: NdfLobes,
    march: MarchKnobs,
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
        let ndf = NdfLobes::new(ndf_lobes).map_err(|m| anyhow::anyhow!("ndf_lobes: {m}"))?;
        let bytes: Vec<u8> = ndf.packed().iter().flat_map(|x| x.to_le_bytes()).collect();
        let mut defines = shadow_defines();
        defines.push(Define::Bool("SKIP_EMPTY", march.skip_empty));
        let shadowed = |file: &str| lib.compute_pipeline(ctx, file, "main", &defines);
        Ok(Self {
            pipeline: lib.compute_pipeline(ctx, "shade/shade.wgsl", "main", &[])?,
            self_shadowed: shadowed("shade/shade_self_shadow.wgsl")?,
            self_shadowed_direct: shadowed("shade/shade_self_shadow_direct.wgsl")?,
            ndf: Arc::new(Buffer::with_data(
                ctx,
                "ndf lobes",
                &bytes,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?),
            ndf_lobes: ndf,
            march,
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
        let mut pass = graph.compute_pass(OBJECT_SHADE);
        for (i, l) in lobes.iter().enumerate() {
            let local = l.direct.map(|d| d.local);
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
                _pad: [0; 3],
            };
            let shadow = self_shadow.get(i).copied().flatten();
            let pipeline = match (shadow, l.direct) {
                (Some(_), Some(_)) => &self.self_shadowed_direct,
                (Some(_), None) => &self.self_shadowed,
                (None, _) => &self.pipeline,
            };
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
            d.read_opt("sharp_rays", l.direct.map(|r| r.rays))
                .read_opt("local_lights", local.map(|x| x.lights))
                .threads([width, height, 1]);
        }
        pass.finish();
        out
    }
}

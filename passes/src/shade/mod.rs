//! The object's SG shading pass (`object-shade`, compute; METHOD.md eq. 5)
//! over the G-buffer, with the brute-force CPU reference it is judged by
//! ([`shade_probe_reference`]). One dispatch per object shades that
//! object's pixels with its own fitted lobes; the output is the object's
//! radiance I_v with coverage in alpha, before any shadow.

mod reference;

pub use reference::{shade_probe_reference, shade_reference_with};

use std::sync::Arc;

use inlay_engine::graph::{
    Binding, BufferAccess, BufferHandle, FrameGraph, ImageAccess, ImageHandle, PassKind,
};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, Buffer, ComputePipeline, Context, ImageDesc};

use crate::brdf::NdfLobes;
use crate::camera::CameraFrame;
use crate::gbuffer::GBuffer;
use crate::lighting::LightLobes;
use crate::shadow::{shadow_defines, SsdfBindings};

/// The shading pass's name in the frame graph (and in timings).
pub const OBJECT_SHADE: &str = "object-shade";

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
}

impl ShadePass {
    /// Compiles the pass for an `ndf_lobes`-lobe GGX mixture.
    pub fn new(ctx: &Arc<Context>, lib: &ShaderLibrary, ndf_lobes: u32) -> anyhow::Result<Self> {
        let ndf = NdfLobes::new(ndf_lobes).map_err(|m| anyhow::anyhow!("ndf_lobes: {m}"))?;
        let bytes: Vec<u8> = ndf.packed().iter().flat_map(|x| x.to_le_bytes()).collect();
        let shadowed = |file: &str| lib.compute_pipeline(ctx, file, "main", &shadow_defines());
        Ok(Self {
            pipeline: lib.compute_pipeline(ctx, "object/shade.wgsl", "main", &[])?,
            self_shadowed: shadowed("object/shade_self_shadow.wgsl")?,
            self_shadowed_direct: shadowed("object/shade_self_shadow_direct.wgsl")?,
            ndf: Arc::new(Buffer::with_data(
                ctx,
                "ndf lobes",
                &bytes,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?),
            ndf_lobes: ndf,
        })
    }

    /// The NDF mixture it shades with.
    pub fn ndf_lobes(&self) -> &NdfLobes {
        &self.ndf_lobes
    }

    /// Adds `object-shade`: object i's pixels (index i in the G-buffer) are
    /// shaded with `lobes[i]` (an SG fit's lobe buffer), self-shadowed
    /// (eq. 9) where `self_shadow[i]` is given.
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        camera: &CameraFrame,
        gbuffer: &GBuffer,
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
        let mut pass = graph.add_pass(OBJECT_SHADE, PassKind::Compute);
        for img in [
            gbuffer.normal_roughness,
            gbuffer.albedo_metallic,
            gbuffer.distance_id,
        ] {
            pass.image(img, ImageAccess::Sampled);
        }
        let mut declared = Vec::new();
        for l in lobes {
            if !declared.contains(&l.buffer) {
                pass.buffer(l.buffer, BufferAccess::StorageRead);
                declared.push(l.buffer);
            }
        }
        pass.buffer(ndf, BufferAccess::StorageRead);
        for (i, s) in self_shadow.iter().enumerate() {
            let Some(s) = s else { continue };
            let mut reads = vec![s.fh_table, s.ssdf.object, s.ssdf.rows, s.ssdf.coefs];
            if let Some(d) = lobes.get(i).and_then(|l| l.direct) {
                reads.extend([s.ssdf.bvh_nodes, s.ssdf.bvh_triangles, d.rays]);
            }
            for b in reads {
                if !declared.contains(&b) {
                    pass.buffer(b, BufferAccess::StorageRead);
                    declared.push(b);
                }
            }
        }
        let out = pass.image(out, ImageAccess::StorageWrite);
        let shadows = self_shadow.to_vec();
        let g = *gbuffer;
        let lobes = lobes.to_vec();
        let cam = *camera;
        pass.exec(move |ctx| {
            for (i, l) in lobes.iter().enumerate() {
                let push = cam
                    .push_prefix(i as f32)
                    .u32((i == 0) as u32)
                    .u32(l.count)
                    .u32(l.direct.map_or(0, |d| d.lobes))
                    .u32(l.direct.map_or(0, |d| d.rays_per_lobe))
                    .u32(0);
                let mut bindings = vec![
                    Binding::SampledImage(g.normal_roughness),
                    Binding::SampledImage(g.albedo_metallic),
                    Binding::SampledImage(g.distance_id),
                    Binding::StorageBuffer(l.buffer),
                    Binding::StorageBuffer(ndf),
                    Binding::StorageImage(out),
                ];
                let pipeline = match shadows.get(i).copied().flatten() {
                    Some(s) => {
                        bindings.extend([
                            Binding::StorageBuffer(s.fh_table),
                            Binding::StorageBuffer(s.ssdf.object),
                            Binding::StorageBuffer(s.ssdf.rows),
                            Binding::StorageBuffer(s.ssdf.coefs),
                        ]);
                        match l.direct {
                            Some(d) => {
                                bindings.extend([
                                    Binding::StorageBuffer(s.ssdf.bvh_nodes),
                                    Binding::StorageBuffer(s.ssdf.bvh_triangles),
                                    Binding::StorageBuffer(d.rays),
                                ]);
                                &self.self_shadowed_direct
                            }
                            None => &self.self_shadowed,
                        }
                    }
                    None => &self.pipeline,
                };
                ctx.dispatch(
                    pipeline,
                    &bindings,
                    push.bytes(),
                    pipeline.groups_for([width, height, 1]),
                )?;
            }
            Ok(())
        });
        out
    }
}

//! The cast-shadow pass (`cast-shadow`, compute; METHOD.md §4.4 step 5):
//! ρ per pixel from the field's depth and density gradient, the object's
//! fitted lighting and its SSDF field (`shaders/shadow/cast.wgsl`, mirrored
//! by [`super::cast_shadow_factor`]). One pass per object; each after the
//! first multiplies the previous object's ρ. Where the object's light ends
//! in direct lobes (too sharp for the fit), `shaders/shadow/cast_direct.wgsl`
//! ray-casts their shadows against the object's mesh ([`super::direct`]).

use std::sync::Arc;

use inlay_engine::graph::{
    Binding, BufferAccess, BufferHandle, FrameGraph, ImageAccess, ImageHandle, PassKind,
};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, ComputePipeline, Context, ImageDesc};

use super::gpu::{shadow_defines, SsdfBindings};
use crate::camera::CameraFrame;
use crate::field::GpuGridField;
use crate::lighting::LightLobes;
use crate::march::MarchOutputs;

/// The cast-shadow pass's name in the frame graph (and in timings).
pub const CAST_SHADOW: &str = "cast-shadow";

/// Format of the ρ image (rgb: per-channel factor).
pub const SHADOW_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// The cast-shadow pipelines: first or chained, without or with direct
/// lobes.
pub struct CastShadowPass {
    first: Arc<ComputePipeline>,
    chained: Arc<ComputePipeline>,
    first_direct: Arc<ComputePipeline>,
    chained_direct: Arc<ComputePipeline>,
}

impl CastShadowPass {
    /// Compiles the pass.
    pub fn new(ctx: &Arc<Context>, lib: &ShaderLibrary) -> anyhow::Result<Self> {
        let build = |file: &str, entry: &str| -> anyhow::Result<Arc<ComputePipeline>> {
            Ok(lib.compute_pipeline(ctx, file, entry, &shadow_defines())?)
        };
        Ok(Self {
            first: build("shadow/cast.wgsl", "main")?,
            chained: build("shadow/cast.wgsl", "main_chained")?,
            first_direct: build("shadow/cast_direct.wgsl", "main")?,
            chained_direct: build("shadow/cast_direct.wgsl", "main_chained")?,
        })
    }

    /// Adds `cast-shadow` for one object lit by `lobes`, multiplying
    /// `previous` (another object's ρ) when given; returns the ρ image.
    #[allow(clippy::too_many_arguments)]
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        field: &GpuGridField,
        camera: &CameraFrame,
        march: &MarchOutputs,
        lobes: LightLobes,
        fh_table: BufferHandle,
        ssdf: SsdfBindings,
        previous: Option<ImageHandle>,
    ) -> ImageHandle {
        let (width, height) = (camera.width, camera.height);
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
        let push = camera
            .push_prefix(step)
            .u32(lobes.count)
            .u32(direct.map_or(0, |d| d.lobes))
            .u32(direct.map_or(0, |d| d.rays_per_lobe))
            .u32(0)
            .u32(0);
        let mut pass = graph.add_pass(CAST_SHADOW, PassKind::Compute);
        // The occupancy grid is not read (binding 2 is compiled out).
        pass.buffer(grid.info, BufferAccess::Uniform);
        pass.buffer(grid.nodes, BufferAccess::StorageRead);
        pass.image(march.colour_opacity, ImageAccess::Sampled);
        pass.image(march.depth, ImageAccess::Sampled);
        pass.buffer(lobes.buffer, BufferAccess::StorageRead);
        pass.buffer(fh_table, BufferAccess::StorageRead);
        pass.buffer(ssdf.object, BufferAccess::StorageRead);
        pass.buffer(ssdf.rows, BufferAccess::StorageRead);
        pass.buffer(ssdf.coefs, BufferAccess::StorageRead);
        if let Some(p) = previous {
            pass.image(p, ImageAccess::Sampled);
        }
        if let Some(d) = direct {
            for b in [ssdf.bvh_nodes, ssdf.bvh_triangles, d.rays] {
                pass.buffer(b, BufferAccess::StorageRead);
            }
        }
        let out = pass.image(out, ImageAccess::StorageWrite);
        let m = *march;
        let pipeline = match (previous.is_some(), direct.is_some()) {
            (false, false) => &self.first,
            (true, false) => &self.chained,
            (false, true) => &self.first_direct,
            (true, true) => &self.chained_direct,
        };
        pass.exec(move |ctx| {
            let mut bindings = vec![
                Binding::UniformBuffer(grid.info),
                Binding::StorageBuffer(grid.nodes),
                Binding::SampledImage(m.colour_opacity),
                Binding::SampledImage(m.depth),
                Binding::StorageBuffer(lobes.buffer),
                Binding::StorageBuffer(fh_table),
                Binding::StorageBuffer(ssdf.object),
                Binding::StorageBuffer(ssdf.rows),
                Binding::StorageBuffer(ssdf.coefs),
            ];
            if let Some(p) = previous {
                bindings.push(Binding::SampledImage(p));
            }
            bindings.push(Binding::StorageImage(out));
            if let Some(d) = direct {
                bindings.extend([
                    Binding::StorageBuffer(ssdf.bvh_nodes),
                    Binding::StorageBuffer(ssdf.bvh_triangles),
                    Binding::StorageBuffer(d.rays),
                ]);
            }
            ctx.dispatch(
                pipeline,
                &bindings,
                push.bytes(),
                pipeline.groups_for([width, height, 1]),
            )
        });
        out
    }
}

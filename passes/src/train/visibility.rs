//! Every node's visibility over the training rays on the GPU (`train-
//! visibility`, `shaders/train/visibility.wgsl`): what pruning and the
//! sparse stages read. The CPU reference is
//! [`super::prune::node_visibility`]; at 256 nodes it marched the 4.2
//! million rays of DOG's 64 views for most of a training run's minutes.

use std::sync::Arc;

use inlay_engine::graph::{BufferAccess, FrameGraph};
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{vk, Buffer, BufferReadback, Context, Renderer, SubmitSync};

use super::gpu::host_storage;

use crate::field::bricks::BrickLayout;
use crate::field::{FieldLayout, GpuGridField, GridField};
use crate::geometry::Ray;
use crate::march::MarchKnobs;

inlay_engine::gpu_struct! {
    /// `VisibilityPush` of `shaders/train/visibility.wgsl`.
    pub struct VisibilityPush = "train/visibility.wgsl" : "VisibilityPush" {
        /// Rays in this dispatch.
        pub ray_count: u32,
        /// The march's step.
        pub step: f32,
        /// The march's termination transmittance.
        pub termination: f32,
        /// Padding.
        pub pad: u32,
    }
}

/// Name of the pass in the frame graph.
pub const TRAIN_VISIBILITY: &str = "train-visibility";

/// Rays per dispatch (32 bytes each: 32 MiB, well inside a binding).
const RAYS_PER_FRAME: usize = 1 << 20;

/// Each node of `field`'s visibility over `rays` (unit directions), in the
/// field's node order, marched by `knobs` on the GPU; the field uploaded
/// in `layout` (a field that fits only sparsely goes sparse anyway).
pub fn node_visibility_gpu(
    renderer: &mut Renderer,
    lib: &ShaderLibrary,
    field: &GridField,
    rays: &[Ray],
    knobs: &MarchKnobs,
    layout: FieldLayout,
) -> anyhow::Result<Vec<f32>> {
    let ctx = renderer.context().clone();
    let gpu = GpuGridField::upload_as(&ctx, field, layout)?;
    let pipeline = gpu.library(lib).compute_pipeline(
        &ctx,
        "train/visibility.wgsl",
        "main",
        &[Define::Bool("SKIP_EMPTY", knobs.skip_empty)],
    )?;
    let bricks = gpu.sparse.then(|| BrickLayout::of(field));
    let stored = bricks
        .as_ref()
        .map_or(field.nodes.len() as u64, BrickLayout::pool_nodes)
        .max(1);
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER
        | vk::BufferUsageFlags::TRANSFER_SRC
        | vk::BufferUsageFlags::TRANSFER_DST;
    let visibility = Arc::new(Buffer::with_data(
        &ctx,
        "train-visibility",
        &vec![0u8; 4 * stored as usize],
        usage,
    )?);
    let step = knobs.step(field.bounds.diagonal()) as f32;
    for chunk in rays.chunks(RAYS_PER_FRAME) {
        run_chunk(
            renderer,
            &ctx,
            &gpu,
            &pipeline,
            &visibility,
            chunk,
            step,
            knobs,
        )?;
    }
    let readback = BufferReadback::new(&ctx, "train-visibility (readback)", visibility.size())?;
    renderer.begin_frame()?;
    let mut graph = FrameGraph::new();
    let v = graph.import_buffer(&visibility, None);
    readback.add_to_graph(&mut graph, "train-visibility-readback", v);
    renderer.submit(graph, &SubmitSync::none())?;
    renderer.finish()?;
    let stored = readback.read_f32()?;
    Ok(match &bricks {
        None => stored[..field.nodes.len()].to_vec(),
        Some(l) => {
            let r = field.resolution;
            let mut out = vec![0.0f32; field.nodes.len()];
            for z in 0..r.z {
                for y in 0..r.y {
                    for x in 0..r.x {
                        if let Some(p) = l.pool_index(glam::UVec3::new(x, y, z)) {
                            out[field.index(x, y, z)] = stored[p as usize];
                        }
                    }
                }
            }
            out
        }
    })
}

/// One frame: `rays` marched into `visibility`.
#[allow(clippy::too_many_arguments)]
fn run_chunk(
    renderer: &mut Renderer,
    ctx: &Arc<Context>,
    gpu: &GpuGridField,
    pipeline: &Arc<inlay_engine::ComputePipeline>,
    visibility: &Arc<Buffer>,
    rays: &[Ray],
    step: f32,
    knobs: &MarchKnobs,
) -> anyhow::Result<()> {
    let records: Vec<[f32; 4]> = rays
        .iter()
        .flat_map(|r| {
            let (o, d) = (r.origin.as_vec3(), r.dir.as_vec3());
            [[o.x, o.y, o.z, 0.0], [d.x, d.y, d.z, 0.0]]
        })
        .collect();
    let upload = host_storage(ctx, "train-visibility-rays", bytemuck::cast_slice(&records))?;
    renderer.begin_frame()?;
    let mut graph = FrameGraph::new();
    let field = gpu.import(&mut graph);
    let rays_handle = graph.import_buffer(&upload, None);
    let v = graph.import_buffer(visibility, None);
    let push = VisibilityPush {
        ray_count: rays.len() as u32,
        step,
        termination: knobs.termination as f32,
        pad: 0,
    };
    let groups = (rays.len() as u32).div_ceil(64);
    let mut pass = graph.compute_pass(TRAIN_VISIBILITY);
    pass.buffer_at("visibility_rays", rays_handle, BufferAccess::StorageRead);
    pass.buffer_at("visibility", v, BufferAccess::StorageReadWrite);
    field.bind(pass.dispatch(pipeline)).push(&push).groups([
        groups.min(65535),
        groups.div_ceil(65535),
        1,
    ]);
    pass.finish();
    renderer.submit(graph, &SubmitSync::none())?;
    renderer.finish()?;
    Ok(())
}

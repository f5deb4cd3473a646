//! Every node's visibility over the training rays on the GPU (`train-
//! visibility`, `shaders/train/visibility.wgsl`): what pruning and the
//! sparse stages read. The CPU reference is
//! [`super::prune::node_visibility`]; at 256 nodes it marched the 4.2
//! million rays of DOG's 64 views for most of a training run's minutes.

use std::sync::Arc;

use inlay_engine::graph::{BufferAccess, FrameGraph};
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{vk, Buffer, BufferReadback, Context, Renderer, SubmitSync};

use rayon::prelude::*;

use super::gpu::host_storage;
use super::pixels::{pixel_ray, PixelPool};

use crate::dataset::{Dataset, Frame};
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
    let chunks = rays.chunks(RAYS_PER_FRAME).map(<[Ray]>::to_vec);
    visibility_over(renderer, lib, field, chunks, knobs, layout)
}

/// The farthest apart, in node spacings of the marched field, that the
/// rays of one photograph may pass through the bounds for
/// [`pool_visibility_gpu`]: the nearest ray then passes within a quarter
/// of a spacing of each node along the two directions across the rays,
/// where the node's trilinear weight is still about 0.75² of the weight a
/// ray through it gives, so a node seen by any photograph keeps most of
/// the visibility every pixel's ray would give it.
pub const VISIBILITY_RAY_SPACING: f64 = 0.5;

/// The stride of the pixels of `frame` whose rays [`pool_visibility_gpu`]
/// marches through `field` (every stride-th along rows and columns): the
/// largest that keeps neighbouring rays within [`VISIBILITY_RAY_SPACING`]
/// node spacings at the bounds' corner farthest from the camera. 1 where a
/// pixel is that wide already (every pixel of the Cycles sets at every
/// stage); 4 for the first stage of a 128-node run on 800 × 800
/// photographs.
pub fn visibility_stride(frame: &Frame, field: &GridField) -> u32 {
    let spacing = field.spacing().min_element();
    let far = field
        .bounds
        .corners()
        .iter()
        .map(|c| (*c - frame.pose.origin()).length())
        .fold(0.0f64, f64::max);
    let pixel = far / frame.intrinsics.fx.min(frame.intrinsics.fy);
    let stride = (VISIBILITY_RAY_SPACING * spacing / pixel).floor();
    if stride.is_finite() && stride >= 1.0 {
        stride.min(f64::from(u16::MAX)) as u32
    } else {
        1
    }
}

/// Whether pixel `pixel` of a frame `width` wide is one of those a
/// [`visibility_stride`] of `stride` marches: the middle pixel of each
/// stride × stride block.
pub fn marched_at_stride(stride: u32, width: u32, pixel: u32) -> bool {
    let (x, y) = (pixel % width, pixel / width);
    x % stride == stride / 2 && y % stride == stride / 2
}

/// [`node_visibility_gpu`] over the rays through the centres of `pool`'s
/// pixels, each frame's thinned to its [`visibility_stride`], made a
/// dispatch's worth at a time: a capture of 100 photographs of 800 × 800
/// has 64 million pixels, 3 GiB as one list of rays, and marching them all
/// took most of a 64-node run's time.
pub fn pool_visibility_gpu(
    renderer: &mut Renderer,
    lib: &ShaderLibrary,
    field: &GridField,
    dataset: &Dataset,
    pool: &PixelPool,
    knobs: &MarchKnobs,
    layout: FieldLayout,
) -> anyhow::Result<Vec<f32>> {
    let strides: Vec<u32> = dataset
        .frames
        .iter()
        .map(|f| visibility_stride(f, field))
        .collect();
    let chunks = pool.pixels.chunks(RAYS_PER_FRAME).map(|c| {
        c.par_iter()
            .filter(|p| {
                let width = dataset.frames[p.frame as usize].intrinsics.width;
                marched_at_stride(strides[p.frame as usize], width, p.pixel)
            })
            .filter_map(|p| pixel_ray(&dataset.frames[p.frame as usize], p.pixel))
            .collect()
    });
    visibility_over(renderer, lib, field, chunks, knobs, layout)
}

/// Each node's visibility over the rays of `chunks` (each at most
/// [`RAYS_PER_FRAME`], one dispatch each).
fn visibility_over(
    renderer: &mut Renderer,
    lib: &ShaderLibrary,
    field: &GridField,
    chunks: impl Iterator<Item = Vec<Ray>>,
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
    for chunk in chunks.filter(|c| !c.is_empty()) {
        run_chunk(
            renderer,
            &ctx,
            &gpu,
            &pipeline,
            &visibility,
            &chunk,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::{load_dataset, Intrinsics, LoadOptions, Pose};
    use crate::geometry::Aabb;
    use glam::{DVec3, UVec3};

    fn field(bounds: Aabb, nodes: u32) -> GridField {
        let s = bounds.size() / bounds.size().max_element();
        let r = (s * (nodes - 1) as f64).round().as_uvec3() + UVec3::ONE;
        GridField::new(r, bounds, vec![[0.0; 4]; (r.x * r.y * r.z) as usize], 4)
    }

    /// Fine photographs are thinned to rays half a node spacing apart at
    /// the far side of the bounds, one ray from the middle of each block;
    /// the Cycles sets' pixels are wide enough that every one is marched at
    /// every stage of a 128-node run.
    #[test]
    fn fine_photographs_are_thinned_to_half_a_spacing_and_wide_ones_kept() {
        let bounds = Aabb::new(DVec3::new(-0.9, -0.1, -0.9), DVec3::new(0.9, 0.9, 0.9));
        let mut d = load_dataset(
            std::path::Path::new(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../docs/cycles/dog/training"
            )),
            &LoadOptions::default(),
        )
        .unwrap();
        for nodes in [32, 64, 128] {
            let f = field(d.bounds, nodes);
            assert!(d.frames.iter().all(|fr| visibility_stride(fr, &f) == 1));
        }
        // An 800 × 800 photograph 4.4 from the centre.
        let frame = &mut d.frames[0];
        frame.pose = Pose::looking_at(DVec3::new(4.4, 0.4, 0.0), DVec3::ZERO, DVec3::Y);
        frame.intrinsics = Intrinsics::centred(800, 800, 52.0);
        let far = (bounds.min - frame.pose.origin()).length();
        for (nodes, stride) in [(32, 4), (64, 2), (128, 1)] {
            let f = field(bounds, nodes);
            assert_eq!(visibility_stride(frame, &f), stride, "{nodes}");
            // Neighbouring rays at the far corner: within half a spacing,
            // and a stride more would not be.
            let gap = far * stride as f64 / frame.intrinsics.fx;
            let half = VISIBILITY_RAY_SPACING * f.spacing().min_element();
            assert!(gap <= half && gap * (stride + 1) as f64 / stride as f64 > half);
        }
        // One pixel a block, its middle.
        let kept: Vec<u32> = (0..36).filter(|&p| marched_at_stride(3, 6, p)).collect();
        assert_eq!(kept, vec![7, 10, 25, 28]);
        assert!((0..36).all(|p| marched_at_stride(1, 6, p)));
    }
}

//! The trainer on the GPU: `train-rays` (forward, loss and backward of a
//! batch of rays, gradients scattered atomically) and `train-adam` (one Adam
//! step over every value), passes of the frame graph over buffers that live
//! across steps.

use std::sync::Arc;

use glam::{DVec3, UVec3};
use inlay_engine::graph::{BufferAccess, BufferHandle, FrameGraph};
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{vk, Buffer, BufferReadback, ComputePipeline, Context, Renderer, SubmitSync};

use super::adam::AdamKnobs;
use super::sh_pages::{interleave, ShPages};
use super::tv::TvWeights;
use crate::field::bricks::BrickLayout;
use crate::field::Sky;
use crate::field::{GridField, NodeStorage, DEFAULT_OCCUPANCY_BLOCK};
use crate::geometry::Aabb;
use crate::march::MarchKnobs;

inlay_engine::gpu_struct! {
    /// `TrainPush` of `shaders/train/ray_grad.wgsl`.
    pub struct TrainPush = "train/ray_grad.wgsl" : "TrainPush" {
        /// The grid's smallest corner.
        pub bounds_min: [f32; 3],
        /// Rays in the batch.
        pub ray_count: u32,
        /// The grid's largest corner.
        pub bounds_max: [f32; 3],
        /// The march's step.
        pub step: f32,
        /// Nodes per axis.
        pub resolution: [u32; 3],
        /// The march's termination transmittance.
        pub termination: f32,
        /// Radiance behind the field.
        pub background: [f32; 3],
        /// The relative loss's floor.
        pub epsilon: f32,
        /// Degree of the view-dependent colour (0: none).
        pub sh_degree: u32,
        /// 1: scatter the gradient of the frames' exposure gains.
        pub learn_gains: u32,
        /// The distortion loss's weight λ over the field's diagonal (0:
        /// none).
        pub distortion: f32,
        /// A learnt sky's texels across (0: `background` behind the field).
        pub sky_width: u32,
        /// Bricks per axis of a sparse grid (0: dense).
        pub brick_dims: [u32; 3],
        /// A learnt sky's texels down.
        pub sky_height: u32,
        /// Rays a pixel ([`MAX_RAYS_PER_PIXEL`] at most), consecutive in
        /// the batch.
        pub rays_per_pixel: u32,
        /// The depth loss's weight μ over the field's diagonal (0: none).
        pub depth_weight: f32,
        /// The depth loss's tolerance s (scene units).
        pub depth_tolerance: f32,
        /// 1: densities below zero take the gradient that asks for more
        /// ([`super::DensityGate::Revive`]).
        pub revive: u32,
    }
}

inlay_engine::gpu_struct! {
    /// `TrainRay` of `shaders/train/ray_grad.wgsl`: a ray and what its
    /// pixel says ([`super::PixelTarget`]).
    pub struct TrainRay = "train/ray_grad.wgsl" : "TrainRay" {
        /// Origin.
        pub origin: [f32; 3],
        /// 0 value, 1 lower bound, 2 bracket.
        pub kind: u32,
        /// Unit direction.
        pub dir: [f32; 3],
        /// A bracket's exposure.
        pub exposure: f32,
        /// The value, bound or encoded bracket value.
        pub target_value: [f32; 3],
        /// The ray's weight in the loss.
        pub weight: f32,
        /// The ray's frame (its exposure gain's index).
        pub frame: u32,
        /// The length along the ray to the surface a depth map records
        /// (0: none).
        pub depth: f32,
        /// Padding.
        pub pad0: u32,
        /// Padding.
        pub pad1: u32,
    }
}

inlay_engine::gpu_struct! {
    /// `AdamPush` of `shaders/train/adam.wgsl`.
    pub struct AdamPush = "train/adam.wgsl" : "AdamPush" {
        /// Values (4 per node, or per coefficient of a page).
        pub count: u32,
        /// Colour step size.
        pub rate: f32,
        /// Density step size.
        pub density_rate: f32,
        /// Gradient scale (1 / rays in the batch).
        pub grad_scale: f32,
        /// First-moment decay.
        pub beta1: f32,
        /// Second-moment decay.
        pub beta2: f32,
        /// 1 − β1^t.
        pub correction1: f32,
        /// 1 − β2^t.
        pub correction2: f32,
        /// Values kept non-negative (the nodes'; 0 for a page of
        /// view-dependent colour coefficients).
        pub base_values: u32,
        /// Colour step size as a fraction of each colour's value (the
        /// nodes' colours; 0 for the pages and the gains).
        pub relative_rate: f32,
        /// The colour above which steps grow with the colour.
        pub relative_floor: f32,
        /// The largest magnitude a value other than a density may step to
        /// ([`crate::scene::RADIANCE_LIMIT`]).
        pub limit: f32,
    }
}

inlay_engine::gpu_struct! {
    /// `TvPush` of `shaders/train/tv.wgsl`.
    pub struct TvPush = "train/tv.wgsl" : "TvPush" {
        /// Nodes per axis.
        pub resolution: [u32; 3],
        /// Nodes.
        pub count: u32,
        /// Weight of the colour channels' differences.
        pub colour_weight: f32,
        /// Weight of the density's differences.
        pub density_weight: f32,
        /// 1 / the density difference beyond which its penalty grows as
        /// its size (0: squared everywhere; [`TvWeights::density_edge`]).
        pub density_edge_inverse: f32,
        /// The density's sparsity prior's weight
        /// ([`TvWeights::sparsity`]).
        pub sparsity: f32,
        /// Bricks per axis of a sparse grid (0: dense).
        pub brick_dims: [u32; 3],
        /// 1 / the colour difference beyond which its penalty grows as
        /// its size (0: squared everywhere; [`TvWeights::colour_edge`]).
        pub colour_edge_inverse: f32,
        /// 1 / the sparsity prior's edge (0: σ₊² everywhere;
        /// [`TvWeights::sparsity_edge`]).
        pub sparsity_edge_inverse: f32,
        /// Padding.
        pub pad1: u32,
        /// Padding.
        pub pad2: u32,
        /// Padding.
        pub pad3: u32,
    }
}

inlay_engine::gpu_struct! {
    /// `DescendPush` of `shaders/train/descend.wgsl`.
    pub struct DescendPush = "train/descend.wgsl" : "DescendPush" {
        /// Values (4 per node; the nodes only).
        pub count: u32,
        /// The largest colour ([`crate::scene::RADIANCE_LIMIT`]).
        pub limit: f32,
        /// Padding.
        pub pad1: u32,
        /// Padding.
        pub pad2: u32,
    }
}

/// The buffers of a small set of learnt colours (the frames' exposure
/// gains, a sky's texels), named `name`: the colours as the shader reads
/// them ((r, g, b, 0) each), their gradient and Adam's first and second
/// moments (zero).
fn colour_buffers(
    ctx: &Arc<Context>,
    name: &str,
    colours: &[DVec3],
) -> anyhow::Result<[Arc<Buffer>; 4]> {
    anyhow::ensure!(!colours.is_empty(), "{name}: none");
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER
        | vk::BufferUsageFlags::TRANSFER_SRC
        | vk::BufferUsageFlags::TRANSFER_DST;
    let bytes: Vec<u8> = colours
        .iter()
        .flat_map(|g| [g.x as f32, g.y as f32, g.z as f32, 0.0])
        .flat_map(f32::to_le_bytes)
        .collect();
    let zeros = vec![0u8; bytes.len()];
    let buffer = |part: &str, data: &[u8]| -> anyhow::Result<Arc<Buffer>> {
        Ok(Arc::new(Buffer::with_data(
            ctx,
            &format!("{name}{part}"),
            data,
            usage,
        )?))
    };
    Ok([
        buffer("", &bytes)?,
        buffer("-grad", &zeros)?,
        buffer("-first", &zeros)?,
        buffer("-second", &zeros)?,
    ])
}

impl TrainRay {
    /// The record of `ray` (unit direction) with `target`, weighted
    /// `weight`.
    pub fn new(origin: DVec3, dir: DVec3, target: super::PixelTarget, weight: f64) -> Self {
        let (kind, value, exposure) = match target {
            super::PixelTarget::Value(v) => (0, v, 1.0),
            super::PixelTarget::AtLeast(v) => (1, v, 1.0),
            super::PixelTarget::Bracket { encoded, exposure } => (2, encoded, exposure),
        };
        Self {
            origin: origin.as_vec3().to_array(),
            kind,
            dir: dir.as_vec3().to_array(),
            exposure: exposure as f32,
            target_value: value.as_vec3().to_array(),
            weight: weight as f32,
            frame: 0,
            depth: 0.0,
            pad0: 0,
            pad1: 0,
        }
    }

    /// The same ray, from frame `frame` (whose exposure gain scales it).
    pub fn in_frame(mut self, frame: u32) -> Self {
        self.frame = frame;
        self
    }

    /// The same ray, its surface recorded at length `depth` along it
    /// (None: no depth; [`GpuTrainer::depth`] weighs the loss).
    pub fn with_depth(mut self, depth: Option<f64>) -> Self {
        self.depth = depth.map_or(0.0, |d| d as f32);
        self
    }
}

/// How `train-rays` adds gradients into the shared arrays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GradientScatter {
    /// A compare-and-swap loop on the float's bits (core WGSL, every
    /// device): `train/ray_grad.wgsl`.
    CompareAndSwap,
    /// One atomic float add (VK_EXT_shader_atomic_float):
    /// `train/ray_grad_float.wgsl`.
    FloatAdd,
}

/// Values one invocation of `train/adam.wgsl` and `train/descend.wgsl`
/// steps (consecutive ones). llvmpipe charges every invocation: at one a
/// value, the steps over every node (Adam's, total variation's) took two
/// thirds of a training step at 128 nodes (docs/benchmarks.md, issue 25's
/// fourteenth pass).
pub const VALUES_PER_INVOCATION: u32 = 4;

// `train/adam.wgsl` steps a node's four values at once.
const _: () = assert!(VALUES_PER_INVOCATION % 4 == 0);

/// The defines of the kernels that step every value.
const VALUES_DEFINES: [Define; 1] = [Define::U32("VALUES_PER_INVOCATION", VALUES_PER_INVOCATION)];

/// The bool define of `train/tv.wgsl`: true reads and steps every
/// channel, false the densities alone (a colour weight of zero).
pub const TV_COLOUR_DEFINE: &str = "TV_COLOUR";

/// The bool define of `train/descend.wgsl`: true steps the densities
/// alone (value j is node j's density), false every value.
pub const DENSITIES_ONLY_DEFINE: &str = "DENSITIES_ONLY";

/// A total variation kernel (`train/tv.wgsl`, `train/descend.wgsl`) with
/// its bool define `name` set to `value`, stepping
/// [`VALUES_PER_INVOCATION`] values an invocation where it steps values.
fn tv_pipeline(
    ctx: &Arc<Context>,
    lib: &ShaderLibrary,
    file: &str,
    name: &'static str,
    value: bool,
) -> anyhow::Result<Arc<ComputePipeline>> {
    let defines = [VALUES_DEFINES[0].clone(), Define::Bool(name, value)];
    Ok(lib.compute_pipeline(ctx, file, "main", &defines)?)
}

/// Workgroups (of 64) to step `count` values, [`VALUES_PER_INVOCATION`]
/// an invocation, split over y past the dispatch limit.
fn value_groups(count: u32) -> [u32; 3] {
    let groups = count.div_ceil(64 * VALUES_PER_INVOCATION);
    [groups.min(65535), groups.div_ceil(65535), 1]
}

/// The ray kernel's defines: one pixel an invocation (its rays in an array
/// of at most MAX_RAYS_PER_PIXEL), it takes a
/// view-dependent sample's corners in a loop (faster, counted below).
const RAY_GRAD_DEFINES: [Define; 2] = [
    Define::Bool(crate::march::SH_CORNER_LOOP_DEFINE, true),
    Define::U32("MAX_RAYS_PER_PIXEL", MAX_RAYS_PER_PIXEL),
];

/// The most rays `train-rays` averages into one pixel (a u32 define of
/// `train/ray_grad_body.wgsl`, the size of its per-pixel array of forward
/// marches): 4 × 4 ([`super::TrainKnobs::area_rays`]).
pub const MAX_RAYS_PER_PIXEL: u32 = super::knobs::MAX_AREA_RAYS * super::knobs::MAX_AREA_RAYS;

/// The most loop iterations one invocation of the trainer's ray kernel
/// runs ([`crate::march::loop_budget`]), per sample of a ray across the
/// whole diagonal: the forward's and the backward's turns, and the
/// scatter's eight corners (llvmpipe does not unroll their loop); on a grid
/// with view-dependent colour, the eight corners of its colour forward and
/// back; with compare-and-swap, at least one turn for each word a corner
/// adds to (4, and 3 per further coefficient), and once a ray for the
/// exposure gain's 3 words and a learnt sky's 12. Measured on lavapipe
/// against the f64 gradient: at degree 0, 4096 samples per ray match and
/// 8192 do not; at degree 2, 2048 and 4096; compare-and-swap at degree 0
/// fails from 2048. An invocation marches every ray of its pixel forward
/// and back (`rays_per_pixel` times the ray's count), and loops over them
/// three times.
fn ray_loop_iterations(
    march: &MarchKnobs,
    sh_degree: u32,
    scatter: GradientScatter,
    rays_per_pixel: u32,
) -> u64 {
    let count = crate::field::sh_extra_coefficients(sh_degree) as u64;
    let mut per_sample = 2 + 8;
    if count > 0 {
        per_sample += 2 * crate::march::VIEW_DEPENDENT_SAMPLE_LOOPS;
    }
    // Once a ray: the gains' 3 words and a sky's 12, one turn each at least.
    let mut per_ray = 0;
    if scatter == GradientScatter::CompareAndSwap {
        per_sample += 8 * (4 + 3 * count);
        per_ray += 15;
    }
    let n = rays_per_pixel.max(1) as u64;
    n * ((march.samples_per_ray as u64 + 1) * per_sample + per_ray + 3)
}

/// Refuses training at `samples_per_ray`, `sh_degree` and
/// `rays_per_pixel` on `ctx`'s device when its rays would loop past the
/// device's limit (checked by the command before the dataset is read, and
/// by every trainer built).
pub fn check_train_rays(
    ctx: &Context,
    samples_per_ray: u32,
    sh_degree: u32,
    rays_per_pixel: u32,
) -> anyhow::Result<()> {
    let march = MarchKnobs {
        samples_per_ray,
        ..MarchKnobs::default()
    };
    check_ray_loops(
        ctx,
        &march,
        sh_degree,
        GradientScatter::best(ctx.info()),
        rays_per_pixel,
    )
}

/// Refuses a trainer whose rays would loop past the device's limit,
/// naming the knobs.
fn check_ray_loops(
    ctx: &Context,
    march: &MarchKnobs,
    sh_degree: u32,
    scatter: GradientScatter,
    rays_per_pixel: u32,
) -> anyhow::Result<()> {
    anyhow::ensure!(
        (1..=MAX_RAYS_PER_PIXEL).contains(&rays_per_pixel),
        "train-rays: {rays_per_pixel} rays a pixel, where it takes 1 to {MAX_RAYS_PER_PIXEL}"
    );
    crate::march::loop_budget::check_loop_budget(
        ctx,
        "train-rays",
        ray_loop_iterations(march, sh_degree, scatter, rays_per_pixel),
        || {
            format!(
                "`--samples-per-ray` {} at `--sh-degree` {sh_degree} and {rays_per_pixel} rays a \
                 pixel (`--area-rays`), gradients scattered by {}",
                march.samples_per_ray,
                match scatter {
                    GradientScatter::CompareAndSwap => "compare-and-swap",
                    GradientScatter::FloatAdd => "atomic float adds",
                }
            )
        },
    )
}

impl GradientScatter {
    /// The fastest the device has.
    pub fn best(info: &inlay_engine::DeviceInfo) -> Self {
        if info.float_atomic_add {
            Self::FloatAdd
        } else {
            Self::CompareAndSwap
        }
    }

    fn file(self) -> &'static str {
        match self {
            Self::CompareAndSwap => "train/ray_grad.wgsl",
            Self::FloatAdd => "train/ray_grad_float.wgsl",
        }
    }
}

/// A host-visible storage buffer holding `bytes`: a batch's records, which
/// outgrow the 64 KiB a graph upload takes. One a frame; the frame
/// finishes before the next is made.
pub(crate) fn host_storage(
    ctx: &Arc<Context>,
    name: &str,
    bytes: &[u8],
) -> anyhow::Result<Arc<Buffer>> {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
    Ok(Arc::new(Buffer::host_with_data(ctx, name, bytes, usage)?))
}

/// Name of the batch pass in the frame graph.
pub const TRAIN_RAYS: &str = "train-rays";
/// Name of the optimiser pass.
pub const TRAIN_ADAM: &str = "train-adam";
/// Name of the exposure gains' optimiser pass.
pub const TRAIN_GAINS: &str = "train-gains";
/// Name of the learnt sky's optimiser pass.
pub const TRAIN_SKY: &str = "train-sky";
/// Name of the total-variation pass.
pub const TRAIN_TV: &str = "train-tv";
/// Name of the pass stepping along total variation's gradient.
pub const TRAIN_DESCEND: &str = "train-descend";

/// A grid being trained on the GPU: its nodes' values (laid out as a
/// field's on the device, or only the bricks of a [`BrickLayout`]), its
/// view-dependent coefficients in pages ([`ShPages`]), their gradients and
/// Adam's moments, and the pipelines that step them.
pub struct GpuTrainer {
    layout: Option<BrickLayout>,
    sh_pages: ShPages,
    table: Arc<Buffer>,
    slot_bricks: Arc<Buffer>,
    ray_grad: Arc<ComputePipeline>,
    adam: Arc<ComputePipeline>,
    /// Total variation's gradient and plain step: of every value, and of
    /// the densities only (where the colour's weight is zero).
    tv: [Arc<ComputePipeline>; 2],
    descend: [Arc<ComputePipeline>; 2],
    params: Arc<Buffer>,
    grad: Arc<Buffer>,
    moments: [Arc<Buffer>; 2],
    gains: Arc<Buffer>,
    gain_grad: Arc<Buffer>,
    gain_moments: [Arc<Buffer>; 2],
    /// A learnt sky's texels, gradient and moments (one unused texel
    /// without one), and its size (None: the fixed background).
    sky: [Arc<Buffer>; 4],
    sky_size: Option<(u32, u32)>,
    /// Nodes per axis.
    pub resolution: UVec3,
    /// The region the nodes span.
    pub bounds: Aabb,
    /// Degree of the view-dependent colour being trained (0: none).
    pub sh_degree: u32,
    /// The march the trainer renders with.
    pub march: MarchKnobs,
    /// Adam steps taken.
    pub steps: u32,
    /// Total variation's weights: a step of it after each Adam step
    /// ([`super::tv::tv_step`]); [`TvWeights::NONE`] leaves it out.
    pub tv_weights: TvWeights,
    /// The step size of the frames' exposure gains when they are learnt
    /// (Adam, after each of the grid's steps); None keeps them fixed.
    pub gain_rate: Option<f32>,
    /// The distortion loss's weight λ ([`super::render_ray_with_gradient`];
    /// 0 leaves it out).
    pub distortion: f64,
    /// The depth loss's weight μ and tolerance s, for the rays that record
    /// a depth ([`TrainRay::with_depth`]; [`super::depth`]); None leaves
    /// it out.
    pub depth: Option<(f64, f64)>,
    /// What a density below zero passes of its gradient
    /// ([`super::DensityGate`]; the clamp's true derivative unless set).
    pub gate: super::DensityGate,
    scatter: GradientScatter,
    rays_per_pixel: u32,
}

impl GpuTrainer {
    /// A trainer starting from `field` (its nodes and view-dependent
    /// colour; its occupancy is not used), every node trained.
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        field: &GridField,
        march: MarchKnobs,
    ) -> anyhow::Result<Self> {
        Self::with_layout(ctx, lib, field, march, None)
    }

    /// Whether a trainer of every node of a grid of `resolution` nodes
    /// with colour of `sh_degree` fits `info`: its values, their gradient
    /// and Adam's two moments each in bindings of their own, 16 bytes a
    /// node each ([`crate::field::check_field_fits`]).
    pub fn dense_fits(info: &inlay_engine::DeviceInfo, resolution: UVec3, sh_degree: u32) -> bool {
        crate::field::check_field_fits(info, resolution, sh_degree, NodeStorage::Training).is_ok()
    }

    /// A trainer starting from `field` that trains only the bricks of
    /// `layout` (None: every node), the others held at zero.
    pub fn with_layout(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        field: &GridField,
        march: MarchKnobs,
        layout: Option<BrickLayout>,
    ) -> anyhow::Result<Self> {
        let scatter = GradientScatter::best(ctx.info());
        check_ray_loops(ctx, &march, field.sh_degree, scatter, 1)?;
        let resolution = field.resolution;
        let (mut values, sh) = match &layout {
            Some(l) => l.pool_values(field),
            None => (field.nodes.clone(), field.sh.clone()),
        };
        if values.is_empty() {
            values.push([0.0; 4]); // no brick kept: a buffer is never empty
        }
        let n = values.len();
        let sh_count = crate::field::sh_extra_coefficients(field.sh_degree);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        let bytes = |v: &[f32]| bytemuck::cast_slice::<f32, u8>(v).to_vec();
        let flat: Vec<f32> = values.iter().flatten().copied().collect();
        if layout.is_none() {
            crate::field::check_field_fits(
                ctx.info(),
                resolution,
                field.sh_degree,
                NodeStorage::Training,
            )?;
        }
        let limit = ctx.info().max_storage_buffer_range as u64;
        let what = match &layout {
            Some(l) => format!(
                "{} of the {} bricks of a {resolution} grid",
                l.slots,
                l.table.len()
            ),
            None => format!("a {resolution} grid"),
        };
        anyhow::ensure!(
            (n as u64) * 16 <= limit,
            "training {what} (view-dependent colour of degree {}) needs bindings of {} MiB, more than {}'s {} MiB; train a smaller grid",
            field.sh_degree,
            (n as u64 * 16) >> 20,
            ctx.info().name,
            limit >> 20
        );
        let [gains, gain_grad, gain_first, gain_second] =
            colour_buffers(ctx, "train-gains", &[DVec3::ONE])?;
        let u32_buffer = |name: &str, v: &[u32]| -> anyhow::Result<Arc<Buffer>> {
            let v = if v.is_empty() { &[0u32][..] } else { v };
            Ok(Arc::new(Buffer::with_data(
                ctx,
                name,
                bytemuck::cast_slice(v),
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?))
        };
        // A buffer of the values' size, zero (the gradient, each moment).
        let zeros = |name: &str| -> anyhow::Result<Arc<Buffer>> {
            Ok(Arc::new(Buffer::with_data(
                ctx,
                name,
                &vec![0u8; n * 16],
                usage,
            )?))
        };
        let table = u32_buffer(
            "train-bricks",
            layout.as_ref().map_or(&[][..], |l| &l.table),
        )?;
        let slot_bricks = u32_buffer(
            "train-slot-bricks",
            &layout.as_ref().map_or(Vec::new(), BrickLayout::slot_bricks),
        )?;
        let sh_pages = ShPages::new(ctx, &sh, sh_count)?;
        Ok(Self {
            layout,
            sh_pages,
            table,
            slot_bricks,
            ray_grad: lib.compute_pipeline(
                ctx,
                GradientScatter::best(ctx.info()).file(),
                "main",
                &RAY_GRAD_DEFINES,
            )?,
            adam: lib.compute_pipeline(ctx, "train/adam.wgsl", "main", &VALUES_DEFINES)?,
            tv: [
                tv_pipeline(ctx, lib, "train/tv.wgsl", TV_COLOUR_DEFINE, true)?,
                tv_pipeline(ctx, lib, "train/tv.wgsl", TV_COLOUR_DEFINE, false)?,
            ],
            descend: [
                tv_pipeline(ctx, lib, "train/descend.wgsl", DENSITIES_ONLY_DEFINE, false)?,
                tv_pipeline(ctx, lib, "train/descend.wgsl", DENSITIES_ONLY_DEFINE, true)?,
            ],
            params: Arc::new(Buffer::with_data(
                ctx,
                "train-params",
                &bytes(&flat),
                usage,
            )?),
            grad: zeros("train-grad")?,
            moments: [
                zeros("train-first-moments")?,
                zeros("train-second-moments")?,
            ],
            gains,
            gain_grad,
            gain_moments: [gain_first, gain_second],
            sky: colour_buffers(ctx, "train-sky", &[DVec3::ZERO])?,
            sky_size: None,
            resolution,
            bounds: field.bounds,
            sh_degree: field.sh_degree,
            march,
            steps: 0,
            tv_weights: TvWeights::NONE,
            gain_rate: None,
            distortion: 0.0,
            depth: None,
            gate: super::DensityGate::Clamp,
            scatter,
            rays_per_pixel: 1,
        })
    }

    /// The same trainer scattering its gradients the `scatter` way (by
    /// default the fastest the device has). Fails where the device cannot.
    pub fn with_scatter(
        mut self,
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        scatter: GradientScatter,
    ) -> anyhow::Result<Self> {
        anyhow::ensure!(
            scatter != GradientScatter::FloatAdd || ctx.info().float_atomic_add,
            "{} cannot add floats atomically (VK_EXT_shader_atomic_float)",
            ctx.info().name
        );
        check_ray_loops(
            ctx,
            &self.march,
            self.sh_degree,
            scatter,
            self.rays_per_pixel,
        )?;
        self.ray_grad = lib.compute_pipeline(ctx, scatter.file(), "main", &RAY_GRAD_DEFINES)?;
        self.scatter = scatter;
        Ok(self)
    }

    /// The same trainer taking each pixel of a batch as the mean of `n`
    /// consecutive rays ([`Self::run_batch`]; 1 by default). Fails
    /// outside 1..=[`MAX_RAYS_PER_PIXEL`], or where a pixel's rays would
    /// loop past the device's limit.
    pub fn with_rays_per_pixel(mut self, ctx: &Context, n: u32) -> anyhow::Result<Self> {
        check_ray_loops(ctx, &self.march, self.sh_degree, self.scatter, n)?;
        self.rays_per_pixel = n;
        Ok(self)
    }

    /// Rays a pixel of a batch ([`Self::with_rays_per_pixel`]).
    pub fn rays_per_pixel(&self) -> u32 {
        self.rays_per_pixel
    }

    /// Sets each frame's exposure gain (a ray of frame f records gain f
    /// times its pixel; frame 0's stays as given when gains are learnt),
    /// their gradient and moments cleared.
    pub fn set_gains(&mut self, ctx: &Arc<Context>, gains: &[DVec3]) -> anyhow::Result<()> {
        let [g, grad, first, second] = colour_buffers(ctx, "train-gains", gains)?;
        (self.gains, self.gain_grad, self.gain_moments) = (g, grad, [first, second]);
        Ok(())
    }

    /// Puts `sky` behind the field, learnt at the colours' step size with
    /// each grid step (its gradient and moments cleared); None puts the
    /// fixed background of each batch there instead.
    pub fn set_sky(&mut self, ctx: &Arc<Context>, sky: Option<&Sky>) -> anyhow::Result<()> {
        self.sky = match sky {
            Some(s) => colour_buffers(ctx, "train-sky", &s.texels)?,
            None => colour_buffers(ctx, "train-sky", &[DVec3::ZERO])?,
        };
        self.sky_size = sky.map(|s| (s.width, s.height));
        Ok(())
    }

    /// The learnt sky now (None without one).
    pub fn sky(&self, renderer: &mut Renderer) -> anyhow::Result<Option<Sky>> {
        let Some((width, height)) = self.sky_size else {
            return Ok(None);
        };
        let v = self.read(renderer, &self.sky[0])?;
        let texels = v
            .chunks_exact(4)
            .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64))
            .collect();
        Sky::new(width, height, texels)
            .map(Some)
            .map_err(|e| anyhow::anyhow!("the learnt sky: {e}"))
    }

    /// Which of the sky's texels some ray's loss has moved since
    /// [`Self::set_sky`] (Adam's second moment is not zero; empty without a
    /// sky).
    pub fn sky_seen(&self, renderer: &mut Renderer) -> anyhow::Result<Vec<bool>> {
        if self.sky_size.is_none() {
            return Ok(Vec::new());
        }
        let v = self.read(renderer, &self.sky[3])?;
        Ok(v.chunks_exact(4)
            .map(|c| c[..3].iter().any(|m| *m > 0.0))
            .collect())
    }

    /// The accumulated gradient of the sky's texels (4 per texel).
    pub fn sky_gradient(&self, renderer: &mut Renderer) -> anyhow::Result<Vec<f32>> {
        self.read(renderer, &self.sky[1])
    }

    /// The frames' exposure gains now.
    pub fn gains(&self, renderer: &mut Renderer) -> anyhow::Result<Vec<DVec3>> {
        let v = self.read(renderer, &self.gains)?;
        Ok(v.chunks_exact(4)
            .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64))
            .collect())
    }

    /// The accumulated gradient of the exposure gains (4 per frame).
    pub fn gain_gradient(&self, renderer: &mut Renderer) -> anyhow::Result<Vec<f32>> {
        self.read(renderer, &self.gain_grad)
    }

    fn push(&self, rays: u32, background: DVec3, epsilon: f64) -> TrainPush {
        TrainPush {
            bounds_min: self.bounds.min.as_vec3().to_array(),
            ray_count: rays,
            bounds_max: self.bounds.max.as_vec3().to_array(),
            step: self.march.step(self.bounds.diagonal()) as f32,
            resolution: self.resolution.to_array(),
            termination: self.march.termination as f32,
            background: background.as_vec3().to_array(),
            epsilon: epsilon as f32,
            sh_degree: self.sh_degree,
            learn_gains: self.gain_rate.is_some() as u32,
            distortion: (self.distortion / self.bounds.diagonal()) as f32,
            sky_width: self.sky_size.map_or(0, |s| s.0),
            brick_dims: self.brick_dims(),
            sky_height: self.sky_size.map_or(0, |s| s.1),
            rays_per_pixel: self.rays_per_pixel,
            depth_weight: self.depth.map_or(0.0, |d| d.0 / self.bounds.diagonal()) as f32,
            depth_tolerance: self.depth.map_or(1.0, |d| d.1) as f32,
            revive: (self.gate == super::DensityGate::Revive) as u32,
        }
    }

    fn brick_dims(&self) -> [u32; 3] {
        self.layout.as_ref().map_or([0; 3], |l| l.dims.to_array())
    }

    /// Nodes trained: the grid's, or the pool's of a sparse grid (its
    /// bricks' padding past the grid included).
    pub fn node_count(&self) -> u32 {
        match &self.layout {
            Some(l) => l.pool_nodes() as u32,
            None => self.resolution.x * self.resolution.y * self.resolution.z,
        }
    }

    /// Values trained: 4 per node and 4 per view-dependent colour
    /// coefficient (r, g, b and an unused fourth).
    pub fn value_count(&self) -> u32 {
        4 * self.node_count() * (1 + self.sh_pages.count() as u32)
    }

    /// The bricks trained (None: every node).
    pub fn layout(&self) -> Option<&BrickLayout> {
        self.layout.as_ref()
    }

    /// Runs one batch: renders `rays` over `background` (or the sky of
    /// [`Self::set_sky`]), adds their loss's gradient to the accumulated
    /// gradient and, with `adam` given, takes an Adam step with the
    /// gradient scaled by `grad_scale` (clearing it), then a
    /// total-variation step ([`Self::tv_weights`] not zero), then the
    /// sky's and the gains' steps where they are learnt. Each
    /// [`Self::rays_per_pixel`] consecutive rays are one pixel's (the same
    /// target, weight and frame; through points of its area): the pixel is
    /// their mean, and the loss is taken on it.
    /// Returns each pixel's value and weighted loss.
    pub fn run_batch(
        &mut self,
        renderer: &mut Renderer,
        rays: &[TrainRay],
        background: DVec3,
        epsilon: f64,
        adam: Option<(&AdamKnobs, f32)>,
    ) -> anyhow::Result<Vec<[f32; 4]>> {
        anyhow::ensure!(!rays.is_empty(), "an empty batch");
        let n = self.rays_per_pixel as usize;
        anyhow::ensure!(
            rays.len() % n == 0,
            "a batch of {} rays is not whole pixels of {n} rays",
            rays.len()
        );
        let pixels = (rays.len() / n) as u32;
        let ctx = renderer.context().clone();
        let out_bytes = pixels as u64 * 16;
        let readback = BufferReadback::new(&ctx, "train-ray-out (readback)", out_bytes)?;
        renderer.begin_frame()?;
        let mut graph = FrameGraph::new();
        let params = graph.import_buffer(&self.params, None);
        let grad = graph.import_buffer(&self.grad, None);
        let moments = self.moments.clone().map(|m| graph.import_buffer(&m, None));
        let graph_gains = graph.import_buffer(&self.gains, None);
        let gain_grad = graph.import_buffer(&self.gain_grad, None);
        let gain_moments = self
            .gain_moments
            .clone()
            .map(|m| graph.import_buffer(&m, None));
        let graph_table = graph.import_buffer(&self.table, None);
        let [sky, sky_grad, sky_first, sky_second] =
            self.sky.clone().map(|b| graph.import_buffer(&b, None));
        let mut pages = self.sh_pages.import(&mut graph);
        let graph_slots = graph.import_buffer(&self.slot_bricks, None);
        let batch = host_storage(&ctx, "train-batch", bytemuck::cast_slice(rays))?;
        let batch = graph.import_buffer(&batch, None);
        let out = graph.create_buffer("train-ray-out", out_bytes);
        let push = self.push(rays.len() as u32, background, epsilon);
        let mut pass = graph.compute_pass(TRAIN_RAYS);
        pass.buffer_at("grid_nodes", params, BufferAccess::StorageRead);
        pass.buffer_at("rays", batch, BufferAccess::StorageRead);
        let grad = pass.buffer_at("grad", grad, BufferAccess::StorageReadWrite);
        let out = pass.buffer_at("ray_out", out, BufferAccess::StorageWrite);
        let gains = graph_gains;
        pass.buffer_at("gains", gains, BufferAccess::StorageRead);
        let gain_grad = pass.buffer_at("gain_grad", gain_grad, BufferAccess::StorageReadWrite);
        let table = graph_table;
        pass.buffer_at("bricks", table, BufferAccess::StorageRead);
        pass.buffer_at("sky", sky, BufferAccess::StorageRead);
        let sky_grad = pass.buffer_at("sky_grad", sky_grad, BufferAccess::StorageReadWrite);
        pages.bind_to_batch(&mut pass);
        pass.dispatch(&self.ray_grad)
            .push(&push)
            .groups([pixels.div_ceil(64), 1, 1]);
        pass.finish();
        if let Some((knobs, grad_scale)) = adam {
            self.steps += 1;
            let t = self.steps as i32;
            let a = AdamPush {
                count: 4 * self.node_count(),
                rate: knobs.rate as f32,
                density_rate: knobs.density_rate as f32,
                grad_scale,
                beta1: knobs.beta1 as f32,
                beta2: knobs.beta2 as f32,
                correction1: (1.0 - knobs.beta1.powi(t)) as f32,
                correction2: (1.0 - knobs.beta2.powi(t)) as f32,
                base_values: 4 * self.node_count(),
                relative_rate: knobs.relative_rate as f32,
                relative_floor: knobs.relative_floor as f32,
                limit: crate::scene::RADIANCE_LIMIT as f32,
            };
            let groups = value_groups(4 * self.node_count());
            let mut pass = graph.compute_pass(TRAIN_ADAM);
            let params = pass.buffer_at("params", params, BufferAccess::StorageReadWrite);
            let grad = pass.buffer_at("grad", grad, BufferAccess::StorageReadWrite);
            pass.buffer_at("first", moments[0], BufferAccess::StorageReadWrite);
            pass.buffer_at("second", moments[1], BufferAccess::StorageReadWrite);
            pass.dispatch(&self.adam).push(&a).groups(groups);
            pass.finish();
            // Each page of coefficients: free of sign, at the colour's rate.
            let page_step = AdamPush {
                base_values: 0,
                relative_rate: 0.0,
                ..a
            };
            for (j, [values, grad, first, second]) in pages.trained.iter().enumerate() {
                let mut pass = graph.compute_pass(&format!("{TRAIN_ADAM}-sh-{j}"));
                pass.buffer_at("params", *values, BufferAccess::StorageReadWrite);
                pass.buffer_at("grad", *grad, BufferAccess::StorageReadWrite);
                pass.buffer_at("first", *first, BufferAccess::StorageReadWrite);
                pass.buffer_at("second", *second, BufferAccess::StorageReadWrite);
                pass.dispatch(&self.adam).push(&page_step).groups(groups);
                pass.finish();
            }
            if !self.tv_weights.is_none() {
                self.add_tv_step(&mut graph, params, grad, (graph_table, graph_slots));
            }
            // The sky's texels: colours, non-negative, at the nodes' steps.
            if let Some((w, h)) = self.sky_size {
                let count = 4 * w * h;
                let s = AdamPush {
                    count,
                    density_rate: 0.0,
                    base_values: count,
                    ..a
                };
                let mut pass = graph.compute_pass(TRAIN_SKY);
                pass.buffer_at("params", sky, BufferAccess::StorageReadWrite);
                pass.buffer_at("grad", sky_grad, BufferAccess::StorageReadWrite);
                pass.buffer_at("first", sky_first, BufferAccess::StorageReadWrite);
                pass.buffer_at("second", sky_second, BufferAccess::StorageReadWrite);
                pass.dispatch(&self.adam)
                    .push(&s)
                    .groups(value_groups(count));
                pass.finish();
            }
            if let Some(rate) = self.gain_rate {
                let count = (self.gains.size() / 4) as u32;
                let g = AdamPush {
                    count,
                    rate,
                    density_rate: 0.0,
                    base_values: count,
                    relative_rate: 0.0,
                    ..a
                };
                let mut pass = graph.compute_pass(TRAIN_GAINS);
                pass.buffer_at("params", gains, BufferAccess::StorageReadWrite);
                pass.buffer_at("grad", gain_grad, BufferAccess::StorageReadWrite);
                pass.buffer_at("first", gain_moments[0], BufferAccess::StorageReadWrite);
                pass.buffer_at("second", gain_moments[1], BufferAccess::StorageReadWrite);
                pass.dispatch(&self.adam)
                    .push(&g)
                    .groups(value_groups(count));
                pass.finish();
            }
        }
        readback.add_to_graph(&mut graph, "train-ray-out-readback", out);
        renderer.submit(graph, &SubmitSync::none())?;
        renderer.finish()?;
        let v = readback.read_f32()?;
        Ok(v.chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect())
    }

    /// Adds `train-tv` (the total variation's gradient into `grad`, empty
    /// after Adam) and `train-descend` (one plain step along it).
    fn add_tv_step(
        &self,
        graph: &mut FrameGraph,
        params: BufferHandle,
        grad: BufferHandle,
        (table, slots): (BufferHandle, BufferHandle),
    ) {
        let nodes = self.node_count();
        let t = TvPush {
            resolution: self.resolution.to_array(),
            count: nodes,
            colour_weight: self.tv_weights.colour as f32,
            density_weight: self.tv_weights.density as f32,
            density_edge_inverse: self.tv_weights.density_edge_inverse() as f32,
            sparsity: self.tv_weights.sparsity as f32,
            brick_dims: self.brick_dims(),
            colour_edge_inverse: self.tv_weights.colour_edge_inverse() as f32,
            sparsity_edge_inverse: self.tv_weights.sparsity_edge_inverse() as f32,
            pad1: 0,
            pad2: 0,
            pad3: 0,
        };
        let groups = nodes.div_ceil(64);
        // A colour weight of zero takes nothing from the colours: only the
        // densities are read and stepped (exactly as when all are).
        let densities_only = self.tv_weights.colour == 0.0;
        let which = usize::from(densities_only);
        let mut pass = graph.compute_pass(TRAIN_TV);
        pass.buffer_at("params", params, BufferAccess::StorageRead);
        let grad = pass.buffer_at("grad", grad, BufferAccess::StorageReadWrite);
        pass.buffer_at("bricks", table, BufferAccess::StorageRead);
        pass.buffer_at("slot_bricks", slots, BufferAccess::StorageRead);
        pass.dispatch(&self.tv[which]).push(&t).groups([
            groups.min(65535),
            groups.div_ceil(65535),
            1,
        ]);
        pass.finish();
        let stepped = if densities_only { nodes } else { 4 * nodes };
        let d = DescendPush {
            count: stepped,
            limit: crate::scene::RADIANCE_LIMIT as f32,
            pad1: 0,
            pad2: 0,
        };
        let mut pass = graph.compute_pass(TRAIN_DESCEND);
        pass.buffer_at("params", params, BufferAccess::StorageReadWrite);
        pass.buffer_at("grad", grad, BufferAccess::StorageReadWrite);
        pass.dispatch(&self.descend[which])
            .push(&d)
            .groups(value_groups(stepped));
        pass.finish();
    }

    /// Reads a persistent buffer back whole.
    fn read(&self, renderer: &mut Renderer, buffer: &Arc<Buffer>) -> anyhow::Result<Vec<f32>> {
        let ctx = renderer.context().clone();
        let readback = BufferReadback::new(&ctx, "train-readback", buffer.size())?;
        renderer.begin_frame()?;
        let mut graph = FrameGraph::new();
        let b = graph.import_buffer(buffer, None);
        readback.add_to_graph(&mut graph, "train-readback", b);
        renderer.submit(graph, &SubmitSync::none())?;
        renderer.finish()?;
        Ok(readback.read_f32()?)
    }

    /// Every value now, in [`crate::field::device_values`]' order (the nodes', then each
    /// node's coefficients together).
    pub fn values(&self, renderer: &mut Renderer) -> anyhow::Result<Vec<f32>> {
        let base = self.read(renderer, &self.params)?;
        let pages = (0..self.sh_pages.count())
            .map(|j| self.read(renderer, self.sh_pages.values(j)))
            .collect::<anyhow::Result<Vec<_>>>()?;
        Ok(interleave(base, &pages))
    }

    /// Whether any node's density is above zero (a grid every density of
    /// which lies below renders nothing).
    pub fn holds_density(&self, renderer: &mut Renderer) -> anyhow::Result<bool> {
        let nodes = 4 * self.node_count() as usize;
        let values = self.values(renderer)?;
        Ok(values[..nodes.min(values.len())]
            .chunks_exact(4)
            .any(|v| v[3] > 0.0))
    }

    /// The grid now, as a field (occupancy built from its densities; a
    /// sparse grid's dropped bricks zero).
    pub fn field(&self, renderer: &mut Renderer) -> anyhow::Result<GridField> {
        let v = self.values(renderer)?;
        let n = self.node_count() as usize;
        let (nodes, sh) = match &self.layout {
            Some(l) => {
                let values: Vec<[f32; 4]> = v
                    .chunks_exact(4)
                    .map(|c| [c[0], c[1], c[2], c[3]])
                    .collect();
                l.dense_values(
                    &values,
                    self.resolution,
                    crate::field::sh_extra_coefficients(self.sh_degree),
                )
            }
            None => {
                let (nodes, sh) = v.split_at(4 * n);
                (
                    nodes
                        .chunks_exact(4)
                        .map(|c| [c[0], c[1], c[2], c[3]])
                        .collect(),
                    sh.chunks_exact(4).map(|c| [c[0], c[1], c[2]]).collect(),
                )
            }
        };
        Ok(
            GridField::new(self.resolution, self.bounds, nodes, DEFAULT_OCCUPANCY_BLOCK)
                .with_sh(self.sh_degree, sh),
        )
    }

    /// The accumulated gradient (as [`Self::values`]).
    pub fn gradient(&self, renderer: &mut Renderer) -> anyhow::Result<Vec<f32>> {
        let base = self.read(renderer, &self.grad)?;
        let pages = (0..self.sh_pages.count())
            .map(|j| self.read(renderer, self.sh_pages.gradient(j)))
            .collect::<anyhow::Result<Vec<_>>>()?;
        Ok(interleave(base, &pages))
    }
}

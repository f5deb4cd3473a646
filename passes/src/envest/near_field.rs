//! The near-field light at surface points on the GPU
//! (`shaders/envest/near_field.wgsl`), computed once before the fit:
//! E_nerf(x) = ∫_{Ω+} Ĉ(ω; x)(ω·n) dω by Monte Carlo with cosine-distributed
//! rays ([`super::hemisphere`]), and the field's opacity Ô(ω; x) cached on an
//! octahedral map per point for the environment term. Points go in batches
//! (one submission each) so progress can be shown.
//! [`super::near_field_reference`] is the f64 CPU mirror.

use std::sync::Arc;

use glam::DVec3;
use inlay_engine::graph::FrameGraph;
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{vk, Buffer, BufferReadback, ComputePipeline, Context, Renderer, SubmitSync};

use super::surface::{surface_unit, SurfacePoint, SurfaceTest};
use crate::field::{GpuGridField, GridField};
use crate::march::MarchKnobs;
use crate::probe::octahedral_bilinear;

inlay_engine::gpu_struct! {
    /// `NearFieldPush` of `shaders/envest/near_field.wgsl`.
    pub struct NearFieldPush = "envest/near_field.wgsl" : "NearFieldPush" {
        /// March step (world units).
        pub step: f32,
        /// Early-termination transmittance.
        pub termination: f32,
        /// Rays per point.
        pub rays: u32,
        /// The batch's first point.
        pub first_point: u32,
        /// Points in the batch.
        pub count: u32,
        /// Opacity map side.
        pub map_side: u32,
        /// Ray seed.
        pub seed: u32,
        /// Padding.
        pub pad: u32,
    }
}

/// A point's rays leave the surface point itself but start marching
/// where they have risen this many node spacings above it (on a trained
/// field, this many [`super::surface::trained_surface_scale`]s:
/// [`ray_rise`]): the expected
/// depth lies at the front of the density's smooth edge (about 1.5
/// spacings wide in the bundled recipes), so rays marched from the point
/// would see its own surface. Rising along each ray rather than lifting
/// the origin along the normal keeps every ray on its line through the
/// point: a lifted origin is closer to a lamp above it (on 150 of
/// PLANTS' floor points, E_nerf read 8.6 % above the path tracer's
/// irradiance with the origin lifted, 4.3 % rising along the rays).
pub const SURFACE_OFFSET_SPACINGS: f64 = 2.0;

/// The smallest cosine to the normal the rise is divided by: a ray
/// nearer the horizon starts at most 1/MIN_RISE_COSINE times the rise
/// along itself, short of the rise, rather than skipping real occluders
/// far along the surface.
pub const MIN_RISE_COSINE: f64 = 0.25;

/// Points per submission.
const POINTS_PER_BATCH: usize = 64;

/// Rays one invocation of the irradiance kernel marches. llvmpipe stops
/// every loop of an invocation after 65535 iterations of all its loops
/// together (measured: one invocation marching 470 rays of 32768 returned
/// E_nerf ≈ 0 on PLANTS), so an invocation's share must stay small: eight
/// rays of even a few thousand steps each stay well under it.
pub const RAYS_PER_INVOCATION: u32 = 8;

/// Rays one workgroup (64 invocations) of the irradiance kernel marches.
const RAYS_PER_GROUP: u32 = 64 * RAYS_PER_INVOCATION;

/// The near-field light at every surface point.
#[derive(Debug, Clone, PartialEq)]
pub struct NearField {
    /// E_nerf per point.
    pub irradiance: Vec<DVec3>,
    /// Mean Ô over each point's rays (the fraction of the hemisphere the
    /// field covers, cosine-weighted).
    pub covered: Vec<f64>,
    /// Side of the octahedral opacity maps.
    pub map_side: u32,
    /// side² opacities per point, texel y·side + x.
    pub opacity: Vec<f32>,
}

impl NearField {
    /// Ô(d; x) of point `point`, bilinear over its map.
    pub fn opacity_at(&self, point: usize, d: DVec3) -> f64 {
        let texels = (self.map_side * self.map_side) as usize;
        let map = &self.opacity[point * texels..(point + 1) * texels];
        octahedral_bilinear(self.map_side, d, |t| map[t] as f64).clamp(0.0, 1.0)
    }
}

/// How far above the surface a point's rays start marching:
/// [`SURFACE_OFFSET_SPACINGS`] node spacings where surfaces are told by
/// `test` = [`SurfaceTest::Gradient`] (bakes), as many
/// [`super::surface::trained_surface_scale`]s under
/// [`SurfaceTest::Weight`] ([`surface_unit`]). A trained
/// surface's blur is a length in the scene, not a count of nodes: on DOG
/// trained at 256 nodes, rays risen two of its own spacings started
/// within the blur, and rising two scales put the lobes near the bulb at
/// its light (0.57× → 1.04×; docs/fidelity.md, "Twenty-fifth pass").
pub fn ray_rise(field: &GridField, test: SurfaceTest) -> f64 {
    SURFACE_OFFSET_SPACINGS * surface_unit(field, test)
}

/// Where the ray from `p` along `dir` starts marching: `rise` above the
/// surface along the ray itself (mirrored by `nf_ray_start` in
/// near_field.wgsl).
pub fn ray_start(p: &SurfacePoint, rise: f64, dir: DVec3) -> DVec3 {
    p.position + dir * (rise / dir.dot(p.normal).max(MIN_RISE_COSINE))
}

/// The seed the ray sets use (the low and high halves of `seed` folded).
pub fn ray_seed(seed: u64) -> u32 {
    (seed as u32) ^ ((seed >> 32) as u32)
}

/// The compiled near-field kernels.
pub struct NearFieldTracer {
    irradiance: Arc<ComputePipeline>,
    opacity: Arc<ComputePipeline>,
    march: MarchKnobs,
}

impl NearFieldTracer {
    /// Compiles both kernels for `march`'s quadrature.
    pub fn new(ctx: &Arc<Context>, lib: &ShaderLibrary, march: MarchKnobs) -> anyhow::Result<Self> {
        crate::march::loop_budget::check_loop_budget(
            ctx,
            "near-field",
            RAYS_PER_INVOCATION as u64 * march.loop_iterations(),
            || {
                format!(
                    "{RAYS_PER_INVOCATION} rays an invocation at `[march] samples_per_ray` {}",
                    march.samples_per_ray
                )
            },
        )?;
        let defines = [
            Define::Bool("SKIP_EMPTY", march.skip_empty),
            Define::Bool("OCTAHEDRAL", true),
            Define::U32("NF_RAYS_PER_INVOCATION", RAYS_PER_INVOCATION),
        ];
        let pipeline = |entry: &str| -> anyhow::Result<Arc<ComputePipeline>> {
            Ok(lib.compute_pipeline(ctx, "envest/near_field.wgsl", entry, &defines)?)
        };
        Ok(Self {
            irradiance: pipeline("irradiance")?,
            opacity: pipeline("opacity_map")?,
            march,
        })
    }

    /// E_nerf and the opacity maps of `points` in `field` (already
    /// uploaded as `gpu`; their surfaces told by `test`, which sets the
    /// rays' [`ray_rise`]), `rays` rays per point, maps `map_side` wide;
    /// `progress(done, total)` after each batch.
    #[allow(clippy::too_many_arguments)]
    pub fn trace(
        &self,
        ctx: &Arc<Context>,
        field: &GridField,
        gpu: &GpuGridField,
        points: &[SurfacePoint],
        test: SurfaceTest,
        rays: u32,
        map_side: u32,
        seed: u64,
        progress: &dyn Fn(usize, usize),
    ) -> anyhow::Result<NearField> {
        let mut packed = Vec::with_capacity(points.len() * 8);
        let rise = ray_rise(field, test) as f32;
        for p in points {
            let o = p.position;
            packed.extend([o.x as f32, o.y as f32, o.z as f32, rise]);
            packed.extend([p.normal.x as f32, p.normal.y as f32, p.normal.z as f32, 0.0]);
        }
        let mut bytes: Vec<u8> = packed.iter().flat_map(|x| x.to_le_bytes()).collect();
        bytes.resize(bytes.len().max(32), 0);
        let points_buf = Arc::new(Buffer::with_data(
            ctx,
            "near-field points",
            &bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?);
        let texels = (map_side * map_side) as usize;
        let step = self.march.step(gpu.diagonal) as f32;
        let seed = ray_seed(seed);
        let mut out = NearField {
            irradiance: Vec::with_capacity(points.len()),
            covered: Vec::with_capacity(points.len()),
            map_side,
            opacity: Vec::with_capacity(points.len() * texels),
        };
        let mut renderer = Renderer::new(ctx, 1)?;
        let chunks = rays.div_ceil(RAYS_PER_GROUP) as usize;
        let (e_scale, o_scale) = (std::f64::consts::PI / rays as f64, 1.0 / rays as f64);
        for start in (0..points.len()).step_by(POINTS_PER_BATCH) {
            let count = POINTS_PER_BATCH.min(points.len() - start);
            let e_size = (count * chunks * 16) as u64;
            let o_size = (count * texels * 4) as u64;
            let e_readback = BufferReadback::new(ctx, "near-field irradiance readback", e_size)?;
            let o_readback = BufferReadback::new(ctx, "near-field opacity readback", o_size)?;
            renderer.begin_frame()?;
            let mut graph = FrameGraph::new();
            let grid = gpu.import(&mut graph);
            let pts = graph.import_buffer(&points_buf, None);
            let e_buf = graph.create_buffer("near-field irradiance", e_size);
            let o_buf = graph.create_buffer("near-field opacity", o_size);
            let push = NearFieldPush {
                step,
                termination: self.march.termination as f32,
                rays,
                first_point: start as u32,
                count: count as u32,
                map_side,
                seed,
                pad: 0,
            };
            let (mut e_buf, mut o_buf) = (e_buf, o_buf);
            let mut pass = graph.compute_pass("near-field");
            let kernels = [
                (&self.irradiance, [chunks as u32, count as u32, 1]),
                (
                    &self.opacity,
                    [(texels as u32).div_ceil(64), count as u32, 1],
                ),
            ];
            for (kernel, groups) in kernels {
                grid.bind(pass.dispatch(kernel))
                    .read("points", pts)
                    .write("irradiance_out", &mut e_buf)
                    .write("opacity_out", &mut o_buf)
                    .push(&push)
                    .groups(groups);
            }
            pass.finish();
            e_readback.add_to_graph(&mut graph, "near-field irradiance readback", e_buf);
            o_readback.add_to_graph(&mut graph, "near-field opacity readback", o_buf);
            renderer.submit(graph, &SubmitSync::none())?;
            renderer.finish()?;
            for point in e_readback.read_f32()?.chunks_exact(4 * chunks) {
                let mut sum = [0.0f64; 4];
                for chunk in point.chunks_exact(4) {
                    sum.iter_mut().zip(chunk).for_each(|(s, &c)| *s += c as f64);
                }
                out.irradiance
                    .push(DVec3::new(sum[0], sum[1], sum[2]) * e_scale);
                out.covered.push(sum[3] * o_scale);
            }
            out.opacity.extend(o_readback.read_f32()?);
            progress(start + count, points.len());
        }
        Ok(out)
    }
}

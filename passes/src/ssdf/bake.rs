//! Baking an object's SSDF field (METHOD.md "SSDF field"): S(d; x) at every
//! direction texel of an octahedral map, at every node of the grid, on the
//! GPU, with [`bake_reference`] its f64 CPU mirror. The nodes go in batches
//! (one submission each, so progress can be shown), taken in Morton order
//! so that a batch is a compact block; per batch five kernels run:
//!
//! 1. `ssdf-candidates` (`shaders/ssdf/ssdf_candidates.wgsl`, mirrored by
//!    [`edge_candidates`]): the edges that can be on the silhouette from
//!    some point of the batch's box, so the next kernel tests those for
//!    each node instead of every edge.
//! 2. `ssdf-pieces`: per node, its silhouette edges cut into pieces
//!    ([`SilhouetteEdge::pieces`](super::SilhouetteEdge::pieces)).
//! 3. `ssdf-outer`: one ray per piece tells the outline's pieces.
//! 4. `ssdf-arcs`: each edge's consecutive outline pieces joined into arcs
//!    (2–4 are [`SilhouetteMesh::view_from`]).
//! 5. `ssdf-bake`: S at every direction from them.
//!
//! Each invocation does a bounded amount of work: llvmpipe silently ends
//! all of an invocation's loops after 65535 iterations in all, which cut
//! short the single kernel that found a node's arcs before issue 26's
//! ninth pass (on a 100k-triangle mesh it stopped after two thirds of the
//! edges, and the field came out wrong without a word). The per-node
//! lists have fixed capacities ([`PIECE_CAPACITY`], [`ARC_CAPACITY`]); the
//! counts are read back and a bake that outgrows them is refused.
//!
//! **Nodes inside the object** see it in every direction (S = −π
//! everywhere), which would drag every interpolated value near the surface
//! to "fully blocked" and self-shadow even a convex object. Such nodes take
//! instead the SSDF seen from the nearest surface point, lifted off the
//! surface by 10⁻³ of the radius along its face normal: the field then
//! continues across the surface the way it approaches it from outside.
//!
//! **Nodes far from the object** may take the blend of a coarser lattice's
//! values instead of a bake ([`SsdfKnobs::coarse_angle`], [`NodePlan`]):
//! only the plan's baked nodes go through the kernels.

use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;
use inlay_engine::graph::{BufferHandle, FrameGraph};
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{BufferReadback, ComputePipeline, Context, DeviceInfo, Renderer, SubmitSync};

use super::coarse::{NodePlan, MAX_COARSE_ANGLE};
use super::grid::SsdfGrid;
use super::silhouette::{SilhouetteMesh, ARC_PIECES, OUTSIDE_OFFSET, PIECE_ANGLE};
use crate::geometry::MeshScene;
use crate::object::{ObjectMesh, PlacedObject, Pose};
use crate::probe::{DirectionMap, MapKind};
use crate::shadow::gpu::storage;

inlay_engine::gpu_struct! {
    /// `BakePush` of `shaders/ssdf/ssdf_bake.wgsl`.
    pub struct BakePush = "ssdf/ssdf_bake.wgsl" : "BakePush" {
        /// The batch's first node.
        pub node_offset: u32,
        /// Direction map side.
        pub map_size: u32,
        /// Silhouette edges.
        pub edge_count: u32,
        /// Nodes in the batch.
        pub node_count: u32,
        /// The batch's points' bounding box, lower corner (xyz; w unused).
        pub box_lo: [f32; 4],
        /// Its upper corner.
        pub box_hi: [f32; 4],
    }
}

/// The knobs of an SSDF bake.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SsdfKnobs {
    /// Nodes along each axis of the grid (paper: 16).
    pub grid: u32,
    /// Side of the octahedral direction map (texels = directions²).
    pub directions: u32,
    /// PCA components kept.
    pub components: u32,
    /// A node at distance d from the object takes its values from the
    /// coarsest lattice of the grid whose spacing is at most this angle
    /// (radians) times d, instead of a bake of its own ([`super::coarse`];
    /// 0 bakes every node, at most [`MAX_COARSE_ANGLE`]).
    pub coarse_angle: f64,
}

/// The default [`SsdfKnobs::coarse_angle`]: where a blended node's
/// lattice spacing subtends at most 0.2 rad, about two texels of the
/// default 32² map (docs/benchmarks.md, issue 26's nineteenth pass).
pub const DEFAULT_COARSE_ANGLE: f64 = 0.2;

impl Default for SsdfKnobs {
    fn default() -> Self {
        Self {
            grid: 16,
            directions: 32,
            components: 16,
            coarse_angle: DEFAULT_COARSE_ANGLE,
        }
    }
}

/// Upper limits of the knobs.
pub const MAX_SSDF_GRID: u32 = 64;
/// Largest direction map side.
pub const MAX_SSDF_DIRECTIONS: u32 = 128;
/// Most PCA components (the runtime keeps one coefficient vector per pixel).
pub const MAX_SSDF_COMPONENTS: u32 = 64;

impl SsdfKnobs {
    /// The first knob out of range, with why.
    pub fn problem(&self) -> Option<(&'static str, String)> {
        if !(2..=MAX_SSDF_GRID).contains(&self.grid) {
            return Some((
                "grid",
                format!("{} is not in 2..={MAX_SSDF_GRID}", self.grid),
            ));
        }
        if !(4..=MAX_SSDF_DIRECTIONS).contains(&self.directions) {
            return Some((
                "directions",
                format!("{} is not in 4..={MAX_SSDF_DIRECTIONS}", self.directions),
            ));
        }
        let most = MAX_SSDF_COMPONENTS
            .min(self.directions * self.directions)
            .min(self.grid.pow(3));
        if !(1..=most).contains(&self.components) {
            return Some((
                "components",
                format!("{} is not in 1..={most} (at most the directions, the nodes and {MAX_SSDF_COMPONENTS})", self.components),
            ));
        }
        if !(0.0..=MAX_COARSE_ANGLE).contains(&self.coarse_angle) {
            return Some((
                "coarse_angle",
                format!(
                    "{} is not in 0..={MAX_COARSE_ANGLE} (radians; 0 bakes every node)",
                    self.coarse_angle
                ),
            ));
        }
        None
    }

    /// The direction map.
    pub fn map(&self) -> DirectionMap {
        DirectionMap::new(MapKind::Octahedral, self.directions)
    }
}

/// Raw SSDF samples: S per (node, direction texel), node-major.
#[derive(Debug, Clone)]
pub struct SsdfSamples {
    /// The grid.
    pub grid: SsdfGrid,
    /// Side of the octahedral direction map.
    pub directions: u32,
    /// S values, `grid.count()` rows of `directions²`.
    pub values: Vec<f32>,
    /// The baked mesh's [`ObjectMesh::geometry_key`].
    pub object: u64,
    /// Seconds the bake took.
    pub seconds: f64,
    /// Nodes blended from a coarser lattice rather than baked
    /// ([`super::coarse`]).
    pub blended: usize,
    /// GPU seconds of each kernel over all batches, in the order they run.
    pub kernel_seconds: KernelSeconds,
}

/// GPU seconds of each of the bake's kernels (pass name, seconds).
pub type KernelSeconds = Vec<(String, f64)>;

/// The bake's revision, for caches of baked fields: a change to what the
/// bake computes bumps it. 2: S measured to the outline alone, pieces by
/// angle, per-invocation work bounded (issue 26's ninth pass).
pub const BAKE_REVISION: u32 = 2;

/// Bytes a triangle takes in the bake's largest storage buffer, the edges:
/// a closed mesh has 1.5 edges a triangle, of 96 bytes each.
pub const BAKE_BYTES_PER_TRIANGLE: u64 = 144;

/// Silhouette pieces one node's list holds.
pub const PIECE_CAPACITY: u32 = 65536;

/// Outline arcs one node's list holds; it bounds the bake kernel's loop
/// over them (under llvmpipe's 65535 iterations with the ray's).
pub const ARC_CAPACITY: u32 = 16384;

/// Fails, before the silhouette and BVH are built, when `mesh` is too
/// large for the bake's storage bindings on `info`'s device, naming the
/// object, the limit and the largest triangle count that fits.
pub fn check_bake_fits(info: &DeviceInfo, mesh: &ObjectMesh) -> anyhow::Result<()> {
    let limit = info.max_storage_buffer_range as u64;
    let need = BAKE_BYTES_PER_TRIANGLE * mesh.triangles() as u64;
    anyhow::ensure!(
        need <= limit,
        "{}: {} triangles: the SSDF bake binds the mesh's edges in one buffer of about \
         {} MiB, more than {}'s largest storage binding ({} MiB); simplify the mesh to at \
         most {} triangles",
        mesh.name,
        mesh.triangles(),
        need >> 20,
        info.name,
        limit >> 20,
        limit / BAKE_BYTES_PER_TRIANGLE
    );
    Ok(())
}

/// Fails, before any GPU work, when the outline seen from one of `grid`'s
/// corners (its farthest nodes, which see the whole object) already
/// outgrows a node's lists in the bake ([`PIECE_CAPACITY`],
/// [`ARC_CAPACITY`]), naming the object. Found with the CPU mirror; a
/// node elsewhere that outgrows them still fails the bake when its batch
/// is read back, never silently.
pub fn check_outline_fits(
    mesh: &ObjectMesh,
    sil: &SilhouetteMesh,
    scene: &MeshScene,
    grid: &SsdfGrid,
) -> anyhow::Result<()> {
    let top = grid.nodes - 1;
    for corner in 0..8u32 {
        let at = |bit: u32| if corner & bit != 0 { top } else { 0 };
        let node = (at(1) + grid.nodes * (at(2) + grid.nodes * at(4))) as usize;
        let x = grid.position_of(node);
        let pieces: u32 = sil
            .edges
            .iter()
            .filter(|e| e.is_silhouette(x))
            .map(|e| e.pieces(x))
            .sum();
        let arcs = sil
            .view_from(x, |o, d| super::reference::hits(scene, o, d))
            .arcs() as u32;
        for (what, count, capacity) in [
            ("silhouette pieces", pieces, PIECE_CAPACITY),
            ("outline arcs", arcs, ARC_CAPACITY),
        ] {
            anyhow::ensure!(
                count <= capacity,
                "{}: {count} {what} seen from the SSDF grid's corner {x:.3}, more than the bake \
                 holds ({capacity}); simplify the mesh",
                mesh.name
            );
        }
    }
    Ok(())
}

/// The object in its own frame as a ray-casting scene.
pub fn object_scene(mesh: &Arc<ObjectMesh>) -> MeshScene {
    MeshScene::new(&[PlacedObject {
        name: mesh.name.clone(),
        mesh: mesh.clone(),
        pose: Pose::default(),
        material: Default::default(),
    }])
}

/// The grid of `nodes`³ around `mesh`'s bounding sphere.
pub fn grid_for(mesh: &ObjectMesh, nodes: u32) -> SsdfGrid {
    let (centre, radius) = mesh.bounding_sphere();
    SsdfGrid {
        centre,
        radius: radius.max(1e-12),
        nodes,
    }
}

/// The point each node's SSDF is computed from: the node itself, or for a
/// node inside the object the nearest surface point lifted off the surface.
pub fn lookup_points(scene: &MeshScene, grid: &SsdfGrid) -> Vec<DVec3> {
    node_sites(scene, grid).into_iter().map(|s| s.0).collect()
}

/// Each node's [`lookup_points`] point and whether the node lies inside
/// the object.
pub fn node_sites(scene: &MeshScene, grid: &SsdfGrid) -> Vec<(DVec3, bool)> {
    use rayon::prelude::*;
    (0..grid.count())
        .into_par_iter()
        .map(|i| {
            let p = grid.position_of(i);
            if !scene.inside(p) {
                return (p, false);
            }
            match scene.nearest_point(p) {
                Some((q, n)) => (q + n * (1e-3 * grid.radius), true),
                None => (p, true),
            }
        })
        .collect()
}

/// S at every direction texel seen from each of `points`, in f64 (the
/// kernel's CPU mirror).
pub fn bake_reference(
    mesh: &ObjectMesh,
    scene: &MeshScene,
    points: &[DVec3],
    directions: u32,
) -> Vec<f64> {
    use rayon::prelude::*;
    let sil = SilhouetteMesh::new(mesh);
    let map = DirectionMap::new(MapKind::Octahedral, directions);
    points
        .par_iter()
        .flat_map_iter(|&x| {
            let hits = |o: DVec3, d: DVec3| super::reference::hits(scene, o, d);
            let view = sil.view_from(x, hits);
            (0..map.texels() as u32)
                .map(|t| {
                    let d = map.direction(t % directions, t / directions);
                    view.signed_angle(d, hits(x, d))
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The edges of `sil` (indices) that may be on the silhouette seen from
/// some point of the box `lo`..`hi`: all but those whose two faces both
/// face every point of the box or both face away from every point, by a
/// margin of 10⁻⁵ of the planes' scale (above f32 rounding, so the kernel's
/// f32 test never drops an edge that its per-node test would find). The
/// f64 mirror of `shaders/ssdf/ssdf_candidates.wgsl`, in edge order.
pub fn edge_candidates(sil: &SilhouetteMesh, lo: DVec3, hi: DVec3) -> Vec<u32> {
    let (centre, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
    let side = |plane: glam::DVec4| {
        let n = plane.truncate();
        let s = n.dot(centre) - plane.w;
        let reach = n.abs().dot(half);
        let margin = 1e-5 * (plane.w.abs() + n.abs().dot(centre.abs() + half));
        if s - reach > margin {
            1
        } else if s + reach < -margin {
            -1
        } else {
            0
        }
    };
    (0..sil.edges.len() as u32)
        .filter(|&i| {
            let e = &sil.edges[i as usize];
            let (s0, s1) = (side(e.planes[0]), side(e.planes[1]));
            e.always || s0 == 0 || s0 != s1
        })
        .collect()
}

/// The smallest box holding `points` (lower, upper corner).
fn bounds_of(points: &[DVec3]) -> (DVec3, DVec3) {
    points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

/// The order the bake takes `points` in: along a Morton curve over their
/// bounding box (10 bits an axis), so that consecutive points, a batch,
/// lie in a compact block (a 4 × 4 × 2 block of nodes, for a grid whose
/// side is a power of two).
pub fn morton_order(points: &[DVec3]) -> Vec<usize> {
    let (lo, hi) = bounds_of(points);
    let scale = 1023.0 / (hi - lo).max_element().max(1e-300);
    let spread = |v: u32| -> u64 {
        (0..10).fold(0u64, |m, bit| m | ((((v >> bit) & 1) as u64) << (3 * bit)))
    };
    let code = |p: &DVec3| {
        let q = ((*p - lo) * scale)
            .round()
            .clamp(DVec3::ZERO, DVec3::splat(1023.0));
        spread(q.x as u32) | spread(q.y as u32) << 1 | spread(q.z as u32) << 2
    };
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by_key(|&i| (code(&points[i]), i));
    order
}

/// The bake's five kernels (see the module's documentation).
pub struct SsdfBaker {
    candidates: Arc<ComputePipeline>,
    pieces: Arc<ComputePipeline>,
    outer: Arc<ComputePipeline>,
    arcs: Arc<ComputePipeline>,
    pipeline: Arc<ComputePipeline>,
}

/// Nodes per submission: small enough that progress moves and no single
/// submission runs long on a slow device (a batch's lists take 1.5 MiB a
/// node).
const NODES_PER_BATCH: usize = 32;

/// Directions one invocation of the bake kernel measures: 8, the kernel's
/// two groups of four (`shaders/ssdf/ssdf_bake.wgsl`). Not a knob: 16 in
/// a loop was as fast on lavapipe, 4 slower by a half, 1 by four times.
const DIRECTIONS_PER_INVOCATION: u32 = 8;

/// Bytes of one arc in the outline lists (four vec4s: `ssdf_prepare_arc`
/// in `shaders/ssdf/angles.wgsl`).
const ARC_BYTES: u64 = 64;

impl SsdfBaker {
    /// Compiles the kernels.
    pub fn new(ctx: &Arc<Context>, lib: &ShaderLibrary) -> anyhow::Result<Self> {
        let defines = [
            Define::U32("ARC_PIECES", ARC_PIECES),
            Define::F32("OUTSIDE_OFFSET", OUTSIDE_OFFSET as f32),
            Define::F32("PIECE_ANGLE", PIECE_ANGLE as f32),
            Define::U32("PIECE_CAPACITY", PIECE_CAPACITY),
            Define::U32("ARC_CAPACITY", ARC_CAPACITY),
            Define::U32("DIRECTIONS_PER_INVOCATION", DIRECTIONS_PER_INVOCATION),
            Define::Bool("OCTAHEDRAL", true),
        ];
        let kernel = |file: &str| lib.compute_pipeline(ctx, file, "main", &defines);
        Ok(Self {
            candidates: kernel("ssdf/ssdf_candidates.wgsl")?,
            pieces: kernel("ssdf/ssdf_pieces.wgsl")?,
            outer: kernel("ssdf/ssdf_outer.wgsl")?,
            arcs: kernel("ssdf/ssdf_arcs.wgsl")?,
            pipeline: kernel("ssdf/ssdf_bake.wgsl")?,
        })
    }

    /// Bakes S for `mesh` with `knobs` (`progress(done, total)` after each
    /// batch of nodes).
    pub fn bake(
        &self,
        ctx: &Arc<Context>,
        mesh: &Arc<ObjectMesh>,
        knobs: &SsdfKnobs,
        progress: &dyn Fn(usize, usize),
    ) -> anyhow::Result<SsdfSamples> {
        if let Some((k, m)) = knobs.problem() {
            anyhow::bail!("ssdf knob `{k}`: {m}");
        }
        anyhow::ensure!(
            mesh.triangles() > 0,
            "{}: the object has no triangles to cast a shadow",
            mesh.name
        );
        check_bake_fits(ctx.info(), mesh)?;
        let started = Instant::now();
        let grid = grid_for(mesh, knobs.grid);
        let scene = object_scene(mesh);
        let sil = SilhouetteMesh::new(mesh);
        check_outline_fits(mesh, &sil, &scene, &grid)?;
        let sites = node_sites(&scene, &grid);
        let inside: Vec<bool> = sites.iter().map(|s| s.1).collect();
        let plan = NodePlan::new(&scene, &grid, &inside, knobs.coarse_angle);
        let points: Vec<DVec3> = plan.baked.iter().map(|&i| sites[i].0).collect();
        let (baked, kernel_seconds) =
            self.run_edges(ctx, mesh, &sil, &scene, &points, knobs.directions, progress)?;
        let texels = (knobs.directions * knobs.directions) as usize;
        Ok(SsdfSamples {
            grid,
            directions: knobs.directions,
            values: plan.fill(&grid, &baked, texels),
            object: mesh.geometry_key(),
            seconds: started.elapsed().as_secs_f64(),
            blended: plan.blended.len(),
            kernel_seconds,
        })
    }

    /// S at every direction texel from each of `points` on the GPU, and
    /// the GPU seconds of each kernel over all batches.
    pub fn run(
        &self,
        ctx: &Arc<Context>,
        mesh: &ObjectMesh,
        scene: &MeshScene,
        points: &[DVec3],
        directions: u32,
        progress: &dyn Fn(usize, usize),
    ) -> anyhow::Result<(Vec<f32>, KernelSeconds)> {
        let sil = SilhouetteMesh::new(mesh);
        self.run_edges(ctx, mesh, &sil, scene, points, directions, progress)
    }

    /// [`Self::run`] with the mesh's edges already collected.
    #[allow(clippy::too_many_arguments)]
    fn run_edges(
        &self,
        ctx: &Arc<Context>,
        mesh: &ObjectMesh,
        sil: &SilhouetteMesh,
        scene: &MeshScene,
        points: &[DVec3],
        directions: u32,
        progress: &dyn Fn(usize, usize),
    ) -> anyhow::Result<(Vec<f32>, KernelSeconds)> {
        let mut kernel_seconds: KernelSeconds = Vec::new();
        let order = morton_order(points);
        let sorted: Vec<DVec3> = order.iter().map(|&i| points[i]).collect();
        let pts: Vec<f32> = sorted
            .iter()
            .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32, 0.0])
            .collect();
        let (nodes, tris) = scene.packed();
        let points_buf = storage(ctx, "ssdf points", &pts)?;
        let edges_buf = storage(ctx, "ssdf edges", &pack_edges(sil))?;
        let nodes_buf = storage(ctx, "ssdf bvh nodes", &nodes)?;
        let tris_buf = storage(ctx, "ssdf bvh triangles", &tris)?;
        let texels = (directions * directions) as usize;
        let edge_count = sil.edges.len() as u32;
        let mut out = vec![0.0f32; points.len() * texels];
        let mut renderer = Renderer::new(ctx, 1)?;
        // Sized for a whole batch, reused by every batch (a shorter last
        // batch fills their start).
        let whole = NODES_PER_BATCH as u64;
        let readback = BufferReadback::new(ctx, "ssdf readback", whole * texels as u64 * 4)?;
        let piece_readback = BufferReadback::new(ctx, "ssdf piece counts", 4 * whole)?;
        let arc_readback = BufferReadback::new(ctx, "ssdf arc counts", 4 * whole)?;
        for start in (0..points.len()).step_by(NODES_PER_BATCH) {
            let count = NODES_PER_BATCH.min(points.len() - start);
            let n = count as u64;
            let size = n * texels as u64 * 4;
            renderer.begin_frame()?;
            let mut graph = FrameGraph::new();
            let bound = [&points_buf, &edges_buf, &nodes_buf, &tris_buf]
                .map(|b| graph.import_buffer(b, None));
            let push = batch_push(&sorted[start..start + count], start, directions, edge_count);
            let (candidates, candidate_count, candidate_args) =
                self.add_candidates(&mut graph, bound[1], &push, edge_count, count as u32);
            let zeros =
                |graph: &mut FrameGraph, name: &str| graph.upload_buffer(name, vec![0; 4 * count]);
            let args = [0u32, count as u32, 1]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect();
            let mut piece_args = graph.upload_buffer("ssdf piece args", args);
            let mut pieces = graph.create_buffer("ssdf pieces", 4 * PIECE_CAPACITY as u64 * n);
            let mut piece_counts = zeros(&mut graph, "ssdf piece counts");
            graph
                .compute("ssdf-pieces", &self.pieces)
                .read("points", bound[0])
                .read("edges", bound[1])
                .read("candidates", candidates)
                .read("candidate_count", candidate_count)
                .write("pieces", &mut pieces)
                .read_write("piece_counts", &mut piece_counts)
                .read_write("piece_args", &mut piece_args)
                .push(&push)
                .indirect(candidate_args, 0);
            let mut outer = graph.create_buffer("ssdf outer", 4 * PIECE_CAPACITY as u64 * n);
            graph
                .compute("ssdf-outer", &self.outer)
                .read("points", bound[0])
                .read("edges", bound[1])
                .read("bvh_nodes", bound[2])
                .read("bvh_triangles", bound[3])
                .read("pieces", pieces)
                .read("piece_counts", piece_counts)
                .write("outer", &mut outer)
                .push(&push)
                .indirect(piece_args, 0);
            let mut arcs = graph.create_buffer("ssdf arcs", ARC_BYTES * ARC_CAPACITY as u64 * n);
            let mut arc_counts = zeros(&mut graph, "ssdf arc counts");
            graph
                .compute("ssdf-arcs", &self.arcs)
                .read("points", bound[0])
                .read("edges", bound[1])
                .read("pieces", pieces)
                .read("piece_counts", piece_counts)
                .read("outer", outer)
                .write("arcs", &mut arcs)
                .read_write("arc_counts", &mut arc_counts)
                .push(&push)
                .indirect(piece_args, 0);
            let mut written = graph.create_buffer("ssdf batch", size);
            graph
                .compute("ssdf-bake", &self.pipeline)
                .read("points", bound[0])
                .read("bvh_nodes", bound[2])
                .read("bvh_triangles", bound[3])
                .read("arcs", arcs)
                .read("arc_counts", arc_counts)
                .write("out_ssdf", &mut written)
                .push(&push)
                .groups([
                    (texels as u32).div_ceil(64 * DIRECTIONS_PER_INVOCATION),
                    count as u32,
                    1,
                ]);
            readback.add_to_graph(&mut graph, "ssdf readback", written);
            piece_readback.add_to_graph(&mut graph, "ssdf piece counts readback", piece_counts);
            arc_readback.add_to_graph(&mut graph, "ssdf arc counts readback", arc_counts);
            renderer.submit(graph, &SubmitSync::none())?;
            renderer.finish()?;
            if let Some(timings) = renderer.latest_timings() {
                for pass in timings
                    .passes
                    .iter()
                    .filter(|p| p.name.starts_with("ssdf-"))
                {
                    match kernel_seconds.iter_mut().find(|(n, _)| *n == pass.name) {
                        Some(k) => k.1 += pass.gpu_ms / 1e3,
                        None => kernel_seconds.push((pass.name.clone(), pass.gpu_ms / 1e3)),
                    }
                }
            }
            for (what, counts, capacity) in [
                ("silhouette pieces", &piece_readback, PIECE_CAPACITY),
                ("outline arcs", &arc_readback, ARC_CAPACITY),
            ] {
                let most = counts
                    .read_f32()?
                    .into_iter()
                    .take(count)
                    .map(f32::to_bits)
                    .max()
                    .unwrap_or(0);
                anyhow::ensure!(
                    most <= capacity,
                    "{}: {most} {what} seen from one node of the SSDF grid, more than the bake \
                     holds ({capacity}); simplify the mesh",
                    mesh.name
                );
            }
            let values = readback.read_f32()?;
            for (k, row) in values.chunks_exact(texels).take(count).enumerate() {
                let node = order[start + k];
                out[node * texels..(node + 1) * texels].copy_from_slice(row);
            }
            progress(start + count, points.len());
        }
        Ok((out, kernel_seconds))
    }

    /// Adds the candidates kernel for the batch `push` describes: the
    /// candidate list (edge indices, `edge_count` slots), its length, and
    /// the next kernel's indirect dispatch over it for `nodes` nodes.
    fn add_candidates(
        &self,
        graph: &mut FrameGraph,
        edges: BufferHandle,
        push: &BakePush,
        edge_count: u32,
        nodes: u32,
    ) -> (BufferHandle, BufferHandle, BufferHandle) {
        let mut candidates = graph.create_buffer("ssdf candidates", 4 * edge_count.max(1) as u64);
        let mut candidate_count = graph.upload_buffer("ssdf candidate count", vec![0; 4]);
        let args = [0u32, nodes, 1]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let mut candidate_args = graph.upload_buffer("ssdf candidate args", args);
        graph
            .compute("ssdf-candidates", &self.candidates)
            .read("edges", edges)
            .write("candidates", &mut candidates)
            .read_write("candidate_count", &mut candidate_count)
            .read_write("candidate_args", &mut candidate_args)
            .push(push)
            .groups([edge_count.div_ceil(64), 1, 1]);
        (candidates, candidate_count, candidate_args)
    }

    /// The candidates kernel alone on the box `lo`..`hi` (what
    /// [`edge_candidates`] mirrors): the edge indices it keeps, sorted.
    pub fn candidates(
        &self,
        ctx: &Arc<Context>,
        mesh: &ObjectMesh,
        lo: DVec3,
        hi: DVec3,
    ) -> anyhow::Result<Vec<u32>> {
        let sil = SilhouetteMesh::new(mesh);
        let edge_count = sil.edges.len() as u32;
        let edges_buf = storage(ctx, "ssdf edges", &pack_edges(&sil))?;
        let push = batch_push(&[lo, hi], 0, 0, edge_count);
        let mut renderer = Renderer::new(ctx, 1)?;
        let list = BufferReadback::new(ctx, "ssdf candidates", 4 * edge_count.max(1) as u64)?;
        let total = BufferReadback::new(ctx, "ssdf candidate count", 4)?;
        renderer.begin_frame()?;
        let mut graph = FrameGraph::new();
        let edges = graph.import_buffer(&edges_buf, None);
        let (candidates, count, _) = self.add_candidates(&mut graph, edges, &push, edge_count, 1);
        list.add_to_graph(&mut graph, "ssdf candidates readback", candidates);
        total.add_to_graph(&mut graph, "ssdf candidate count readback", count);
        renderer.submit(graph, &SubmitSync::none())?;
        renderer.finish()?;
        let as_u32 = |v: Vec<f32>| -> Vec<u32> { v.into_iter().map(f32::to_bits).collect() };
        let n = as_u32(total.read_f32()?)[0] as usize;
        let mut kept = as_u32(list.read_f32()?);
        kept.truncate(n);
        kept.sort_unstable();
        Ok(kept)
    }
}

/// The push block of the batch of `points` (sorted order) from `start`.
fn batch_push(points: &[DVec3], start: usize, directions: u32, edge_count: u32) -> BakePush {
    let (lo, hi) = bounds_of(points);
    let v4 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
    BakePush {
        node_offset: start as u32,
        map_size: directions,
        edge_count,
        node_count: points.len() as u32,
        box_lo: v4(lo),
        box_hi: v4(hi),
    }
}

/// The edges as the kernels read them: six vec4s each, (a, always),
/// (b, 0), the two faces' planes, the two faces' third corners.
fn pack_edges(sil: &SilhouetteMesh) -> Vec<f32> {
    let mut edges = Vec::with_capacity(sil.edges.len() * 24);
    for e in &sil.edges {
        let v4 = |v: DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
        edges.extend(v4(e.a, e.always as u32 as f64));
        edges.extend(v4(e.b, 0.0));
        for p in e.planes {
            edges.extend(p.to_array().map(|x| x as f32));
        }
        edges.extend(v4(e.opposite[0], 0.0));
        edges.extend(v4(e.opposite[1], 0.0));
    }
    edges
}

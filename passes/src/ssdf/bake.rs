//! Baking an object's SSDF field (METHOD.md "SSDF field"): S(d; x) at every
//! direction texel of an octahedral map, at every node of the grid, on the
//! GPU (`shaders/ssdf/ssdf_bake.wgsl`, batches of nodes per submission so
//! progress can be shown), with [`bake_reference`] its f64 CPU mirror.
//!
//! **Nodes inside the object** see it in every direction (S = −π
//! everywhere), which would drag every interpolated value near the surface
//! to "fully blocked" and self-shadow even a convex object. Such nodes take
//! instead the SSDF seen from the nearest surface point, lifted off the
//! surface by 10⁻³ of the radius along its face normal: the field then
//! continues across the surface the way it approaches it from outside.

use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;
use inlay_engine::graph::FrameGraph;
use inlay_engine::shader::{Define, ShaderLibrary};
use inlay_engine::{
    vk, Buffer, BufferReadback, ComputePipeline, Context, DeviceInfo, Renderer, SubmitSync,
};

use super::grid::SsdfGrid;
use super::silhouette::{SilhouetteMesh, ARC_PIECES, OUTSIDE_OFFSET};
use crate::geometry::MeshScene;
use crate::object::{ObjectMesh, PlacedObject, Pose};
use crate::probe::{DirectionMap, MapKind};

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
    }
}

/// The knobs of an SSDF bake.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SsdfKnobs {
    /// Nodes along each axis of the grid (paper: 16).
    pub grid: u32,
    /// Side of the octahedral direction map (texels = directions²).
    pub directions: u32,
    /// PCA components kept.
    pub components: u32,
}

impl Default for SsdfKnobs {
    fn default() -> Self {
        Self {
            grid: 16,
            directions: 32,
            components: 16,
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
}

/// Bytes a triangle takes in the bake's largest storage buffer: a closed
/// mesh has 1.5 edges a triangle, and one node's silhouette may hold every
/// edge in up to `ARC_PIECES` arcs of 32 bytes (192 bytes a triangle; the
/// edges themselves take 96 bytes each, 144 a triangle).
pub const BAKE_BYTES_PER_TRIANGLE: u64 = 192;

/// Fails, before the silhouette and BVH are built, when `mesh` is too
/// large for the bake's storage bindings on `info`'s device, naming the
/// object, the limit and the largest triangle count that fits.
pub fn check_bake_fits(info: &DeviceInfo, mesh: &ObjectMesh) -> anyhow::Result<()> {
    let limit = info.max_storage_buffer_range as u64;
    let need = BAKE_BYTES_PER_TRIANGLE * mesh.triangles() as u64;
    anyhow::ensure!(
        need <= limit,
        "{}: {} triangles: the SSDF bake binds one node's silhouette arcs in one buffer of about \
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
    use rayon::prelude::*;
    (0..grid.count())
        .into_par_iter()
        .map(|i| {
            let p = grid.position_of(i);
            if !scene.inside(p) {
                return p;
            }
            match scene.nearest_point(p) {
                Some((q, n)) => q + n * (1e-3 * grid.radius),
                None => p,
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

/// The bake's two kernels: each node's silhouette arcs, then S at every
/// direction from them.
pub struct SsdfBaker {
    silhouette: Arc<ComputePipeline>,
    pipeline: Arc<ComputePipeline>,
}

/// Nodes per submission at most: small enough that progress moves and no
/// single submission runs long on a slow device (fewer when a batch's
/// arcs would outgrow a storage binding).
const NODES_PER_BATCH: usize = 32;

/// Bytes of one arc in the buffer between the two kernels (two vec4s).
const ARC_BYTES: u64 = 32;

impl SsdfBaker {
    /// Compiles the kernels.
    pub fn new(ctx: &Arc<Context>, lib: &ShaderLibrary) -> anyhow::Result<Self> {
        let silhouette = lib.compute_pipeline(
            ctx,
            "ssdf/ssdf_silhouette.wgsl",
            "main",
            &[
                Define::U32("ARC_PIECES", ARC_PIECES),
                Define::F32("OUTSIDE_OFFSET", OUTSIDE_OFFSET as f32),
            ],
        )?;
        let pipeline = lib.compute_pipeline(
            ctx,
            "ssdf/ssdf_bake.wgsl",
            "main",
            &[
                Define::U32("ARC_PIECES", ARC_PIECES),
                Define::Bool("OCTAHEDRAL", true),
            ],
        )?;
        Ok(Self {
            silhouette,
            pipeline,
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
        let points = lookup_points(&scene, &grid);
        let values = self.run(ctx, mesh, &scene, &points, knobs.directions, progress)?;
        Ok(SsdfSamples {
            grid,
            directions: knobs.directions,
            values,
            object: mesh.geometry_key(),
            seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// S at every direction texel from each of `points` on the GPU.
    pub fn run(
        &self,
        ctx: &Arc<Context>,
        mesh: &ObjectMesh,
        scene: &MeshScene,
        points: &[DVec3],
        directions: u32,
        progress: &dyn Fn(usize, usize),
    ) -> anyhow::Result<Vec<f32>> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let bytes = |v: &[f32]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
        let pts: Vec<f32> = points
            .iter()
            .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32, 0.0])
            .collect();
        let sil = SilhouetteMesh::new(mesh);
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
        let (nodes, tris) = scene.packed();
        let upload = |name: &str, v: &[f32]| -> anyhow::Result<Arc<Buffer>> {
            let mut b = bytes(v);
            b.resize(b.len().max(16), 0);
            Ok(Arc::new(Buffer::with_data(ctx, name, &b, storage)?))
        };
        let points_buf = upload("ssdf points", &pts)?;
        let edges_buf = upload("ssdf edges", &edges)?;
        let nodes_buf = upload("ssdf bvh nodes", &nodes)?;
        let tris_buf = upload("ssdf bvh triangles", &tris)?;
        let texels = (directions * directions) as usize;
        let edge_count = sil.edges.len() as u32;
        let mut out = Vec::with_capacity(points.len() * texels);
        let mut renderer = Renderer::new(ctx, 1)?;
        let node_arc_bytes = ARC_BYTES * edge_count as u64 * ARC_PIECES as u64;
        let limit = ctx.info().max_storage_buffer_range as u64;
        let batch = NODES_PER_BATCH.min((limit / node_arc_bytes.max(1)).max(1) as usize);
        for start in (0..points.len()).step_by(batch) {
            let count = batch.min(points.len() - start);
            let size = (count * texels * 4) as u64;
            let readback = BufferReadback::new(ctx, "ssdf readback", size)?;
            renderer.begin_frame()?;
            let mut graph = FrameGraph::new();
            let target = graph.create_buffer("ssdf batch", size);
            let bound = [&points_buf, &edges_buf, &nodes_buf, &tris_buf]
                .map(|b| graph.import_buffer(b, None));
            let push = BakePush {
                node_offset: start as u32,
                map_size: directions,
                edge_count,
                node_count: count as u32,
            };
            let mut arcs = graph.create_buffer("ssdf arcs", node_arc_bytes.max(16) * count as u64);
            let mut arc_counts = graph.create_buffer("ssdf arc counts", 4 * count as u64);
            graph
                .compute("ssdf-silhouette", &self.silhouette)
                .read("points", bound[0])
                .read("edges", bound[1])
                .read("bvh_nodes", bound[2])
                .read("bvh_triangles", bound[3])
                .write("arcs", &mut arcs)
                .write("arc_counts", &mut arc_counts)
                .push(&push)
                .groups([count as u32, 1, 1]);
            let mut written = target;
            graph
                .compute("ssdf-bake", &self.pipeline)
                .read("points", bound[0])
                .read("bvh_nodes", bound[2])
                .read("bvh_triangles", bound[3])
                .read("arcs", arcs)
                .read("arc_counts", arc_counts)
                .write("out_ssdf", &mut written)
                .push(&push)
                .groups([(texels as u32).div_ceil(64), count as u32, 1]);
            readback.add_to_graph(&mut graph, "ssdf readback", written);
            renderer.submit(graph, &SubmitSync::none())?;
            renderer.finish()?;
            out.extend(readback.read_f32()?);
            progress(start + count, points.len());
        }
        Ok(out)
    }
}

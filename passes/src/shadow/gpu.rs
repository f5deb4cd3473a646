//! Shadow data on the GPU: an object's compressed SSDF field, the f_h
//! table, the per-frame object block (`SsdfObject` in
//! `shaders/ssdf/ssdf.wgsl`) and the defines every shadow shader needs.

use std::sync::Arc;

use inlay_engine::graph::{BufferHandle, FrameGraph};
use inlay_engine::shader::Define;
use inlay_engine::{vk, Buffer, Context};

use super::fh::{FhTable, FH_COLUMNS, FH_ROWS, FH_SHARPNESS_RANGE};
use super::ObjectReflectance;
use crate::object::{ObjectMesh, ObjectRecords, PlacedObject};
use crate::ssdf::bake::MAX_SSDF_COMPONENTS;
use crate::ssdf::field::{OutsideMode, SsdfField};

inlay_engine::gpu_struct! {
    /// `SsdfObject` of `shaders/ssdf/ssdf.wgsl` (checked through the cast
    /// shadow, which binds it): an object's SSDF as one
    /// frame reads it.
    pub struct SsdfObject = "shadow/cast.wgsl" : "SsdfObject" {
        /// Grid centre (object space) and bounding-sphere radius.
        pub grid: [f32; 4],
        /// Nodes per axis, direction map side, components, outside mode.
        pub dims: [u32; 4],
        /// Silhouette fill times albedo (rgb) and the fill alone (w).
        pub reflectance: [f32; 4],
        /// The object's record in the frame's [`ObjectRecords`] (its pose).
        pub object: u32,
        /// Padding (the struct's size rounds up to 16 bytes).
        pub _pad: [u32; 3],
    }
}

/// The defines of `shadow/fh.wgsl`, `shadow/cone.wgsl`, `ssdf/ssdf.wgsl`
/// and `shadow/cast_body.wgsl`.
pub fn shadow_defines() -> Vec<Define> {
    vec![
        Define::U32("FH_COLUMNS", FH_COLUMNS),
        Define::U32("FH_ROWS", FH_ROWS),
        Define::F32("FH_SHARPNESS_MIN", FH_SHARPNESS_RANGE.0 as f32),
        Define::F32("FH_SHARPNESS_MAX", FH_SHARPNESS_RANGE.1 as f32),
        Define::U32("SSDF_MAX_ROW_VEC4S", row_vec4s(MAX_SSDF_COMPONENTS)),
        Define::U32("MAX_LOCAL_LIGHTS", crate::lighting::local::MAX_LOCAL_LIGHTS),
        Define::U32("CONE_POINTS", super::CONE_POINTS as u32),
        Define::F32("CONE_RESOLUTION", super::CONE_RESOLUTION as f32),
    ]
}

/// vec4s a row of the GPU's SSDF data holds for `components` PCA
/// components: the mean (or a 1) and the k values, zero-padded to whole
/// vec4s (`ssdf_row_vec4s` in `shaders/ssdf/ssdf.wgsl`).
pub fn row_vec4s(components: u32) -> u32 {
    (components + 4) / 4
}

/// `field`'s texel rows and node coefficients as the GPU reads them: each
/// texel's (mean, basis values) and each node's (1, coefficients) in
/// [`row_vec4s`] vec4s, zero-padded, so that a texel's value is the dot
/// product of its row with a node's (or a blend of nodes') and the shader
/// reads a vec4 at a time (DOG's shading read its SSDF in 36 ms of 99 at
/// 1280 × 720 one float at a time; docs/benchmarks.md, issue 26's eighth
/// pass).
pub fn gpu_rows(field: &SsdfField) -> (Vec<f32>, Vec<f32>) {
    let k = field.components as usize;
    let stride = 4 * row_vec4s(field.components) as usize;
    let pad = |rows: &mut Vec<f32>| rows.resize(rows.len().next_multiple_of(stride), 0.0);
    let mut texels = Vec::with_capacity(field.texels() * stride);
    for row in field.texel_rows.chunks_exact(k + 1) {
        texels.extend_from_slice(row);
        pad(&mut texels);
    }
    let mut nodes = Vec::with_capacity(field.grid.count() * stride);
    for coefficients in field.coefficients.chunks_exact(k) {
        nodes.push(1.0);
        nodes.extend_from_slice(coefficients);
        pad(&mut nodes);
    }
    (texels, nodes)
}

/// A storage buffer holding `values` (at least 16 bytes, as a binding
/// may not be empty).
pub(crate) fn storage(
    ctx: &Arc<Context>,
    name: &str,
    values: &[f32],
) -> anyhow::Result<Arc<Buffer>> {
    let mut bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    bytes.resize(bytes.len().max(16), 0);
    Ok(Arc::new(Buffer::with_data(
        ctx,
        name,
        &bytes,
        vk::BufferUsageFlags::STORAGE_BUFFER,
    )?))
}

/// The f_h table, uploaded once.
pub struct GpuFhTable {
    /// The table (also used by the CPU mirrors).
    pub table: FhTable,
    buffer: Arc<Buffer>,
}

impl GpuFhTable {
    /// Tabulates and uploads.
    pub fn new(ctx: &Arc<Context>) -> anyhow::Result<Self> {
        let table = FhTable::new();
        let buffer = storage(ctx, "fh table", table.values())?;
        Ok(Self { table, buffer })
    }

    /// The buffer in `graph`.
    pub fn import(&self, graph: &mut FrameGraph) -> BufferHandle {
        graph.import_buffer(&self.buffer, None)
    }
}

/// An object's shadow geometry on the GPU: its SSDF field, and its mesh
/// in a bounding-volume hierarchy for the direct lobes' ray-cast shadows
/// ([`super::direct`]), both in the object's own frame.
pub struct GpuSsdf {
    /// The field (for the CPU mirrors and the per-frame block).
    pub field: Arc<SsdfField>,
    rows: Arc<Buffer>,
    coefs: Arc<Buffer>,
    bvh_nodes: Arc<Buffer>,
    bvh_triangles: Arc<Buffer>,
    /// How much of its bounding sphere the mesh fills, with what albedo
    /// (the light it sends back onto the field, [`super::bounce`]).
    pub reflectance: super::ObjectReflectance,
}

/// A [`GpuSsdf`]'s buffers in one frame's graph.
#[derive(Debug, Clone, Copy)]
pub struct SsdfBindings {
    /// The per-frame `SsdfObject` block (read-only storage; see
    /// shaders/ssdf/ssdf.wgsl for why not uniform).
    pub object: BufferHandle,
    /// The frame's object records (the object's pose is one of them).
    pub records: BufferHandle,
    /// Per texel: mean and basis.
    pub rows: BufferHandle,
    /// Per node: coefficients.
    pub coefs: BufferHandle,
    /// The mesh's hierarchy: nodes (`shaders/geometry/mesh_bvh.wgsl`).
    pub bvh_nodes: BufferHandle,
    /// The mesh's hierarchy: triangles.
    pub bvh_triangles: BufferHandle,
}

impl GpuSsdf {
    /// Uploads `field` and the hierarchy of `mesh` (the mesh it was baked
    /// from); fails with a clear message when the mesh's triangles exceed
    /// the device's largest storage binding.
    pub fn upload(
        ctx: &Arc<Context>,
        field: Arc<SsdfField>,
        mesh: &Arc<ObjectMesh>,
    ) -> anyhow::Result<Self> {
        let (nodes, triangles) = crate::ssdf::object_scene(mesh).packed();
        let limit = ctx.info().max_storage_buffer_range as u64;
        let bytes = triangles.len() as u64 * 4;
        anyhow::ensure!(
            bytes <= limit,
            "object `{}`: its {} triangles take {} MiB for the shadow rays, beyond this \
             device's largest storage binding ({} MiB): simplify the mesh",
            mesh.name,
            triangles.len() / 12,
            bytes >> 20,
            limit >> 20
        );
        let (rows, coefs) = gpu_rows(&field);
        Ok(Self {
            rows: storage(ctx, "ssdf rows", &rows)?,
            coefs: storage(ctx, "ssdf coefficients", &coefs)?,
            bvh_nodes: storage(ctx, "shadow bvh nodes", &nodes)?,
            bvh_triangles: storage(ctx, "shadow bvh triangles", &triangles)?,
            reflectance: super::ObjectReflectance::measure(mesh),
            field,
        })
    }

    /// Imports the field and uploads this frame's block for `placed`,
    /// whose pose is record `record` of `records`.
    pub fn import(
        &self,
        graph: &mut FrameGraph,
        placed: &PlacedObject,
        (records, record): (ObjectRecords, u32),
        mode: OutsideMode,
    ) -> SsdfBindings {
        let block = object_block(&self.field, placed, record, mode, &self.reflectance);
        SsdfBindings {
            object: graph.upload_buffer("ssdf object", bytemuck::bytes_of(&block).to_vec()),
            records: records.buffer,
            rows: graph.import_buffer(&self.rows, None),
            coefs: graph.import_buffer(&self.coefs, None),
            bvh_nodes: graph.import_buffer(&self.bvh_nodes, None),
            bvh_triangles: graph.import_buffer(&self.bvh_triangles, None),
        }
    }
}

/// The `SsdfObject` block: grid, dims, the object's silhouette reflectance
/// ([`ObjectReflectance::of`]) and fill, and the index of its pose in the
/// frame's object records.
pub fn object_block(
    field: &SsdfField,
    placed: &PlacedObject,
    record: u32,
    mode: OutsideMode,
    object: &ObjectReflectance,
) -> SsdfObject {
    let g = &field.grid;
    SsdfObject {
        grid: g.centre.extend(g.radius).as_vec4().to_array(),
        dims: [g.nodes, field.directions, field.components, mode.index()],
        reflectance: object.of(placed).extend(object.fill).as_vec4().to_array(),
        object: record,
        _pad: [0; 3],
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::{gpu_rows, row_vec4s};
    use crate::ssdf::field::SsdfField;
    use crate::ssdf::grid::SsdfGrid;

    /// Every texel's value at every node, read as the shader reads the
    /// padded rows (one dot product of whole vec4s), equals the field's own,
    /// for component counts below, at and past a vec4's width.
    #[test]
    fn padded_rows_give_the_fields_values() {
        for k in [1u32, 3, 4, 7, 16] {
            let grid = SsdfGrid {
                centre: DVec3::ZERO,
                radius: 1.0,
                nodes: 3,
            };
            let directions = 4;
            let texels = (directions * directions) as usize;
            let value = |i: usize| (i as f32 * 0.61).sin() * 1.7;
            let field = SsdfField {
                grid,
                directions,
                components: k,
                texel_rows: (0..texels * (k as usize + 1)).map(value).collect(),
                coefficients: (0..grid.count() * k as usize)
                    .map(|i| value(i + 1000))
                    .collect(),
                object: 0,
            };
            let (rows, nodes) = gpu_rows(&field);
            let stride = 4 * row_vec4s(k) as usize;
            assert_eq!(rows.len(), texels * stride);
            assert_eq!(nodes.len(), grid.count() * stride);
            for n in 0..grid.count() {
                for t in 0..texels {
                    let node = &nodes[n * stride..(n + 1) * stride];
                    let row = &rows[t * stride..(t + 1) * stride];
                    let gpu: f64 = node
                        .iter()
                        .zip(row)
                        .map(|(a, b)| *a as f64 * *b as f64)
                        .sum();
                    assert!(
                        (gpu - field.node_value(n, t)).abs() < 1e-12,
                        "k {k}, node {n}, texel {t}"
                    );
                }
            }
        }
    }
}

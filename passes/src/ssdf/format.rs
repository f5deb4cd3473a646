//! The SSDF field file format (`.inlayssdf`), version 2: an object's
//! visibility, independent of any scene or radiance field. All numbers are
//! little-endian:
//!
//! | offset | size | content |
//! | --- | --- | --- |
//! | 0 | 8 | magic `INLAYSDF` |
//! | 8 | 4 | format version, u32 = 2 |
//! | 12 | 4 | grid nodes per axis n, u32, 2..=64 |
//! | 16 | 4 | direction map side m, u32, 4..=128 (octahedral, m² texels) |
//! | 20 | 4 | PCA components k, u32, 1..=min(64, m², n³) |
//! | 24 | 12 | grid centre x, y, z (object space), f32 each |
//! | 36 | 4 | bounding-sphere radius r, f32 > 0 (the grid's side is 3r) |
//! | 40 | 8 | the object's geometry key, u64 (`ObjectMesh::geometry_key` of the mesh baked) |
//! | 48 | 4(k+1)·m² | per texel (row-major, see the probe's octahedral map): mean S, then the k basis values |
//! | … | 4k·n³ | per node (x fastest): k coefficients |
//!
//! S is in radians. Loading checks every field, rejects NaN/Inf and
//! trailing or missing bytes, and names the first bad one; whoever uses a
//! loaded field for an object checks its key against the object's
//! ([`check_ssdf_object`]).

use std::path::{Path, PathBuf};

use glam::DVec3;

use super::bake::{MAX_SSDF_COMPONENTS, MAX_SSDF_DIRECTIONS, MAX_SSDF_GRID};
use super::field::SsdfField;
use super::grid::SsdfGrid;

/// The file's first eight bytes.
pub const SSDF_MAGIC: &[u8; 8] = b"INLAYSDF";
/// The version this build reads and writes.
pub const SSDF_VERSION: u32 = 2;
const HEADER_BYTES: usize = 48;

/// Why an SSDF file could not be read or written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {field}: {message}")]
pub struct SsdfFormatError {
    /// The file.
    pub path: PathBuf,
    /// The header field or value the problem is in.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

fn err(path: &Path, field: &str, message: impl Into<String>) -> SsdfFormatError {
    SsdfFormatError {
        path: path.to_owned(),
        field: field.to_owned(),
        message: message.into(),
    }
}

/// The field as file bytes.
pub fn ssdf_bytes(field: &SsdfField) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_BYTES + field.compressed_bytes() as usize);
    out.extend_from_slice(SSDF_MAGIC);
    for v in [
        SSDF_VERSION,
        field.grid.nodes,
        field.directions,
        field.components,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let c = field.grid.centre;
    for v in [c.x, c.y, c.z, field.grid.radius] {
        out.extend_from_slice(&(v as f32).to_le_bytes());
    }
    out.extend_from_slice(&field.object.to_le_bytes());
    for v in field.texel_rows.iter().chain(&field.coefficients) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// Writes `field` to `path` (through a temporary file renamed into place).
pub fn save_ssdf(field: &SsdfField, path: &Path) -> Result<(), SsdfFormatError> {
    inlay_engine::output::write_atomically(path, &ssdf_bytes(field))
        .map_err(|e| err(path, "file", e.detail()))
}

/// Reads and checks an SSDF file.
pub fn load_ssdf(path: &Path) -> Result<SsdfField, SsdfFormatError> {
    let bytes = std::fs::read(path).map_err(|e| err(path, "file", e.to_string()))?;
    parse_ssdf(&bytes, path)
}

/// Checks and decodes file bytes (`path` names them in errors).
pub fn parse_ssdf(bytes: &[u8], path: &Path) -> Result<SsdfField, SsdfFormatError> {
    if bytes.len() < HEADER_BYTES {
        return Err(err(
            path,
            "header",
            format!("{} bytes; the header alone is {HEADER_BYTES}", bytes.len()),
        ));
    }
    if &bytes[0..8] != SSDF_MAGIC {
        return Err(err(
            path,
            "magic",
            "not an SSDF field file (expected INLAYSDF)",
        ));
    }
    let u = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let f = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let version = u(8);
    if version != SSDF_VERSION {
        return Err(err(
            path,
            "version",
            format!("{version}; this build reads version {SSDF_VERSION} (bake it again with `inlay bake-ssdf`)"),
        ));
    }
    let (nodes, directions, components) = (u(12), u(16), u(20));
    if !(2..=MAX_SSDF_GRID).contains(&nodes) {
        return Err(err(
            path,
            "grid",
            format!("{nodes} nodes per axis is not in 2..={MAX_SSDF_GRID}"),
        ));
    }
    if !(4..=MAX_SSDF_DIRECTIONS).contains(&directions) {
        return Err(err(
            path,
            "directions",
            format!("{directions} is not in 4..={MAX_SSDF_DIRECTIONS}"),
        ));
    }
    let texels = (directions * directions) as usize;
    let count = (nodes as usize).pow(3);
    let most = (MAX_SSDF_COMPONENTS as usize).min(texels).min(count);
    if !(1..=most).contains(&(components as usize)) {
        return Err(err(
            path,
            "components",
            format!("{components} is not in 1..={most}"),
        ));
    }
    let centre = [f(24), f(28), f(32)];
    let radius = f(36);
    for (i, c) in centre.iter().enumerate() {
        if !c.is_finite() {
            return Err(err(
                path,
                &format!("centre[{i}]"),
                format!("{c} is not finite"),
            ));
        }
    }
    if !(radius.is_finite() && radius > 0.0) {
        return Err(err(
            path,
            "radius",
            format!("{radius} is not a finite positive number"),
        ));
    }
    let object = u64::from_le_bytes(bytes[40..48].try_into().expect("8 bytes"));
    let k = components as usize;
    let rows = texels * (k + 1);
    let coefs = count * k;
    let expected = HEADER_BYTES + 4 * (rows + coefs);
    if bytes.len() != expected {
        return Err(err(
            path,
            "data",
            format!("{} bytes; a {nodes}³ grid with {directions}² directions and {k} components takes {expected}", bytes.len()),
        ));
    }
    let values: Vec<f32> = (0..rows + coefs).map(|i| f(HEADER_BYTES + 4 * i)).collect();
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        let field = if i < rows {
            format!("texel {} value {}", i / (k + 1), i % (k + 1))
        } else {
            format!("node {} coefficient {}", (i - rows) / k, (i - rows) % k)
        };
        return Err(err(path, &field, format!("{} is not finite", values[i])));
    }
    let coefficients = values[rows..].to_vec();
    let mut texel_rows = values;
    texel_rows.truncate(rows);
    Ok(SsdfField {
        grid: SsdfGrid {
            centre: DVec3::new(centre[0] as f64, centre[1] as f64, centre[2] as f64),
            radius: radius as f64,
            nodes,
        },
        directions,
        components,
        texel_rows,
        coefficients,
        object,
    })
}

/// Fails unless `field` (read from `path`) was baked from `mesh`, naming
/// the file and what to do.
pub fn check_ssdf_object(
    field: &SsdfField,
    path: &Path,
    mesh: &crate::object::ObjectMesh,
) -> Result<(), SsdfFormatError> {
    if field.object == mesh.geometry_key() {
        return Ok(());
    }
    Err(err(
        path,
        "object",
        format!(
            "baked from another mesh than {} (key {:016x}, the object's is {:016x}): \
             bake it again with `inlay bake-ssdf`",
            mesh.name,
            field.object,
            mesh.geometry_key()
        ),
    ))
}

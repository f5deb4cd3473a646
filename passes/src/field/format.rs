//! The grid-field file format (`.inlayfield`), version 1. All numbers are
//! little-endian:
//!
//! | offset | size | content |
//! | --- | --- | --- |
//! | 0 | 8 | magic `INLAYFLD` |
//! | 8 | 4 | format version, u32 = 1 |
//! | 12 | 4 | colour model, u32: 0 = view-independent linear RGB; 1 or 2 = view-dependent, spherical harmonics of that degree |
//! | 16 | 12 | nodes per axis x, y, z, u32 each, 2..=1024 |
//! | 28 | 24 | bounds: min x, y, z then max x, y, z, f32 each |
//! | 52 | 4 | flags, u32, must be 0 |
//! | 56 | 16·N | N = x·y·z nodes, x fastest: r, g, b, σ as f32 |
//! | 56 + 16·N | 12·K·N | colour models 1 and 2: K = 3 or 8 further coefficients per node, node-major, r, g, b as f32 each |
//!
//! Colours are linear HDR radiance (finite, ≥ 0); with view-dependent
//! colour the node's r, g, b are its mean over directions and the further
//! coefficients (finite, of magnitude within the radiance limit) weigh
//! the real spherical harmonics of bands 1 and 2 (`super::sh`). σ is
//! density per unit length (finite, ≥ 0). Node (0,0,0) lies at `min`, the
//! last at `max`.
//! Loading checks every field and names the first bad one.

use std::path::{Path, PathBuf};

use glam::{DVec3, UVec3};

use super::grid::GridField;
use super::occupancy::DEFAULT_OCCUPANCY_BLOCK;
use super::sh::{sh_extra_coefficients, MAX_SH_DEGREE};
use crate::geometry::Aabb;

/// The file's first eight bytes.
pub const FIELD_MAGIC: &[u8; 8] = b"INLAYFLD";
/// The version this build reads and writes.
pub const FIELD_VERSION: u32 = 1;
const HEADER_BYTES: usize = 56;
const MAX_NODES_PER_AXIS: u32 = 1024;

/// Why a field file could not be read or written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {field}: {message}")]
pub struct FieldFormatError {
    /// The file.
    pub path: PathBuf,
    /// The header field or node the problem is in.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

fn err(path: &Path, field: &str, message: impl Into<String>) -> FieldFormatError {
    FieldFormatError {
        path: path.to_owned(),
        field: field.to_owned(),
        message: message.into(),
    }
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
}

fn f32_at(bytes: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
}

/// What a field file's header says, read without its nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldHeader {
    /// Nodes per axis.
    pub resolution: UVec3,
    /// The grid's bounds.
    pub bounds: Aabb,
    /// Degree of the view-dependent colour (the colour model; 0: none).
    pub sh_degree: u32,
}

impl FieldHeader {
    /// Bytes of the node data after the header: the nodes and the
    /// view-dependent colour's coefficients.
    pub fn node_bytes(&self) -> u64 {
        let n = self.resolution.as_u64vec3().element_product();
        16 * n + 12 * sh_extra_coefficients(self.sh_degree) as u64 * n
    }
}

/// Reads and checks a field file's header, and that the file's size
/// matches it, without reading the nodes: a caller can refuse a field too
/// large for its device before spending memory and time on it.
pub fn read_field_header(path: &Path) -> Result<FieldHeader, FieldFormatError> {
    use std::io::Read as _;
    let mut file = std::fs::File::open(path).map_err(|e| err(path, "file", e.to_string()))?;
    let len = file
        .metadata()
        .map_err(|e| err(path, "file", e.to_string()))?
        .len();
    let mut head = Vec::with_capacity(HEADER_BYTES);
    file.by_ref()
        .take(HEADER_BYTES as u64)
        .read_to_end(&mut head)
        .map_err(|e| err(path, "file", e.to_string()))?;
    parse_header(path, &head, len)
}

/// Reads a grid field from `path`; the file's size is checked against its
/// header before the nodes are read.
pub fn load_field(path: &Path) -> Result<GridField, FieldFormatError> {
    read_field_header(path)?;
    let bytes = std::fs::read(path).map_err(|e| err(path, "file", e.to_string()))?;
    parse_field(path, &bytes)
}

/// Checks the header at the start of `bytes` (at least its 56 bytes, or
/// the whole file when shorter) against a file of `len` bytes.
fn parse_header(path: &Path, bytes: &[u8], len: u64) -> Result<FieldHeader, FieldFormatError> {
    if bytes.len() < 8 || &bytes[..8] != FIELD_MAGIC {
        return Err(err(
            path,
            "magic",
            "not an inlay field file (expected the bytes `INLAYFLD` at the start)",
        ));
    }
    if bytes.len() < HEADER_BYTES {
        return Err(err(
            path,
            "header",
            format!("truncated: {len} bytes, the header needs {HEADER_BYTES}"),
        ));
    }
    let version = u32_at(bytes, 8);
    if version != FIELD_VERSION {
        return Err(err(
            path,
            "version",
            format!(
                "version {version} is not supported (this build reads version {FIELD_VERSION})"
            ),
        ));
    }
    let model = u32_at(bytes, 12);
    if model > MAX_SH_DEGREE {
        return Err(err(
            path,
            "colour model",
            format!(
                "unknown colour model {model} (0 = view-independent RGB, 1..={MAX_SH_DEGREE} = \
                 spherical harmonics of that degree)"
            ),
        ));
    }
    let res = UVec3::new(u32_at(bytes, 16), u32_at(bytes, 20), u32_at(bytes, 24));
    for (axis, n) in ["x", "y", "z"].iter().zip(res.to_array()) {
        if !(2..=MAX_NODES_PER_AXIS).contains(&n) {
            return Err(err(
                path,
                &format!("resolution.{axis}"),
                format!("{n} nodes; must be 2..={MAX_NODES_PER_AXIS}"),
            ));
        }
    }
    let min = DVec3::new(
        f32_at(bytes, 28) as f64,
        f32_at(bytes, 32) as f64,
        f32_at(bytes, 36) as f64,
    );
    let max = DVec3::new(
        f32_at(bytes, 40) as f64,
        f32_at(bytes, 44) as f64,
        f32_at(bytes, 48) as f64,
    );
    let bounds = Aabb::new(min, max);
    if !bounds.is_valid() {
        return Err(err(
            path,
            "bounds",
            format!("min {min} max {max}: must be finite with min < max on every axis"),
        ));
    }
    let flags = u32_at(bytes, 52);
    if flags != 0 {
        return Err(err(path, "flags", format!("{flags:#x}; must be 0")));
    }
    let header = FieldHeader {
        resolution: res,
        bounds,
        sh_degree: model,
    };
    let expected = HEADER_BYTES as u64 + header.node_bytes();
    if len != expected {
        return Err(err(
            path,
            "nodes",
            format!(
                "{} bytes of node data for {}x{}x{} nodes, expected {} ({})",
                len - HEADER_BYTES as u64,
                res.x,
                res.y,
                res.z,
                header.node_bytes(),
                if len < expected {
                    "truncated"
                } else {
                    "trailing bytes"
                }
            ),
        ));
    }
    Ok(header)
}

/// Parses the bytes of a field file (`path` is only used in messages).
pub fn parse_field(path: &Path, bytes: &[u8]) -> Result<GridField, FieldFormatError> {
    let header = parse_header(path, bytes, bytes.len() as u64)?;
    let res = header.resolution;
    let count = (res.x as usize) * (res.y as usize) * (res.z as usize);
    let mut nodes = Vec::with_capacity(count);
    let node_end = HEADER_BYTES + 16 * count;
    let node_name = |n: usize| {
        let n = n as u32;
        (n % res.x, (n / res.x) % res.y, n / (res.x * res.y))
    };
    for (n, chunk) in bytes[HEADER_BYTES..node_end].chunks_exact(16).enumerate() {
        let v: [f32; 4] = std::array::from_fn(|c| f32_at(chunk, 4 * c));
        for (c, name) in ["r", "g", "b", "density"].iter().enumerate() {
            let too_bright = c < 3 && v[c] as f64 > crate::scene::RADIANCE_LIMIT;
            if !v[c].is_finite() || v[c] < 0.0 || too_bright {
                let (i, j, k) = node_name(n);
                return Err(err(
                    path,
                    &format!("node ({i}, {j}, {k}).{name}"),
                    if too_bright {
                        format!(
                            "{} is above the radiance limit {:e}",
                            v[c],
                            crate::scene::RADIANCE_LIMIT
                        )
                    } else {
                        format!("{} is not a finite, non-negative number", v[c])
                    },
                ));
            }
        }
        nodes.push(v);
    }
    let per_node = sh_extra_coefficients(header.sh_degree);
    let mut sh = Vec::with_capacity(count * per_node);
    for (at, chunk) in bytes[node_end..].chunks_exact(12).enumerate() {
        let v: [f32; 3] = std::array::from_fn(|c| f32_at(chunk, 4 * c));
        if let Some(c) = (0..3)
            .find(|&c| !(v[c].is_finite() && v[c].abs() as f64 <= crate::scene::RADIANCE_LIMIT))
        {
            let (i, j, k) = node_name(at / per_node);
            return Err(err(
                path,
                &format!(
                    "node ({i}, {j}, {k}).sh[{}].{}",
                    at % per_node + 1,
                    ["r", "g", "b"][c]
                ),
                format!(
                    "{} is not a finite number within the radiance limit {:e}",
                    v[c],
                    crate::scene::RADIANCE_LIMIT
                ),
            ));
        }
        sh.push(v);
    }
    Ok(
        GridField::new(res, header.bounds, nodes, DEFAULT_OCCUPANCY_BLOCK)
            .with_sh(header.sh_degree, sh),
    )
}

/// The bytes of `field` in the file format.
pub fn field_bytes(field: &GridField) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_BYTES + 16 * field.nodes.len() + 12 * field.sh.len());
    out.extend_from_slice(FIELD_MAGIC);
    out.extend_from_slice(&FIELD_VERSION.to_le_bytes());
    out.extend_from_slice(&field.sh_degree.to_le_bytes());
    for v in field.resolution.to_array() {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in field
        .bounds
        .min
        .to_array()
        .into_iter()
        .chain(field.bounds.max.to_array())
    {
        out.extend_from_slice(&(v as f32).to_le_bytes());
    }
    out.extend_from_slice(&0u32.to_le_bytes());
    for n in &field.nodes {
        for c in n {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for n in &field.sh {
        for c in n {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    out
}

/// Writes `field` to `path` (through a temporary file renamed into place).
pub fn save_field(path: &Path, field: &GridField) -> Result<(), FieldFormatError> {
    inlay_engine::output::write_atomically(path, &field_bytes(field))
        .map_err(|e| err(path, "file", e.detail()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> GridField {
        let nodes = (0..8)
            .map(|i| [i as f32, 1.0, 2.0, 0.5 * i as f32])
            .collect();
        GridField::new(
            UVec3::splat(2),
            Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
            nodes,
            8,
        )
    }

    fn parse(bytes: &[u8]) -> Result<GridField, FieldFormatError> {
        parse_field(Path::new("t.inlayfield"), bytes)
    }

    #[test]
    fn round_trips() {
        let f = small();
        let g = parse(&field_bytes(&f)).unwrap();
        assert_eq!(g.nodes, f.nodes);
        assert_eq!(g.resolution, f.resolution);
        assert_eq!(g.bounds, f.bounds);
        assert_eq!(g.sh_degree, 0);
    }

    /// View-dependent colour of each degree round-trips; a bad coefficient
    /// is named by node, coefficient and channel; an unknown colour model
    /// is refused.
    #[test]
    fn view_dependent_colour_round_trips_and_is_checked() {
        for degree in 1..=MAX_SH_DEGREE {
            let k = sh_extra_coefficients(degree);
            let sh: Vec<[f32; 3]> = (0..8 * k)
                .map(|i| [i as f32 * 0.1, -(i as f32), 0.5])
                .collect();
            let f = small().with_sh(degree, sh.clone());
            let bytes = field_bytes(&f);
            assert_eq!(bytes.len(), HEADER_BYTES + 16 * 8 + 12 * 8 * k);
            let g = parse(&bytes).unwrap();
            assert_eq!((g.sh_degree, &g.sh), (degree, &sh));
            let mut bad = bytes.clone();
            let at = HEADER_BYTES + 16 * 8 + 12 * (k + 1) + 4;
            bad[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
            let e = parse(&bad).unwrap_err().to_string();
            assert!(e.contains("node (1, 0, 0).sh[2].g"), "{e}");
            let e = parse(&bytes[..bytes.len() - 12]).unwrap_err().to_string();
            assert!(e.contains("truncated"), "{e}");
        }
        let mut b = field_bytes(&small());
        b[12] = 3;
        let e = parse(&b).unwrap_err().to_string();
        assert!(
            e.contains("colour model") && e.contains("unknown colour model 3"),
            "{e}"
        );
    }

    #[test]
    fn rejects_bad_files_naming_the_field() {
        let good = field_bytes(&small());
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (b"NOTAFILE".to_vec(), "magic"),
            (good[..30].to_vec(), "header"),
            (good[..good.len() - 3].to_vec(), "truncated"),
            ([good.clone(), vec![0; 4]].concat(), "trailing"),
            (
                {
                    let mut b = good.clone();
                    b[8] = 2;
                    b
                },
                "version 2",
            ),
            (
                {
                    let mut b = good.clone();
                    b[16..20].copy_from_slice(&1u32.to_le_bytes());
                    b
                },
                "resolution.x",
            ),
            (
                {
                    let mut b = good.clone();
                    b[40..44].copy_from_slice(&(-5.0f32).to_le_bytes());
                    b
                },
                "bounds",
            ),
            (
                {
                    let mut b = good.clone();
                    let at = HEADER_BYTES + 16 * 3 + 12;
                    b[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
                    b
                },
                "node (1, 1, 0).density",
            ),
            (
                {
                    let mut b = good.clone();
                    let at = HEADER_BYTES + 16 * 7 + 12;
                    b[at..at + 4].copy_from_slice(&(-1.0f32).to_le_bytes());
                    b
                },
                "node (1, 1, 1).density",
            ),
            (
                {
                    let mut b = good.clone();
                    let at = HEADER_BYTES + 4;
                    b[at..at + 4].copy_from_slice(&f32::INFINITY.to_le_bytes());
                    b
                },
                "node (0, 0, 0).g",
            ),
        ];
        for (bytes, expect) in cases {
            let e = parse(&bytes).expect_err(expect).to_string();
            assert!(e.contains(expect), "`{e}` should mention `{expect}`");
            assert!(e.starts_with("t.inlayfield: "), "{e}");
        }
    }
}

#[cfg(test)]
mod radiance_tests {
    use super::*;
    use crate::geometry::Aabb;
    use glam::{DVec3, UVec3};

    /// A colour above the radiance limit is refused with the node and
    /// channel; a density that large is fine (it is not radiance).
    #[test]
    fn colours_above_the_radiance_limit_are_refused() {
        let field = |node: [f32; 4]| {
            let mut nodes = vec![[0.5, 0.5, 0.5, 1.0]; 8];
            nodes[3] = node;
            GridField::new(
                UVec3::splat(2),
                Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
                nodes,
                8,
            )
        };
        let path = Path::new("t.inlayfield");
        let e = parse_field(path, &field_bytes(&field([1.0, 1e20, 1.0, 1.0])))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("node (1, 1, 0).g") && e.contains("radiance limit"),
            "{e}"
        );
        assert!(parse_field(path, &field_bytes(&field([1.0, 1.0, 1.0, 1e20]))).is_ok());
        assert!(parse_field(path, &field_bytes(&field([1e6, 1.0, 1.0, 1.0]))).is_ok());
    }
}

//! The grid-field file format (`.inlayfield`), version 2; version-1 files
//! still load. All numbers are little-endian:
//!
//! | offset | size | content |
//! | --- | --- | --- |
//! | 0 | 8 | magic `INLAYFLD` |
//! | 8 | 4 | format version, u32: 1 or 2 |
//! | 12 | 4 | colour model, u32: 0 = view-independent linear RGB; 1 or 2 = view-dependent, spherical harmonics of that degree |
//! | 16 | 12 | nodes per axis x, y, z, u32 each, 2..=1024 |
//! | 28 | 24 | bounds: min x, y, z then max x, y, z, f32 each |
//! | 52 | 4 | flags, u32: version 1 must be 0; version 2 bit 0 = sparse, the others 0 |
//! | 56 | 4 | version 2 only: bricks kept B, u32 (0 unless sparse) |
//! | 60 | 4 | version 2 only: the coefficients' unscale, f32, a power of two ≥ 1 (1 at colour model 0) |
//!
//! Version 2, after its 64-byte header, with K = 0, 3 or 8 further
//! coefficients a node (colour models 0, 1, 2):
//!
//! - sparse only: the brick table, one u32 per brick of 8³ nodes
//!   (`super::bricks`; ⌈n/8⌉ bricks along an axis of n nodes, x fastest):
//!   the brick's slot, or 0xFFFFFFFF where every node of it is zero; the
//!   kept bricks' slots are 0, 1, 2, … in table order;
//! - the nodes, P of them (P = 512·B sparse, x·y·z dense): r, g, b, σ as
//!   f32 each; sparse, the pool's order (slot by slot, each brick's nodes
//!   x fastest; a brick reaching past the grid's far faces keeps its full
//!   size, and its nodes past the grid are not read);
//! - the further coefficients, K per node in the nodes' order, r, g, b as
//!   f16 each, to be multiplied by the unscale (`super::sh_half`).
//!
//! Version 1, after its 56-byte header: x·y·z nodes as r, g, b, σ f32,
//! then K·x·y·z coefficients as r, g, b f32, dense.
//!
//! Colours are linear HDR radiance (finite, ≥ 0, within the radiance
//! limit); with view-dependent colour the node's r, g, b are its mean over
//! directions and the further coefficients (finite, of magnitude within
//! the radiance limit) weigh the real spherical harmonics of bands 1 and
//! 2 (`super::sh`). σ is density per unit length (finite); a node's σ may
//! be negative, the density at a point being the trilinear value clamped
//! at zero (`super::density_at`: a trained surface crosses a cell where
//! that value crosses zero). Node
//! (0,0,0) lies at `min`, the last at `max`. Loading checks every field
//! and names the first bad one. Saving writes version 2, sparse when a
//! brick can be left out.

use std::path::{Path, PathBuf};

use glam::{DVec3, UVec3};

use super::bricks::{BrickLayout, BRICK_NODES, EMPTY_BRICK};
use super::grid::GridField;
use super::occupancy::DEFAULT_OCCUPANCY_BLOCK;
use super::sh::{sh_extra_coefficients, MAX_SH_DEGREE};
use super::sh_half::{sh_from_half_bytes, sh_half_bytes, sh_unscale, SH_HALF_BYTES};
use crate::geometry::Aabb;

/// The file's first eight bytes.
pub const FIELD_MAGIC: &[u8; 8] = b"INLAYFLD";
/// The version this build writes (it reads this one and version 1).
pub const FIELD_VERSION: u32 = 2;
const HEADER_BYTES_V1: usize = 56;
const HEADER_BYTES: usize = 64;
const MAX_NODES_PER_AXIS: u32 = 1024;
const FLAG_SPARSE: u32 = 1;

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
    /// The format version (1 or 2).
    pub version: u32,
    /// Nodes per axis.
    pub resolution: UVec3,
    /// The grid's bounds.
    pub bounds: Aabb,
    /// Degree of the view-dependent colour (the colour model; 0: none).
    pub sh_degree: u32,
    /// Bricks kept when the file is sparse (None: dense).
    pub bricks: Option<u32>,
    /// What the stored coefficients are multiplied by (version 2).
    pub sh_unscale: f32,
}

impl FieldHeader {
    /// Nodes the file stores: the kept bricks' when sparse, else all.
    pub fn stored_nodes(&self) -> u64 {
        match self.bricks {
            Some(b) => b as u64 * BRICK_NODES as u64,
            None => self.resolution.as_u64vec3().element_product(),
        }
    }

    /// Entries of the brick table (sparse files).
    fn table_entries(&self) -> u64 {
        BrickLayout::dims_of(self.resolution)
            .as_u64vec3()
            .element_product()
    }

    /// Bytes of the header.
    fn header_bytes(&self) -> usize {
        if self.version == 1 {
            HEADER_BYTES_V1
        } else {
            HEADER_BYTES
        }
    }

    /// Bytes of the data after the header: the brick table, the nodes and
    /// the view-dependent colour's coefficients.
    pub fn node_bytes(&self) -> u64 {
        let n = self.stored_nodes();
        let k = sh_extra_coefficients(self.sh_degree) as u64;
        let per_coefficient = if self.version == 1 { 12 } else { SH_HALF_BYTES };
        let table = if self.bricks.is_some() {
            4 * self.table_entries()
        } else {
            0
        };
        table + 16 * n + per_coefficient * k * n
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

/// Checks the header at the start of `bytes` (at least its 64 bytes, or
/// the whole file when shorter) against a file of `len` bytes.
fn parse_header(path: &Path, bytes: &[u8], len: u64) -> Result<FieldHeader, FieldFormatError> {
    if bytes.len() < 8 || &bytes[..8] != FIELD_MAGIC {
        return Err(err(
            path,
            "magic",
            "not an inlay field file (expected the bytes `INLAYFLD` at the start)",
        ));
    }
    let truncated = |needs: usize| {
        err(
            path,
            "header",
            format!("truncated: {len} bytes, the header needs {needs}"),
        )
    };
    if bytes.len() < 12 {
        return Err(truncated(HEADER_BYTES));
    }
    let version = u32_at(bytes, 8);
    if !(1..=FIELD_VERSION).contains(&version) {
        return Err(err(
            path,
            "version",
            format!(
                "version {version} is not supported (this build reads versions 1 to {FIELD_VERSION})"
            ),
        ));
    }
    let header_bytes = if version == 1 {
        HEADER_BYTES_V1
    } else {
        HEADER_BYTES
    };
    if bytes.len() < header_bytes {
        return Err(truncated(header_bytes));
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
    let known = if version == 1 { 0 } else { FLAG_SPARSE };
    if flags & !known != 0 {
        return Err(err(
            path,
            "flags",
            format!("{flags:#x}; version {version} knows only {known:#x}"),
        ));
    }
    let mut header = FieldHeader {
        version,
        resolution: res,
        bounds,
        sh_degree: model,
        bricks: None,
        sh_unscale: 1.0,
    };
    if version >= 2 {
        let kept = u32_at(bytes, 56);
        if flags & FLAG_SPARSE != 0 {
            if kept as u64 > header.table_entries() {
                return Err(err(
                    path,
                    "bricks",
                    format!(
                        "{kept} kept, but the grid has {} bricks",
                        header.table_entries()
                    ),
                ));
            }
            header.bricks = Some(kept);
        } else if kept != 0 {
            return Err(err(path, "bricks", format!("{kept}; a dense file has 0")));
        }
        let unscale = f32_at(bytes, 60);
        let power_of_two = unscale.is_finite() && unscale >= 1.0 && unscale.log2().fract() == 0.0;
        if !power_of_two || (model == 0 && unscale != 1.0) {
            return Err(err(
                path,
                "unscale",
                format!(
                    "{unscale}; must be a power of two at least 1 (1 without view-dependent colour)"
                ),
            ));
        }
        header.sh_unscale = unscale;
    }
    let expected = header_bytes as u64 + header.node_bytes();
    if len != expected {
        return Err(err(
            path,
            "nodes",
            format!(
                "{} bytes of data for {}x{}x{} nodes{}, expected {} ({})",
                len.saturating_sub(header_bytes as u64),
                res.x,
                res.y,
                res.z,
                header
                    .bricks
                    .map_or(String::new(), |b| format!(" in {b} bricks")),
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
    let mut at = header.header_bytes();
    let layout = match header.bricks {
        Some(kept) => {
            let layout = parse_table(path, &header, &bytes[at..], kept)?;
            at += 4 * layout.table.len();
            Some(layout)
        }
        None => None,
    };
    let stored = header.stored_nodes() as usize;
    let k = sh_extra_coefficients(header.sh_degree);
    let node_bytes = &bytes[at..at + 16 * stored];
    let sh_bytes = &bytes[at + 16 * stored..];
    let stored_sh = if header.version == 1 {
        sh_bytes
            .chunks_exact(12)
            .map(|c| std::array::from_fn(|i| f32_at(c, 4 * i)))
            .collect()
    } else {
        sh_from_half_bytes(sh_bytes, header.sh_unscale)
    };
    let count = (res.x as usize) * (res.y as usize) * (res.z as usize);
    let mut nodes = vec![[0.0f32; 4]; count];
    let mut sh = vec![[0.0f32; 3]; count * k];
    for z in 0..res.z {
        for y in 0..res.y {
            for x in 0..res.x {
                let i = UVec3::new(x, y, z);
                let from = match &layout {
                    Some(l) => match l.pool_index(i) {
                        Some(p) => p as usize,
                        None => continue,
                    },
                    None => (x + res.x * (y + res.y * z)) as usize,
                };
                let n = (x + res.x * (y + res.y * z)) as usize;
                let v: [f32; 4] = std::array::from_fn(|c| f32_at(&node_bytes[16 * from..], 4 * c));
                check_node(path, i, &v)?;
                nodes[n] = v;
                for j in 0..k {
                    let c = stored_sh[from * k + j];
                    check_coefficient(path, i, j, &c)?;
                    sh[n * k + j] = c;
                }
            }
        }
    }
    Ok(
        GridField::new(res, header.bounds, nodes, DEFAULT_OCCUPANCY_BLOCK)
            .with_sh(header.sh_degree, sh),
    )
}

/// The brick table at the start of `bytes`, checked: each entry a slot or
/// empty, the `kept` slots 0, 1, 2, … in order.
fn parse_table(
    path: &Path,
    header: &FieldHeader,
    bytes: &[u8],
    kept: u32,
) -> Result<BrickLayout, FieldFormatError> {
    let dims = BrickLayout::dims_of(header.resolution);
    let mut keep = Vec::with_capacity(header.table_entries() as usize);
    let mut next = 0u32;
    for (t, chunk) in bytes[..4 * header.table_entries() as usize]
        .chunks_exact(4)
        .enumerate()
    {
        let slot = u32_at(chunk, 0);
        if slot != EMPTY_BRICK && slot != next {
            let t = t as u32;
            let b = (t % dims.x, (t / dims.x) % dims.y, t / (dims.x * dims.y));
            return Err(err(
                path,
                &format!("brick table ({}, {}, {})", b.0, b.1, b.2),
                format!("slot {slot}; the kept bricks' slots run 0, 1, 2, … in table order, so {next} was expected"),
            ));
        }
        next += (slot != EMPTY_BRICK) as u32;
        keep.push(slot != EMPTY_BRICK);
    }
    if next != kept {
        return Err(err(
            path,
            "brick table",
            format!("{next} bricks kept, the header says {kept}"),
        ));
    }
    Ok(BrickLayout::from_kept(header.resolution, &keep))
}

/// Fails, naming the first node and channel [`load_field`] would refuse,
/// unless every node and coefficient of `field` is one it reads: a field is
/// never written that no command can load.
fn check_values(path: &Path, field: &GridField) -> Result<(), FieldFormatError> {
    let r = field.resolution;
    let per_node = field.sh_count();
    for (n, v) in field.nodes.iter().enumerate() {
        let n32 = n as u32;
        let i = UVec3::new(n32 % r.x, (n32 / r.x) % r.y, n32 / (r.x * r.y));
        check_node(path, i, v)?;
        for (j, c) in field.sh[n * per_node..(n + 1) * per_node]
            .iter()
            .enumerate()
        {
            check_coefficient(path, i, j, c)?;
        }
    }
    Ok(())
}

/// Fails, naming node `i` and the channel, unless `v` is a valid node.
fn check_node(path: &Path, i: UVec3, v: &[f32; 4]) -> Result<(), FieldFormatError> {
    for (c, name) in ["r", "g", "b", "density"].iter().enumerate() {
        let too_bright = c < 3 && v[c] as f64 > crate::scene::RADIANCE_LIMIT;
        // A density may be negative (clamped after interpolation:
        // `super::density_at`); a colour may not.
        let negative = c < 3 && v[c] < 0.0;
        if !v[c].is_finite() || negative || too_bright {
            return Err(err(
                path,
                &format!("node ({}, {}, {}).{name}", i.x, i.y, i.z),
                if too_bright {
                    format!(
                        "{} is above the radiance limit {:e}",
                        v[c],
                        crate::scene::RADIANCE_LIMIT
                    )
                } else if c < 3 {
                    format!("{} is not a finite, non-negative number", v[c])
                } else {
                    format!("{} is not a finite number", v[c])
                },
            ));
        }
    }
    Ok(())
}

/// Fails, naming node `i`, coefficient `j` and the channel, unless `c` is
/// finite and within the radiance limit.
fn check_coefficient(
    path: &Path,
    i: UVec3,
    j: usize,
    c: &[f32; 3],
) -> Result<(), FieldFormatError> {
    match (0..3)
        .find(|&ch| !(c[ch].is_finite() && c[ch].abs() as f64 <= crate::scene::RADIANCE_LIMIT))
    {
        None => Ok(()),
        Some(ch) => Err(err(
            path,
            &format!(
                "node ({}, {}, {}).sh[{}].{}",
                i.x,
                i.y,
                i.z,
                j + 1,
                ["r", "g", "b"][ch]
            ),
            format!(
                "{} is not a finite number within the radiance limit {:e}",
                c[ch],
                crate::scene::RADIANCE_LIMIT
            ),
        )),
    }
}

/// The bytes of `field` in the file format (version 2; sparse when a brick
/// can be left out).
pub fn field_bytes(field: &GridField) -> Vec<u8> {
    let layout = BrickLayout::of(field);
    let sparse = (layout.slots as usize) < layout.table.len();
    let (nodes, sh) = if sparse {
        layout.pool_values(field)
    } else {
        (field.nodes.clone(), field.sh.clone())
    };
    let unscale = sh_unscale(&sh);
    let mut out = Vec::with_capacity(HEADER_BYTES + 16 * nodes.len() + 6 * sh.len());
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
    let (flags, kept) = if sparse {
        (FLAG_SPARSE, layout.slots)
    } else {
        (0, 0)
    };
    out.extend_from_slice(&flags.to_le_bytes());
    out.extend_from_slice(&kept.to_le_bytes());
    out.extend_from_slice(&unscale.to_le_bytes());
    if sparse {
        for t in &layout.table {
            out.extend_from_slice(&t.to_le_bytes());
        }
    }
    for v in nodes.iter().flatten() {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&sh_half_bytes(&sh, unscale));
    out
}

/// The bytes of `field` to be written to `path`, or, naming the first node
/// and channel, why [`load_field`] would refuse them: a field no command
/// can load is never written.
pub fn checked_field_bytes(path: &Path, field: &GridField) -> Result<Vec<u8>, FieldFormatError> {
    check_values(path, field)?;
    Ok(field_bytes(field))
}

/// Writes `field` to `path` (through a temporary file renamed into place),
/// refused as [`checked_field_bytes`] refuses it.
pub fn save_field(path: &Path, field: &GridField) -> Result<(), FieldFormatError> {
    inlay_engine::output::write_atomically(path, &checked_field_bytes(path, field)?)
        .map_err(|e| err(path, "file", e.detail()))
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(super) fn small() -> GridField {
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

    /// View-dependent colour of each degree round-trips (as f16, which
    /// the field already holds); a bad coefficient is named by node,
    /// coefficient and channel; an unknown colour model is refused.
    #[test]
    fn view_dependent_colour_round_trips_and_is_checked() {
        for degree in 1..=MAX_SH_DEGREE {
            let k = sh_extra_coefficients(degree);
            let sh: Vec<[f32; 3]> = (0..8 * k)
                .map(|i| [i as f32 * 0.1, -(i as f32), 0.5])
                .collect();
            let f = small().with_sh(degree, sh.clone());
            let bytes = field_bytes(&f);
            assert_eq!(bytes.len(), HEADER_BYTES + 16 * 8 + 6 * 8 * k);
            let g = parse(&bytes).unwrap();
            assert_eq!((g.sh_degree, &g.sh), (degree, &f.sh));
            let mut bad = bytes.clone();
            let at = HEADER_BYTES + 16 * 8 + 6 * (k + 1) + 2;
            bad[at..at + 2].copy_from_slice(&half::f16::NAN.to_le_bytes());
            let e = parse(&bad).unwrap_err().to_string();
            assert!(e.contains("node (1, 0, 0).sh[2].g"), "{e}");
            let e = parse(&bytes[..bytes.len() - 6]).unwrap_err().to_string();
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

    /// A field with empty bricks is written sparse and read back exactly,
    /// in fewer bytes than dense; coefficients past f16's range keep their
    /// scale.
    #[test]
    fn a_sparse_field_round_trips() {
        let res = UVec3::new(20, 11, 9);
        let count = (res.x * res.y * res.z) as usize;
        let mut nodes = vec![[0.0f32; 4]; count];
        let index = |x: u32, y: u32, z: u32| (x + res.x * (y + res.y * z)) as usize;
        nodes[index(13, 4, 2)] = [1.0, 2.0, 3.0, 4.0];
        nodes[index(19, 10, 8)] = [0.5, 0.0, 0.0, 9.0];
        let mut sh = vec![[0.0f32; 3]; count * 3];
        sh[index(13, 4, 2) * 3 + 2] = [1.0e5, -0.25, 3.0e-3];
        let f = GridField::new(res, Aabb::new(DVec3::ZERO, DVec3::ONE), nodes, 4).with_sh(1, sh);
        let bytes = field_bytes(&f);
        assert_eq!(u32_at(&bytes, 52), FLAG_SPARSE);
        assert_eq!(u32_at(&bytes, 56), 2);
        assert_eq!(f32_at(&bytes, 60), 4.0);
        let table = 3 * 2 * 2;
        assert_eq!(bytes.len(), HEADER_BYTES + 4 * table + 2 * 512 * (16 + 18));
        let g = parse(&bytes).unwrap();
        assert_eq!(
            (&g.nodes, &g.sh, g.resolution),
            (&f.nodes, &f.sh, f.resolution)
        );
        let header = parse_header(Path::new("t"), &bytes, bytes.len() as u64).unwrap();
        assert_eq!((header.bricks, header.stored_nodes()), (Some(2), 1024));
    }

    /// A brick table whose slots are out of order, or disagree with the
    /// header's count, is refused by the brick it names.
    #[test]
    fn a_bad_brick_table_is_named() {
        let res = UVec3::new(20, 11, 9);
        let mut nodes = vec![[0.0f32; 4]; (res.x * res.y * res.z) as usize];
        nodes[0] = [1.0; 4];
        nodes[(19 + 20 * 10 + 220 * 8) as usize] = [1.0; 4];
        let f = GridField::new(res, Aabb::new(DVec3::ZERO, DVec3::ONE), nodes, 4);
        let good = field_bytes(&f);
        let mut b = good.clone();
        // The last brick (2, 1, 1) says slot 5.
        let at = HEADER_BYTES + 4 * 11;
        b[at..at + 4].copy_from_slice(&5u32.to_le_bytes());
        let e = parse(&b).unwrap_err().to_string();
        assert!(
            e.contains("brick table (2, 1, 1)") && e.contains("slot 5"),
            "{e}"
        );
        let mut b = good.clone();
        b[at..at + 4].copy_from_slice(&EMPTY_BRICK.to_le_bytes());
        let e = parse(&b).unwrap_err().to_string();
        assert!(e.contains("1 bricks kept, the header says 2"), "{e}");
        let mut b = good.clone();
        b[56..60].copy_from_slice(&13u32.to_le_bytes());
        let e = parse(&b).unwrap_err().to_string();
        assert!(e.contains("bricks: 13 kept, but the grid has 12"), "{e}");
        let mut b = good;
        b[60..64].copy_from_slice(&3.0f32.to_le_bytes());
        let e = parse(&b).unwrap_err().to_string();
        assert!(e.contains("unscale: 3"), "{e}");
    }

    /// Files of version 1 (dense, f32 coefficients, a 56-byte header) still
    /// load, and are checked as before.
    #[test]
    fn version_1_files_still_load() {
        let f = small().with_sh(1, (0..24).map(|i| [i as f32, 0.5, -0.25]).collect());
        let mut v1 = Vec::new();
        v1.extend_from_slice(FIELD_MAGIC);
        v1.extend_from_slice(&1u32.to_le_bytes());
        v1.extend_from_slice(&1u32.to_le_bytes());
        let good = field_bytes(&f);
        v1.extend_from_slice(&good[16..52]);
        v1.extend_from_slice(&0u32.to_le_bytes());
        for v in f.nodes.iter().flatten().chain(f.sh.iter().flatten()) {
            v1.extend_from_slice(&v.to_le_bytes());
        }
        let g = parse(&v1).unwrap();
        assert_eq!((&g.nodes, &g.sh, g.sh_degree), (&f.nodes, &f.sh, 1));
        let mut b = v1.clone();
        b[52] = 1;
        let e = parse(&b).unwrap_err().to_string();
        assert!(
            e.contains("flags") && e.contains("version 1 knows only 0x0"),
            "{e}"
        );
        let e = parse(&v1[..v1.len() - 4]).unwrap_err().to_string();
        assert!(e.contains("truncated"), "{e}");
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
                    b[8] = 3;
                    b
                },
                "version 3",
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
                    b[at..at + 4].copy_from_slice(&f32::NEG_INFINITY.to_le_bytes());
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

    /// A field the loader would refuse is not written, and the file it
    /// would have replaced is left as it was; a valid one is written.
    #[test]
    fn a_field_no_command_could_load_is_not_written() {
        let dir = std::env::temp_dir().join(format!("inlay-save-check-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("f.inlayfield");
        let good = tests::small();
        save_field(&path, &good).unwrap();
        let before = std::fs::read(&path).unwrap();
        let mut bright = tests::small();
        bright.nodes[5][2] = 4.8e6;
        let e = save_field(&path, &bright).unwrap_err().to_string();
        assert!(
            e.contains("node (1, 0, 1).b") && e.contains("radiance limit"),
            "{e}"
        );
        let sh = vec![[0.0, f32::NAN, 0.0]; 8 * 3];
        let e = save_field(&path, &tests::small().with_sh(1, sh))
            .unwrap_err()
            .to_string();
        assert!(e.contains("node (0, 0, 0).sh[1].g"), "{e}");
        assert_eq!(std::fs::read(&path).unwrap(), before);
        assert_eq!(load_field(&path).unwrap().nodes, good.nodes);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

//! Reads glTF 2.0 objects (.gltf with external or embedded buffers, .glb):
//! every triangle primitive of every mesh reachable from the default scene,
//! flattened into object space through the node transforms, with
//! metallic-roughness materials and their textures. What the engine cannot
//! use is an error naming the file and the element: required extensions
//! (Draco, meshopt, KTX2 …), missing buffers or images, non-triangle
//! primitives, texture coordinate sets other than 0.

use std::path::{Path, PathBuf};

use glam::{DMat3, DMat4, DVec3, DVec4};

use super::material::Material;
use super::mesh::{MeshPart, MeshVertex, ObjectMesh};
use super::texture::Texture;

/// Why an object file could not be used.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {field}: {message}")]
pub struct ObjectError {
    /// The file.
    pub path: PathBuf,
    /// The element the problem is in (e.g. `meshes[2].primitives[0]`).
    pub field: String,
    /// What is wrong.
    pub message: String,
}

/// The message for a file the glTF crate panicked on.
fn malformed(panic: Box<dyn std::any::Any + Send>) -> String {
    let why = panic
        .downcast_ref::<String>()
        .map(String::as_str)
        .or_else(|| panic.downcast_ref::<&str>().copied())
        .unwrap_or("no message");
    format!("malformed: the glTF reader failed on it ({why})")
}

/// Opens and validates `path` as glTF, and checks what the crate's own
/// validation lets through but its importer would panic on: an image with
/// neither a URI nor a buffer view, or a buffer view without a MIME type.
fn open_gltf(path: &Path) -> Result<gltf::Gltf, ObjectError> {
    let err = |field: String, message: String| ObjectError {
        path: path.to_owned(),
        field,
        message,
    };
    // Read whole (the file's real size), not through the crate's reader,
    // which allocates whatever length a .glb header claims before reading.
    let bytes = std::fs::read(path).map_err(|e| err("file".into(), e.to_string()))?;
    let gltf = match std::panic::catch_unwind(|| gltf::Gltf::from_slice(&bytes)) {
        Ok(parsed) => parsed.map_err(|e| err("file".into(), e.to_string()))?,
        Err(panic) => return Err(err("file".into(), malformed(panic))),
    };
    for (i, image) in gltf.document.as_json().images.iter().enumerate() {
        let problem = match (&image.uri, &image.buffer_view, &image.mime_type) {
            (None, None, _) => Some("has neither a `uri` nor a `bufferView`"),
            (_, Some(_), None) => Some("has a `bufferView` but no `mimeType`"),
            _ => None,
        };
        if let Some(m) = problem {
            return Err(err(format!("images[{i}]"), m.into()));
        }
    }
    Ok(gltf)
}

/// The files loading `path` reads: the .gltf or .glb itself, then every
/// buffer and image it refers to by a (non-`data:`) URI, in document order.
/// A cache of what is baked from the object hashes all of them.
pub fn gltf_files(path: &Path) -> Result<Vec<PathBuf>, ObjectError> {
    let gltf = open_gltf(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let external = |uri: &str| (!uri.starts_with("data:")).then(|| base.join(uri));
    let buffers = gltf.document.buffers().filter_map(|b| match b.source() {
        gltf::buffer::Source::Uri(uri) => external(uri),
        gltf::buffer::Source::Bin => None,
    });
    let images = gltf.document.images().filter_map(|i| match i.source() {
        gltf::image::Source::Uri { uri, .. } => external(uri),
        gltf::image::Source::View { .. } => None,
    });
    Ok(std::iter::once(path.to_owned())
        .chain(buffers)
        .chain(images)
        .collect())
}

/// Loads a .gltf or .glb file. A file the glTF crate panics on (it does
/// on some malformed ones) is an error naming the file, like any other.
pub fn load_gltf(path: &Path) -> Result<ObjectMesh, ObjectError> {
    std::panic::catch_unwind(|| load_gltf_unguarded(path)).unwrap_or_else(|panic| {
        Err(ObjectError {
            path: path.to_owned(),
            field: "file".into(),
            message: malformed(panic),
        })
    })
}

fn load_gltf_unguarded(path: &Path) -> Result<ObjectMesh, ObjectError> {
    let err = |field: &str, message: String| ObjectError {
        path: path.to_owned(),
        field: field.to_owned(),
        message,
    };
    // The crate's validation refuses required extensions it does not
    // implement (Draco, meshopt, KTX2 …), naming them.
    let gltf = open_gltf(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let gltf::Gltf { document, blob } = gltf;
    let buffers = gltf::import_buffers(&document, Some(base), blob).map_err(|e| {
        err(
            "buffers",
            format!("{e} (a buffer file is missing or unreadable)"),
        )
    })?;
    let images = gltf::import_images(&document, Some(base), &buffers)
        .map_err(|e| err("images", e.to_string()))?;
    let mut textures = Vec::with_capacity(images.len());
    for (i, img) in images.iter().enumerate() {
        textures.push(to_rgba8(img).map_err(|m| err(&format!("images[{i}]"), m))?);
    }
    let texture_of = |info: Option<gltf::texture::Info<'_>>,
                      field: &str|
     -> Result<Option<usize>, ObjectError> {
        let Some(info) = info else { return Ok(None) };
        if info.tex_coord() != 0 {
            return Err(err(
                field,
                format!(
                    "uses TEXCOORD_{}; only TEXCOORD_0 is supported",
                    info.tex_coord()
                ),
            ));
        }
        Ok(Some(info.texture().source().index()))
    };
    let mut materials = Vec::new();
    for (i, m) in document.materials().enumerate() {
        let pbr = m.pbr_metallic_roughness();
        let f = format!("materials[{i}]");
        materials.push(Material {
            name: m.name().map(str::to_owned).unwrap_or_else(|| f.clone()),
            base_colour: DVec4::from_array(pbr.base_color_factor().map(f64::from)),
            roughness: pbr.roughness_factor() as f64,
            metallic: pbr.metallic_factor() as f64,
            base_colour_texture: texture_of(pbr.base_color_texture(), &f)?,
            metallic_roughness_texture: texture_of(pbr.metallic_roughness_texture(), &f)?,
        });
    }
    let default_material = materials.len();
    materials.push(Material::default());

    let mut out = ObjectMesh {
        name: path.display().to_string(),
        vertices: Vec::new(),
        indices: Vec::new(),
        parts: Vec::new(),
        materials,
        textures,
    };
    let roots: Vec<gltf::Node<'_>> = match document.default_scene().or(document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => document.nodes().collect(),
    };
    let mut stack: Vec<(gltf::Node<'_>, DMat4)> =
        roots.into_iter().map(|n| (n, DMat4::IDENTITY)).collect();
    let mut depth_guard = 0usize;
    while let Some((node, parent)) = stack.pop() {
        depth_guard += 1;
        if depth_guard > 1_000_000 {
            return Err(err("nodes", "the node hierarchy has a cycle".into()));
        }
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            add_mesh(&mut out, &mesh, world, &buffers, default_material, &err)?;
        }
        for child in node.children() {
            stack.push((child, world));
        }
    }
    if out.indices.is_empty() {
        return Err(err("meshes", "the default scene holds no triangles".into()));
    }
    if !out.vertices.iter().all(|v| v.position.is_finite()) {
        return Err(err(
            "accessors",
            "vertex positions contain NaN or infinity".into(),
        ));
    }
    Ok(out)
}

fn add_mesh(
    out: &mut ObjectMesh,
    mesh: &gltf::Mesh<'_>,
    world: DMat4,
    buffers: &[gltf::buffer::Data],
    default_material: usize,
    err: &dyn Fn(&str, String) -> ObjectError,
) -> Result<(), ObjectError> {
    let normal_matrix = DMat3::from_mat4(world).inverse().transpose();
    let flip = DMat3::from_mat4(world).determinant() < 0.0;
    for prim in mesh.primitives() {
        let field = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
        if prim.mode() != gltf::mesh::Mode::Triangles {
            return Err(err(
                &field,
                format!("mode {:?}: only triangle lists are supported", prim.mode()),
            ));
        }
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let positions: Vec<[f32; 3]> = reader
            .read_positions()
            .ok_or_else(|| err(&field, "has no POSITION attribute".into()))?
            .collect();
        let normals: Option<Vec<[f32; 3]>> = reader.read_normals().map(|n| n.collect());
        let uvs: Option<Vec<[f32; 2]>> = reader.read_tex_coords(0).map(|t| t.into_f32().collect());
        let mut indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        if indices.len() % 3 != 0 {
            return Err(err(
                &field,
                format!(
                    "{} indices is not a whole number of triangles",
                    indices.len()
                ),
            ));
        }
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(err(
                &field,
                format!("index {bad} is past the {} vertices", positions.len()),
            ));
        }
        if normals.as_ref().is_some_and(|n| n.len() != positions.len())
            || uvs.as_ref().is_some_and(|t| t.len() != positions.len())
        {
            return Err(err(&field, "attribute counts differ".into()));
        }
        if flip {
            for t in indices.chunks_exact_mut(3) {
                t.swap(1, 2);
            }
        }
        let point =
            |i: usize| world.transform_point3(DVec3::from_array(positions[i].map(f64::from)));
        let uv = |i: usize| uvs.as_ref().map_or([0.0; 2], |t| t[i]);
        let first_index = out.indices.len() as u32;
        match &normals {
            Some(ns) => {
                let base = out.vertices.len() as u32;
                for (i, normal) in ns.iter().enumerate() {
                    let n = (normal_matrix * DVec3::from_array(normal.map(f64::from)))
                        .normalize_or(DVec3::Y);
                    out.vertices.push(MeshVertex {
                        position: point(i).as_vec3(),
                        normal: n.as_vec3(),
                        uv: uv(i),
                    });
                }
                out.indices.extend(indices.iter().map(|i| base + i));
            }
            None => {
                // glTF: without normals, shading is flat (one normal per triangle).
                for t in indices.chunks_exact(3) {
                    let p = [0, 1, 2].map(|k| point(t[k] as usize));
                    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or(DVec3::Y);
                    for k in 0..3 {
                        out.indices.push(out.vertices.len() as u32);
                        out.vertices.push(MeshVertex {
                            position: p[k].as_vec3(),
                            normal: n.as_vec3(),
                            uv: uv(t[k] as usize),
                        });
                    }
                }
            }
        }
        let count = out.indices.len() as u32 - first_index;
        if count > 0 {
            out.parts.push(MeshPart {
                first_index,
                index_count: count,
                material: prim.material().index().unwrap_or(default_material),
            });
        }
    }
    Ok(())
}

/// Any 8- or 16-bit glTF image as RGBA8 (grey and grey-alpha spread to
/// RGB, alpha 1 when absent; 16-bit channels keep their high byte).
fn to_rgba8(img: &gltf::image::Data) -> Result<Texture, String> {
    use gltf::image::Format as F;
    let (channels, bytes_per) = match img.format {
        F::R8 => (1, 1),
        F::R8G8 => (2, 1),
        F::R8G8B8 => (3, 1),
        F::R8G8B8A8 => (4, 1),
        F::R16 => (1, 2),
        F::R16G16 => (2, 2),
        F::R16G16B16 => (3, 2),
        F::R16G16B16A16 => (4, 2),
        other => return Err(format!("pixel format {other:?} is not supported")),
    };
    let n = img.width as usize * img.height as usize;
    if img.pixels.len() != n * channels * bytes_per || n == 0 {
        return Err("image data does not match its size".into());
    }
    let mut rgba8 = Vec::with_capacity(n * 4);
    for p in img.pixels.chunks_exact(channels * bytes_per) {
        // High byte of little-endian 16-bit channels.
        let c = |k: usize| p[k * bytes_per + bytes_per - 1];
        let px = match channels {
            1 => [c(0), c(0), c(0), 255],
            2 => [c(0), c(0), c(0), c(1)],
            3 => [c(0), c(1), c(2), 255],
            _ => [c(0), c(1), c(2), c(3)],
        };
        rgba8.extend_from_slice(&px);
    }
    Ok(Texture {
        width: img.width,
        height: img.height,
        rgba8,
    })
}

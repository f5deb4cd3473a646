//! An object's mesh and textures on the GPU: one vertex and one index
//! storage buffer (vertices are pulled in the vertex shader), and each
//! texture uploaded once in the encoding its use needs (sRGB for base
//! colour, linear for metallic-roughness), plus a 1×1 white texture that
//! stands in where a material has none.

use std::collections::HashMap;
use std::sync::Arc;

use inlay_engine::{vk, Buffer, Context, DeviceInfo, Image, ImageDesc};

use super::mesh::{MeshVertex, ObjectMesh};
use super::texture::Texture;

/// A mesh uploaded for drawing.
pub struct GpuObject {
    /// Vertices (32 bytes each, see [`super::MeshVertex::to_bytes`]).
    pub vertices: Arc<Buffer>,
    /// Triangle indices.
    pub indices: Arc<Buffer>,
    textures: HashMap<(usize, bool), Arc<Image>>,
    white: Arc<Image>,
}

/// Fails, naming the object, the limit and what fits, unless `mesh`'s
/// vertex and index buffers each fit one storage binding on `info`'s device.
pub fn check_mesh_fits(info: &DeviceInfo, mesh: &ObjectMesh) -> anyhow::Result<()> {
    let limit = info.max_storage_buffer_range as u64;
    for (what, count, bytes) in [
        (
            "vertices",
            mesh.vertices.len() as u64,
            MeshVertex::BYTES as u64,
        ),
        ("indices", mesh.indices.len() as u64, 4),
    ] {
        anyhow::ensure!(
            count * bytes <= limit,
            "{}: {count} {what} take {} MiB, more than {}'s largest storage binding ({} MiB); \
             simplify the mesh to at most {} {what}",
            mesh.name,
            (count * bytes) >> 20,
            info.name,
            limit >> 20,
            limit / bytes
        );
    }
    Ok(())
}

impl GpuObject {
    /// Uploads `mesh` ([`check_mesh_fits`] first).
    pub fn upload(ctx: &Arc<Context>, mesh: &ObjectMesh) -> anyhow::Result<Self> {
        check_mesh_fits(ctx.info(), mesh)?;
        let vertex_bytes: Vec<u8> = mesh.vertices.iter().flat_map(|v| v.to_bytes()).collect();
        let index_bytes: Vec<u8> = mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let mut textures = HashMap::new();
        for m in &mesh.materials {
            for (t, srgb) in [
                (m.base_colour_texture, true),
                (m.metallic_roughness_texture, false),
            ] {
                if let Some(i) = t {
                    if let (Some(tex), false) =
                        (mesh.textures.get(i), textures.contains_key(&(i, srgb)))
                    {
                        textures.insert(
                            (i, srgb),
                            Arc::new(upload_texture(ctx, &mesh.name, tex, srgb)?),
                        );
                    }
                }
            }
        }
        let white = Texture {
            width: 1,
            height: 1,
            rgba8: vec![255; 4],
        };
        Ok(Self {
            vertices: Arc::new(Buffer::with_data(
                ctx,
                "object vertices",
                &vertex_bytes,
                storage,
            )?),
            indices: Arc::new(Buffer::with_data(
                ctx,
                "object indices",
                &index_bytes,
                storage,
            )?),
            textures,
            white: Arc::new(upload_texture(ctx, "white", &white, false)?),
        })
    }

    /// The image of texture `index` in the given encoding, or the white
    /// texture when there is none.
    pub fn texture(&self, index: Option<usize>, srgb: bool) -> &Arc<Image> {
        index
            .and_then(|i| self.textures.get(&(i, srgb)))
            .unwrap_or(&self.white)
    }
}

fn upload_texture(
    ctx: &Arc<Context>,
    name: &str,
    t: &Texture,
    srgb: bool,
) -> anyhow::Result<Image> {
    let format = if srgb {
        vk::Format::R8G8B8A8_SRGB
    } else {
        vk::Format::R8G8B8A8_UNORM
    };
    let image = Image::new(
        ctx,
        &format!("{name} texture"),
        ImageDesc {
            width: t.width,
            height: t.height,
            format,
        },
        vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
    )?;
    image.write_texels(&t.rgba8)?;
    Ok(image)
}

//! Writing HDR frames: linear EXR (full float) and tonemapped sRGB PNG.

use std::path::Path;

use crate::error::{EngineError, Result};
use crate::tonemap::tonemap_to_srgb8;

/// The most pixels [`HdrImage::load_exr`] reads (2²⁷, a 16384 × 8192
/// equirect map: 2 GiB as float RGBA).
pub const MAX_EXR_PIXELS: u64 = 1 << 27;

/// The file extensions [`HdrImage::save`] writes.
pub const IMAGE_EXTENSIONS: [&str; 2] = ["exr", "png"];

/// A linear HDR RGBA image on the CPU, row-major from the top-left.
#[derive(Debug, Clone, PartialEq)]
pub struct HdrImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` RGBA pixels.
    pub pixels: Vec<[f32; 4]>,
}

impl HdrImage {
    /// The pixel at (x, y).
    pub fn at(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Number of pixels with a NaN or infinite channel.
    pub fn non_finite_count(&self) -> usize {
        self.pixels
            .iter()
            .filter(|p| p.iter().any(|c| !c.is_finite()))
            .count()
    }

    /// Writes the image through a temporary file renamed into place (see
    /// [`crate::output`]); the format follows the extension: `.exr` (linear,
    /// 32-bit float RGBA) or `.png` (tonemapped with `exposure`, sRGB, 8-bit).
    pub fn save(&self, path: &Path, exposure: f32) -> Result<()> {
        crate::output::write_atomically_with(path, |temp| self.write_file(temp, exposure))
    }

    /// Checks before any work that `path` can take an image: a format
    /// [`save`](Self::save) writes, in a directory that takes files.
    pub fn check_output(path: &Path) -> Result<()> {
        crate::output::check_output_path(path, &IMAGE_EXTENSIONS)
    }

    /// Writes the image straight to `path` (no temporary file: for an
    /// [`OutputBatch`](crate::output::OutputBatch) to stage), in the format
    /// [`save`](Self::save) picks.
    pub fn write_file(&self, path: &Path, exposure: f32) -> Result<()> {
        let err = |message: String| EngineError::File {
            path: path.display().to_string(),
            message,
        };
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("exr") => {
                let w = self.width as usize;
                exr::prelude::write_rgba_file(path, w, self.height as usize, |x, y| {
                    let p = self.pixels[y * w + x];
                    (p[0], p[1], p[2], p[3])
                })
                .map_err(|e| err(format!("writing EXR: {e}")))
            }
            Some("png") => {
                let mut bytes = Vec::with_capacity(self.pixels.len() * 3);
                for p in &self.pixels {
                    bytes.extend_from_slice(&tonemap_to_srgb8([p[0], p[1], p[2]], exposure));
                }
                image::save_buffer(
                    path,
                    &bytes,
                    self.width,
                    self.height,
                    image::ExtendedColorType::Rgb8,
                )
                .map_err(|e| err(format!("writing PNG: {e}")))
            }
            _ => Err(err(
                "unknown image format: use a .exr or .png file name".into()
            )),
        }
    }

    /// Reads a linear RGBA EXR file. Its header is read first: an image of
    /// more than [`MAX_EXR_PIXELS`] pixels (which the EXR reader would
    /// allocate whole before reading a pixel) is refused.
    pub fn load_exr(path: &Path) -> Result<Self> {
        let meta =
            exr::meta::MetaData::read_from_file(path, false).map_err(|e| EngineError::File {
                path: path.display().to_string(),
                message: format!("reading EXR: {e}"),
            })?;
        for header in &meta.headers {
            let size = header.layer_size;
            let pixels = (size.0 as u64).saturating_mul(size.1 as u64);
            if pixels > MAX_EXR_PIXELS {
                return Err(EngineError::File {
                    path: path.display().to_string(),
                    message: format!(
                        "EXR of {}x{} pixels: more than the {MAX_EXR_PIXELS} this reader takes",
                        size.0, size.1
                    ),
                });
            }
        }
        let image = exr::prelude::read_first_rgba_layer_from_file(
            path,
            |res, _| (res.width(), vec![[0f32; 4]; res.width() * res.height()]),
            |(w, px), pos, (r, g, b, a): (f32, f32, f32, f32)| {
                px[pos.y() * *w + pos.x()] = [r, g, b, a]
            },
        )
        .map_err(|e| EngineError::File {
            path: path.display().to_string(),
            message: format!("reading EXR: {e}"),
        })?;
        let size = image.layer_data.size;
        Ok(Self {
            width: size.width() as u32,
            height: size.height() as u32,
            pixels: image.layer_data.channel_data.pixels.1,
        })
    }
}

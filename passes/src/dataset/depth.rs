//! A frame's depth map (nerfstudio's per-frame `depth_file_path`): the
//! z-depth of each pixel, its distance along the camera's viewing
//! direction, as phones' LiDAR captures, RGB-D cameras and renderers'
//! depth passes record it. A greyscale PNG (16 or 8 bits) holds integers
//! in units of the file's `depth_unit_scale_factor` (nerfstudio's default
//! 0.001: millimetres of a scene in metres); an EXR holds depths in the
//! scene's units, from its `Z` channel (else `depth`, `Y`, `R` or its
//! only one), scaled only where the file gives the factor. Zero, negative
//! and non-finite pixels record nothing.

use std::path::Path;

/// How many frames of a dataset have depth maps, and how many of their
/// pixels record a depth.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DepthCounts {
    /// Frames with a depth map.
    pub frames: usize,
    /// Their pixels.
    pub pixels: usize,
    /// Their pixels that record a depth.
    pub recorded: usize,
}

impl DepthCounts {
    /// The counts over `frames`.
    pub fn of(frames: &[super::Frame]) -> Self {
        let mut c = Self::default();
        for f in frames.iter().filter(|f| !f.depth.is_empty()) {
            c.frames += 1;
            c.pixels += f.depth.len();
            c.recorded += f.depth.iter().filter(|&&z| z > 0.0).count();
        }
        c
    }

    /// A line that says so (None where no frame has a depth map).
    pub fn line(&self, of: usize) -> Option<String> {
        (self.frames > 0).then(|| {
            format!(
                "depth maps: {} of {of} frames, {:.1} % of their pixels record a depth",
                self.frames,
                100.0 * self.recorded as f64 / self.pixels.max(1) as f64
            )
        })
    }
}

/// The unit of a PNG depth map's integers where the file gives none
/// (nerfstudio's `depth_unit_scale_factor` default: millimetres).
pub const PNG_DEPTH_UNIT: f64 = 1e-3;

/// The EXR channels a depth map is read from, the first present.
const EXR_DEPTH_CHANNELS: [&str; 4] = ["Z", "depth", "Y", "R"];

/// Reads the depth map at `path` for an image of `size` (width, height):
/// each pixel's z-depth in the scene's units, 0 where it records nothing.
/// `unit` is the file's `depth_unit_scale_factor` where given.
pub fn load_depth_map(
    path: &Path,
    size: (u32, u32),
    unit: Option<f64>,
) -> Result<Vec<f32>, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let (w, h, raw, default_unit) = match ext.as_deref() {
        Some("png") => {
            let img = image::open(path).map_err(|e| format!("unreadable depth map: {e}"))?;
            // The integers as written, not scaled to a common range.
            let raw: Vec<f32> = match &img {
                image::DynamicImage::ImageLuma16(g) => g.pixels().map(|p| p[0] as f32).collect(),
                image::DynamicImage::ImageLuma8(g) => g.pixels().map(|p| p[0] as f32).collect(),
                other => {
                    return Err(format!(
                        "a PNG depth map must be greyscale, 8 or 16 bits (this one is {:?})",
                        other.color()
                    ))
                }
            };
            (img.width(), img.height(), raw, PNG_DEPTH_UNIT)
        }
        Some("exr") => {
            let (w, h, raw) = exr_depth(path)?;
            (w, h, raw, 1.0)
        }
        _ => return Err("a depth map must be a greyscale .png or an .exr".into()),
    };
    if (w, h) != size {
        return Err(format!(
            "depth map is {w}x{h}, the image {}x{}",
            size.0, size.1
        ));
    }
    let unit = unit.unwrap_or(default_unit) as f32;
    Ok(raw
        .into_iter()
        .map(|v| {
            let z = v * unit;
            if z.is_finite() && z > 0.0 {
                z
            } else {
                0.0
            }
        })
        .collect())
}

/// The depth channel of the EXR at `path`: its size and values.
fn exr_depth(path: &Path) -> Result<(u32, u32, Vec<f32>), String> {
    let image = exr::prelude::read_first_flat_layer_from_file(path)
        .map_err(|e| format!("unreadable depth map: {e}"))?;
    let layer = &image.layer_data;
    let channels = &layer.channel_data.list;
    let named = |n: &str| channels.iter().find(|c| c.name.to_string() == n);
    let channel = EXR_DEPTH_CHANNELS
        .iter()
        .find_map(|n| named(n))
        .or(if channels.len() == 1 {
            channels.first()
        } else {
            None
        })
        .ok_or_else(|| {
            format!(
                "depth map has no channel named {} (and more than one channel)",
                EXR_DEPTH_CHANNELS.join(", ")
            )
        })?;
    let values = channel.sample_data.values_as_f32().collect();
    Ok((layer.size.0 as u32, layer.size.1 as u32, values))
}

/// A 16-bit grey PNG of the z-depths `z` (`width` × `height`, row-major) in
/// integers of `unit` (rounded; 0 where nothing is recorded or a depth
/// is past the largest integer), the form [`load_depth_map`] reads.
pub fn depth_png(z: &[f32], width: u32, height: u32, unit: f64) -> Vec<u8> {
    let codes: Vec<u16> = z
        .iter()
        .map(|&d| {
            let k = (d as f64 / unit).round();
            if k.is_finite() && k >= 1.0 && k <= u16::MAX as f64 {
                k as u16
            } else {
                0
            }
        })
        .collect();
    let img = image::ImageBuffer::<image::Luma<u16>, _>::from_raw(width, height, codes)
        .expect("one depth a pixel");
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .expect("a PNG encodes in memory");
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("inlay-depth-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    /// A PNG depth map round-trips at its unit, nothing recorded stays
    /// nothing, and the file's factor scales it.
    #[test]
    fn a_png_depth_map_round_trips_in_its_unit() {
        let z = [0.0, 1.234, 2.5, 70.0, f32::NAN, 0.0004];
        let path = temp("round.png");
        std::fs::write(&path, depth_png(&z, 3, 2, PNG_DEPTH_UNIT)).unwrap();
        let read = load_depth_map(&path, (3, 2), None).unwrap();
        // 70 is past 65.535 at millimetres; 0.0004 rounds to nothing.
        let expected = [0.0, 1.234, 2.5, 0.0, 0.0, 0.0];
        for (r, e) in read.iter().zip(expected) {
            assert!((r - e).abs() < 1e-6, "{read:?}");
        }
        let scaled = load_depth_map(&path, (3, 2), Some(0.01)).unwrap();
        assert!((scaled[1] - 12.34).abs() < 1e-4, "{scaled:?}");
    }

    /// A depth map of another size than its image, a colour PNG, or
    /// another format is refused with a message that says so; an 8-bit
    /// PNG's integers are read as they are.
    #[test]
    fn a_depth_map_of_the_wrong_size_or_kind_is_refused() {
        let path = temp("small.png");
        std::fs::write(&path, depth_png(&[1.0; 4], 2, 2, PNG_DEPTH_UNIT)).unwrap();
        let e = load_depth_map(&path, (3, 2), None).unwrap_err();
        assert!(e.contains("2x2") && e.contains("3x2"), "{e}");
        let e = load_depth_map(&temp("d.npy"), (3, 2), None).unwrap_err();
        assert!(e.contains(".png") && e.contains(".exr"), "{e}");
        let rgb = temp("rgb.png");
        image::RgbImage::from_pixel(3, 2, image::Rgb([1, 2, 3]))
            .save(&rgb)
            .unwrap();
        let e = load_depth_map(&rgb, (3, 2), None).unwrap_err();
        assert!(e.contains("greyscale"), "{e}");
        let grey = temp("grey8.png");
        image::GrayImage::from_pixel(3, 2, image::Luma([200]))
            .save(&grey)
            .unwrap();
        let z = load_depth_map(&grey, (3, 2), Some(0.01)).unwrap();
        assert!((z[0] - 2.0).abs() < 1e-6, "{z:?}");
    }

    /// An EXR depth map is read from its Z channel, in the scene's units.
    #[test]
    fn an_exr_depth_map_is_read_from_its_z_channel() {
        use exr::prelude::*;
        let path = temp("z.exr");
        let z = vec![0.5f32, 0.0, -1.0, 3.25];
        let zc = AnyChannel::new("Z", FlatSamples::F32(z));
        let other = AnyChannel::new("A", FlatSamples::F32(vec![9.0; 4]));
        let layer = Layer::new(
            (2, 2),
            LayerAttributes::default(),
            Encoding::default(),
            AnyChannels::sort(SmallVec::from_vec(vec![zc, other])),
        );
        Image::from_layer(layer).write().to_file(&path).unwrap();
        let read = load_depth_map(&path, (2, 2), None).unwrap();
        assert_eq!(read, vec![0.5, 0.0, 0.0, 3.25]);
    }
}

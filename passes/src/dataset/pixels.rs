//! A frame's pixels as linear radiance: EXR as it is (linear HDR), PNG and
//! JPEG through the sRGB curve, with what each pixel can tell the trainer:
//! a value, a lower bound (a channel at the top of an LDR range: the true
//! radiance is at least that), or nothing (NaN, infinite or negative, or
//! masked out).

use std::path::Path;

/// What a pixel tells the trainer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum PixelState {
    /// A measured radiance.
    Value = 0,
    /// Saturated: the radiance is at least this.
    LowerBound = 1,
    /// No information.
    Masked = 2,
}

/// Counts of the pixels a frame could not use as values.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PixelCounts {
    /// NaN or infinite in some channel (masked).
    pub non_finite: usize,
    /// Negative in some channel (masked).
    pub negative: usize,
    /// Masked by the frame's mask image.
    pub masked: usize,
    /// Saturated LDR pixels (lower bounds).
    pub saturated: usize,
    /// Pixels whose alpha is below 1, composited over the background when
    /// read (their alpha kept: [`FrameImage::alpha`]).
    pub transparent: usize,
}

impl std::ops::AddAssign for PixelCounts {
    fn add_assign(&mut self, o: Self) {
        self.non_finite += o.non_finite;
        self.negative += o.negative;
        self.masked += o.masked;
        self.saturated += o.saturated;
        self.transparent += o.transparent;
    }
}

/// One frame's pixels, row-major from the top-left.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB radiance (0 where masked).
    pub radiance: Vec<[f32; 3]>,
    /// What each pixel tells.
    pub state: Vec<PixelState>,
    /// Each pixel's alpha (the share of it a surface covers), where some
    /// pixel's is below 1; empty where every pixel is opaque. The radiance
    /// is already composited over the background the frame was read with;
    /// the alpha lets a trainer put another behind it.
    pub alpha: Vec<f32>,
    /// How many pixels are not values, and why.
    pub counts: PixelCounts,
}

/// The image formats a frame may be in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageKind {
    /// OpenEXR: linear radiance.
    Exr,
    /// PNG or JPEG: sRGB-encoded, 8 or 16 bits.
    Srgb,
}

/// The kind of image `path` names by its extension, if one this reads.
pub fn image_kind(path: &Path) -> Option<ImageKind> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "exr" => Some(ImageKind::Exr),
        "png" | "jpg" | "jpeg" => Some(ImageKind::Srgb),
        _ => None,
    }
}

/// The size of the image at `path`, from its header.
pub fn image_size(path: &Path) -> Result<(u32, u32), String> {
    match image_kind(path) {
        Some(ImageKind::Exr) => {
            let meta = exr::meta::MetaData::read_from_file(path, false)
                .map_err(|e| format!("unreadable EXR: {e}"))?;
            let h = meta.headers.first().ok_or("EXR without a layer")?;
            Ok((h.layer_size.0 as u32, h.layer_size.1 as u32))
        }
        Some(ImageKind::Srgb) => {
            image::image_dimensions(path).map_err(|e| format!("unreadable image: {e}"))
        }
        None => Err("not an .exr, .png, .jpg or .jpeg file".into()),
    }
}

/// Linear to sRGB-encoded, clipped to [0, 1] first (the engine's one
/// definition): what the training sets' PNGs, the trainer's bracket loss and
/// every PSNR use.
pub use inlay_engine::tonemap::srgb_encode_f64 as srgb_encode;

/// sRGB-encoded [0, 1] to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl FrameImage {
    /// Pixel `i`'s alpha: 1 where the frame is opaque.
    pub fn alpha_at(&self, i: usize) -> f32 {
        self.alpha.get(i).copied().unwrap_or(1.0)
    }

    /// Whether any pixel that is not masked records light (a channel above
    /// 0).
    pub fn records_light(&self) -> bool {
        self.radiance
            .iter()
            .zip(&self.state)
            .any(|(c, s)| *s != PixelState::Masked && c.iter().any(|v| *v > 0.0))
    }
}

/// Reads the frame at `path`. An alpha channel is composited over
/// `background` (linear RGB) in linear light, and kept
/// ([`FrameImage::alpha`]): an LDR image's colour is straight (the pixel's
/// radiance is the alpha-weighted mix of it and the background), an EXR's
/// premultiplied (its radiance plus 1 − alpha of the background), as
/// OpenEXR defines it. An EXR without an alpha channel is opaque.
pub fn load_image(path: &Path, background: [f32; 3]) -> Result<FrameImage, String> {
    let mut counts = PixelCounts::default();
    let mut alpha = Vec::new();
    let (width, height, rgb, saturated) = match image_kind(path) {
        Some(ImageKind::Exr) => {
            let img = inlay_engine::HdrImage::load_exr(path).map_err(|e| e.to_string())?;
            // A NaN alpha stays NaN (clamp keeps it) and leaves a NaN
            // pixel, masked below.
            alpha = img.pixels.iter().map(|p| p[3].clamp(0.0, 1.0)).collect();
            counts.transparent = alpha.iter().filter(|a| **a < 1.0).count();
            let rgb: Vec<[f32; 3]> = img
                .pixels
                .iter()
                .zip(&alpha)
                .map(|(p, a)| [0, 1, 2].map(|k| p[k] + (1.0 - a) * background[k]))
                .collect();
            (img.width, img.height, rgb, vec![false; img.pixels.len()])
        }
        Some(ImageKind::Srgb) => {
            let img = image::open(path).map_err(|e| format!("unreadable image: {e}"))?;
            let (w, h) = (img.width(), img.height());
            let img = img.to_rgba16();
            let mut rgb = Vec::with_capacity((w * h) as usize);
            let mut sat = Vec::with_capacity((w * h) as usize);
            for p in img.pixels() {
                let a = p[3] as f32 / 65535.0;
                alpha.push(a);
                counts.transparent += usize::from(p[3] < u16::MAX);
                let mut c = [0f32; 3];
                for k in 0..3 {
                    let v = srgb_to_linear(p[k] as f32 / 65535.0);
                    c[k] = a * v + (1.0 - a) * background[k];
                }
                rgb.push(c);
                sat.push(a > 0.0 && p.0[..3].contains(&u16::MAX));
            }
            (w, h, rgb, sat)
        }
        None => return Err("not an .exr, .png, .jpg or .jpeg file".into()),
    };
    if counts.transparent == 0 {
        alpha = Vec::new();
    }
    let mut radiance = rgb;
    let state = radiance
        .iter_mut()
        .zip(saturated)
        .map(|(c, sat)| {
            if c.iter().any(|v| !v.is_finite()) {
                counts.non_finite += 1;
                *c = [0.0; 3];
                PixelState::Masked
            } else if c.iter().any(|&v| v < 0.0) {
                counts.negative += 1;
                *c = [0.0; 3];
                PixelState::Masked
            } else if sat {
                counts.saturated += 1;
                PixelState::LowerBound
            } else {
                PixelState::Value
            }
        })
        .collect();
    Ok(FrameImage {
        width,
        height,
        radiance,
        state,
        alpha,
        counts,
    })
}

/// Masks the pixels of `image` that the mask image at `path` marks with 0
/// (nerfstudio's convention: 0 ignore, anything else keep).
pub fn apply_mask(image: &mut FrameImage, path: &Path) -> Result<(), String> {
    let mask = image::open(path)
        .map_err(|e| format!("unreadable mask: {e}"))?
        .to_luma8();
    if (mask.width(), mask.height()) != (image.width, image.height) {
        return Err(format!(
            "mask is {}x{}, the image {}x{}",
            mask.width(),
            mask.height(),
            image.width,
            image.height
        ));
    }
    for (i, m) in mask.pixels().enumerate() {
        if m[0] == 0 && image.state[i] != PixelState::Masked {
            image.state[i] = PixelState::Masked;
            image.radiance[i] = [0.0; 3];
            image.counts.masked += 1;
        }
    }
    Ok(())
}

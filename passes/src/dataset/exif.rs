//! A photograph's exposure time from its EXIF block (JPEG, PNG, WebP), for
//! frames whose `transforms.json` entry gives none: the TIFF structure's
//! first image directory, then the Exif directory it points to (tag
//! 0x8769), read for ExposureTime (tag 0x829A, a rational number of
//! seconds). Aperture and ISO are not read: brackets vary the time.

use std::path::Path;

/// ExposureTime.
const TAG_EXPOSURE_TIME: u16 = 0x829A;
/// The Exif directory's offset.
const TAG_EXIF_IFD: u16 = 0x8769;
/// TIFF field types.
const TYPE_LONG: u16 = 4;
const TYPE_RATIONAL: u16 = 5;

/// Reads numbers in the block's byte order.
struct Tiff<'a> {
    bytes: &'a [u8],
    little: bool,
}

impl Tiff<'_> {
    fn u16_at(&self, at: usize) -> Option<u16> {
        let b: [u8; 2] = self.bytes.get(at..at + 2)?.try_into().ok()?;
        Some(if self.little {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        })
    }

    fn u32_at(&self, at: usize) -> Option<u32> {
        let b: [u8; 4] = self.bytes.get(at..at + 4)?.try_into().ok()?;
        Some(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    /// The entry of `tag` in the directory at `at`: (type, count, the
    /// value-or-offset field's position).
    fn entry(&self, at: usize, tag: u16) -> Option<(u16, u32, usize)> {
        let n = self.u16_at(at)? as usize;
        (0..n.min(1024)).find_map(|i| {
            let e = at + 2 + 12 * i;
            (self.u16_at(e)? == tag).then_some((self.u16_at(e + 2)?, self.u32_at(e + 4)?, e + 8))
        })
    }

    /// The unsigned rational at the entry's offset.
    fn rational(&self, field: usize) -> Option<f64> {
        let at = self.u32_at(field)? as usize;
        let (num, den) = (self.u32_at(at)?, self.u32_at(at + 4)?);
        (den > 0 && num > 0).then(|| num as f64 / den as f64)
    }
}

/// The exposure time in seconds that the EXIF block `exif` (a TIFF
/// structure, as image decoders return it, with or without the
/// `Exif\0\0` prefix) records, or None where it records none or the block
/// is malformed.
pub fn exposure_time_from_exif(exif: &[u8]) -> Option<f64> {
    let bytes = exif.strip_prefix(b"Exif\0\0").unwrap_or(exif);
    let little = match bytes.get(..2)? {
        b"II" => true,
        b"MM" => false,
        _ => return None,
    };
    let t = Tiff { bytes, little };
    if t.u16_at(2)? != 42 {
        return None;
    }
    let ifd0 = t.u32_at(4)? as usize;
    let in_dir = |dir: usize| match t.entry(dir, TAG_EXPOSURE_TIME) {
        Some((TYPE_RATIONAL, 1, field)) => t.rational(field),
        _ => None,
    };
    let exif_dir = match t.entry(ifd0, TAG_EXIF_IFD) {
        Some((TYPE_LONG, 1, field)) => t.u32_at(field).map(|o| o as usize),
        _ => None,
    };
    exif_dir.and_then(in_dir).or_else(|| in_dir(ifd0))
}

/// The exposure time the image at `path` records in its EXIF block, if
/// any (None for files without one, or that cannot be read: the loader
/// reports unreadable images itself).
pub fn exposure_time_of(path: &Path) -> Option<f64> {
    use image::ImageDecoder as _;
    let reader = image::ImageReader::open(path)
        .ok()?
        .with_guessed_format()
        .ok()?;
    let mut decoder = reader.into_decoder().ok()?;
    exposure_time_from_exif(&decoder.exif_metadata().ok()??)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A TIFF block in either byte order: IFD0 with one unrelated entry and
    /// the Exif pointer, the Exif directory with ExposureTime num/den.
    pub(crate) fn exif_block(little: bool, num: u32, den: u32) -> Vec<u8> {
        let u16b = |v: u16| {
            if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            }
        };
        let u32b = |v: u32| {
            if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            }
        };
        let mut b = Vec::new();
        b.extend_from_slice(if little { b"II" } else { b"MM" });
        b.extend_from_slice(&u16b(42));
        b.extend_from_slice(&u32b(8));
        // IFD0 at 8: 2 entries.
        b.extend_from_slice(&u16b(2));
        b.extend_from_slice(&u16b(0x010F)); // Make, ASCII, ignored
        b.extend_from_slice(&u16b(2));
        b.extend_from_slice(&u32b(4));
        b.extend_from_slice(b"abc\0");
        b.extend_from_slice(&u16b(TAG_EXIF_IFD));
        b.extend_from_slice(&u16b(TYPE_LONG));
        b.extend_from_slice(&u32b(1));
        let exif_at = 8 + 2 + 24 + 4;
        b.extend_from_slice(&u32b(exif_at));
        b.extend_from_slice(&u32b(0)); // no next IFD
                                       // Exif IFD: 1 entry, the rational after it.
        b.extend_from_slice(&u16b(1));
        b.extend_from_slice(&u16b(TAG_EXPOSURE_TIME));
        b.extend_from_slice(&u16b(TYPE_RATIONAL));
        b.extend_from_slice(&u32b(1));
        let value_at = exif_at + 2 + 12 + 4;
        b.extend_from_slice(&u32b(value_at));
        b.extend_from_slice(&u32b(0));
        b.extend_from_slice(&u32b(num));
        b.extend_from_slice(&u32b(den));
        b
    }

    #[test]
    fn reads_the_exposure_time_in_both_byte_orders() {
        for little in [true, false] {
            let b = exif_block(little, 1, 250);
            assert_eq!(exposure_time_from_exif(&b), Some(0.004));
            let prefixed = [b"Exif\0\0".as_slice(), &b].concat();
            assert_eq!(exposure_time_from_exif(&prefixed), Some(0.004));
        }
    }

    /// Truncated, zero denominators, wrong magic: None, never a panic.
    #[test]
    fn malformed_blocks_give_none() {
        let good = exif_block(true, 1, 60);
        assert_eq!(exposure_time_from_exif(&exif_block(true, 1, 0)), None);
        assert_eq!(exposure_time_from_exif(&exif_block(true, 0, 5)), None);
        for cut in 0..good.len() {
            assert_eq!(exposure_time_from_exif(&good[..cut]), None, "cut at {cut}");
        }
        let mut bad = good.clone();
        bad[2] = 43;
        assert_eq!(exposure_time_from_exif(&bad), None);
        assert_eq!(exposure_time_from_exif(b"JUNKJUNKJUNK"), None);
    }
}

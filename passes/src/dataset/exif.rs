//! A photograph's exposure from its EXIF block (JPEG, PNG, WebP), for
//! frames whose `transforms.json` entry gives none: the TIFF structure's
//! first image directory, then the Exif directory it points to (tag
//! 0x8769), read for ExposureTime (tag 0x829A, a rational number of
//! seconds), FNumber (0x829D, rational) and the ISO speed
//! (PhotographicSensitivity, 0x8827, a short or long). The light a sensor
//! records grows with the time and the ISO and falls with the square of
//! the f-number; a phone's bracket often varies the ISO with the time, and
//! the time alone would then put its frames' radiance off by the ISO's
//! ratio ([`relative_exposure`]).

use std::path::Path;

/// ExposureTime.
const TAG_EXPOSURE_TIME: u16 = 0x829A;
/// FNumber.
const TAG_F_NUMBER: u16 = 0x829D;
/// PhotographicSensitivity (ISOSpeedRatings before Exif 2.3).
const TAG_ISO: u16 = 0x8827;
/// The Exif directory's offset.
const TAG_EXIF_IFD: u16 = 0x8769;
/// TIFF field types.
const TYPE_SHORT: u16 = 3;
const TYPE_LONG: u16 = 4;
const TYPE_RATIONAL: u16 = 5;

/// Reads numbers in the block's byte order.
#[derive(Clone, Copy)]
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

/// What an EXIF block records of a photograph's exposure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExifExposure {
    /// ExposureTime, seconds.
    pub time: f64,
    /// FNumber, where recorded.
    pub f_number: Option<f64>,
    /// The ISO speed, where recorded.
    pub iso: Option<f64>,
}

/// The exposure that the EXIF block `exif` (a TIFF structure, as image
/// decoders return it, with or without the `Exif\0\0` prefix) records:
/// None where it records no exposure time or the block is malformed; the
/// f-number and ISO where recorded (a zero or unreadable one is left out).
pub fn exposure_from_exif(exif: &[u8]) -> Option<ExifExposure> {
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
    let exif_dir = match t.entry(ifd0, TAG_EXIF_IFD) {
        Some((TYPE_LONG, 1, field)) => t.u32_at(field).map(|o| o as usize),
        _ => None,
    };
    // The Exif directory first, then IFD0 (some writers put them there).
    let find = |read: &dyn Fn(usize) -> Option<f64>| exif_dir.and_then(read).or_else(|| read(ifd0));
    let rational = |tag: u16| {
        move |dir: usize| match t.entry(dir, tag) {
            Some((TYPE_RATIONAL, 1, field)) => t.rational(field),
            _ => None,
        }
    };
    let iso = |dir: usize| {
        let v = match t.entry(dir, TAG_ISO) {
            Some((TYPE_SHORT, n, field)) if n >= 1 => t.u16_at(field).map(f64::from),
            Some((TYPE_LONG, 1, field)) => t.u32_at(field).map(f64::from),
            _ => None,
        }?;
        (v > 0.0).then_some(v)
    };
    Some(ExifExposure {
        time: find(&rational(TAG_EXPOSURE_TIME))?,
        f_number: find(&rational(TAG_F_NUMBER)),
        iso: find(&iso),
    })
}

/// The EXIF block of the image at `path`, if it has one (None for files
/// without one, or that cannot be read: the loader reports unreadable
/// images itself).
fn exif_block(path: &Path) -> Option<Vec<u8>> {
    use image::ImageDecoder as _;
    let reader = image::ImageReader::open(path)
        .ok()?
        .with_guessed_format()
        .ok()?;
    let mut decoder = reader.into_decoder().ok()?;
    decoder.exif_metadata().ok()?
}

/// The exposure the image at `path` records in its EXIF block, if any.
pub fn exposure_of(path: &Path) -> Option<ExifExposure> {
    exposure_from_exif(&exif_block(path)?)
}

/// The turn or flip the image at `path` records in its EXIF block
/// (Orientation, tag 0x0112) for a viewer to show it upright, where it
/// records one other than none. The loader reads the pixels as stored,
/// as COLMAP, instant-ngp and nerfstudio do: a capture's poses are those
/// of the stored pixels.
pub fn orientation_of(path: &Path) -> Option<image::metadata::Orientation> {
    let o = image::metadata::Orientation::from_exif_chunk(&exif_block(path)?)?;
    (o != image::metadata::Orientation::NoTransforms).then_some(o)
}

/// Whether `o` turns an image by a quarter (its width and height swap).
pub fn turns_quarter(o: image::metadata::Orientation) -> bool {
    use image::metadata::Orientation::*;
    matches!(o, Rotate90 | Rotate270 | Rotate90FlipH | Rotate270FlipH)
}

/// `o` in words.
pub fn orientation_words(o: image::metadata::Orientation) -> &'static str {
    use image::metadata::Orientation::*;
    match o {
        NoTransforms => "upright",
        Rotate90 => "turned 90° clockwise",
        Rotate180 => "turned 180°",
        Rotate270 => "turned 90° anticlockwise",
        FlipHorizontal => "mirrored left to right",
        FlipVertical => "mirrored top to bottom",
        Rotate90FlipH => "turned 90° clockwise and mirrored",
        Rotate270FlipH => "turned 90° anticlockwise and mirrored",
    }
}

/// Each of `exposures`' relative exposure, in seconds at the reference ISO
/// and f-number: time × ISO / ISO_ref × (N_ref / N)², the references the
/// medians over the frames that record them (so a dataset shot at one ISO
/// and aperture keeps its times as they are). A frame that does not
/// record one of them while others do keeps its time for that factor.
pub fn relative_exposure(exposures: &[ExifExposure]) -> Vec<f64> {
    let median = |values: Vec<f64>| -> Option<f64> {
        let mut v = values;
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        Some(v[v.len() / 2])
    };
    let iso_ref = median(exposures.iter().filter_map(|e| e.iso).collect());
    let n_ref = median(exposures.iter().filter_map(|e| e.f_number).collect());
    exposures
        .iter()
        .map(|e| {
            let iso = match (e.iso, iso_ref) {
                (Some(i), Some(r)) => i / r,
                _ => 1.0,
            };
            let aperture = match (e.f_number, n_ref) {
                (Some(n), Some(r)) => (r / n).powi(2),
                _ => 1.0,
            };
            e.time * iso * aperture
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The exposure time alone.
    fn exposure_time_from_exif(exif: &[u8]) -> Option<f64> {
        exposure_from_exif(exif).map(|e| e.time)
    }

    /// A TIFF block in either byte order: IFD0 with one unrelated entry and
    /// the Exif pointer, the Exif directory with ExposureTime num/den.
    pub(crate) fn exif_block(little: bool, num: u32, den: u32) -> Vec<u8> {
        exif_block_with(little, (num, den), None, None)
    }

    /// As [`exif_block`], the Exif directory also holding FNumber (a
    /// rational) and the ISO (a short) where given.
    pub(crate) fn exif_block_with(
        little: bool,
        (num, den): (u32, u32),
        f_number: Option<(u32, u32)>,
        iso: Option<u16>,
    ) -> Vec<u8> {
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
                                       // The Exif IFD, its rationals after it.
        let entries = 1 + f_number.is_some() as u32 + iso.is_some() as u32;
        let values_at = exif_at + 2 + 12 * entries + 4;
        b.extend_from_slice(&u16b(entries as u16));
        let mut rationals = vec![(num, den)];
        b.extend_from_slice(&u16b(TAG_EXPOSURE_TIME));
        b.extend_from_slice(&u16b(TYPE_RATIONAL));
        b.extend_from_slice(&u32b(1));
        b.extend_from_slice(&u32b(values_at));
        if let Some(n) = f_number {
            b.extend_from_slice(&u16b(TAG_F_NUMBER));
            b.extend_from_slice(&u16b(TYPE_RATIONAL));
            b.extend_from_slice(&u32b(1));
            b.extend_from_slice(&u32b(values_at + 8));
            rationals.push(n);
        }
        if let Some(v) = iso {
            b.extend_from_slice(&u16b(TAG_ISO));
            b.extend_from_slice(&u16b(TYPE_SHORT));
            b.extend_from_slice(&u32b(1));
            b.extend_from_slice(&u16b(v));
            b.extend_from_slice(&u16b(0));
        }
        b.extend_from_slice(&u32b(0));
        for (n, d) in rationals {
            b.extend_from_slice(&u32b(n));
            b.extend_from_slice(&u32b(d));
        }
        b
    }

    /// FNumber and ISO in both byte orders, and absent.
    #[test]
    fn reads_the_aperture_and_the_iso() {
        for little in [true, false] {
            let b = exif_block_with(little, (1, 100), Some((28, 10)), Some(800));
            assert_eq!(
                exposure_from_exif(&b),
                Some(ExifExposure {
                    time: 0.01,
                    f_number: Some(2.8),
                    iso: Some(800.0)
                })
            );
            let bare = exposure_from_exif(&exif_block(little, 1, 100)).unwrap();
            assert_eq!((bare.f_number, bare.iso), (None, None));
            let zero = exif_block_with(little, (1, 100), Some((0, 10)), Some(0));
            let e = exposure_from_exif(&zero).unwrap();
            assert_eq!((e.time, e.f_number, e.iso), (0.01, None, None));
        }
    }

    /// The ISO and f-number scale the time against the frames' medians: a
    /// bracket that varies the ISO with the time gets exposures in the
    /// ratio of the light recorded; one shot at a single ISO and aperture
    /// keeps its times; a frame missing a value keeps its time for it.
    #[test]
    fn relative_exposures_follow_the_iso_and_the_aperture() {
        let e = |time, f_number, iso| ExifExposure {
            time,
            f_number,
            iso,
        };
        let same = [
            e(0.01, Some(4.0), Some(100.0)),
            e(0.04, Some(4.0), Some(100.0)),
        ];
        assert_eq!(relative_exposure(&same), vec![0.01, 0.04]);
        // Equal times, ISO 100, 400, 1600: exposures 1 : 4 : 16.
        let iso = [
            e(0.01, None, Some(100.0)),
            e(0.01, None, Some(400.0)),
            e(0.01, None, Some(1600.0)),
        ];
        let r = relative_exposure(&iso);
        assert!(
            (r[1] - 0.01).abs() < 1e-15
                && (r[0] - 0.0025).abs() < 1e-15
                && (r[2] - 0.04).abs() < 1e-15,
            "{r:?}"
        );
        // f/2.8 against f/5.6 gathers four times the light.
        let aperture = [
            e(0.01, Some(5.6), None),
            e(0.01, Some(2.8), None),
            e(0.01, Some(5.6), None),
        ];
        let r = relative_exposure(&aperture);
        assert!((r[1] / r[0] - 4.0).abs() < 1e-12 && r[0] == 0.01, "{r:?}");
        let missing = [e(0.01, None, Some(200.0)), e(0.02, None, None)];
        assert_eq!(relative_exposure(&missing)[1], 0.02);
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

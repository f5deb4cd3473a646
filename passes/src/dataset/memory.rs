//! Whether a dataset's photographs fit in memory once read: a capture of a
//! hundred 12-megapixel phone photographs holds 1.2 billion pixels, about
//! 36 GiB once read and pooled for training, and a machine that cannot
//! hold them would stop the run part-way (the system's out-of-memory
//! killer, not an error). The check reads the images' headers alone and
//! refuses such a dataset before any pixel is read, with the
//! `--downscale` that would fit.

/// Bytes each pixel costs once read and pooled for training: its linear
/// radiance (12), what it tells (1), its alpha (4), its depth (4) and its
/// place in the trainer's pool of pixels (8), with some slack.
pub const BYTES_PER_PIXEL: u64 = 32;

/// Bytes each pixel of an image costs while it is decoded, before it is
/// reduced and kept: the decoder's own buffer (up to 16 for an EXR's
/// f32 RGBA), a 16-bit RGBA copy of an sRGB image (8), and the linear
/// radiance, alpha, saturation and state read from it (18), with some
/// slack. Each reading thread holds one image so, at full size whatever
/// `--downscale` asks.
pub const DECODE_BYTES_PER_PIXEL: u64 = 40;

/// The bytes `pixels` photographs' pixels hold read at 1/`n` of their
/// width and height (a close upper bound: the blocks a side leaves out are
/// counted).
pub fn bytes_held(pixels: u64, n: u32) -> u64 {
    BYTES_PER_PIXEL * pixels / (n as u64 * n as u64)
}

/// The photographs a dataset would read, as their headers give them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PhotoSizes {
    /// Pixels of all of them, at full size.
    pub pixels: u64,
    /// Pixels of the largest one.
    pub largest: u64,
    /// Images decoded at once (the reading threads, at most one a photograph).
    pub readers: u64,
}

impl PhotoSizes {
    /// Bytes the images being decoded hold at once.
    pub fn decoding(&self) -> u64 {
        DECODE_BYTES_PER_PIXEL * self.largest * self.readers
    }

    /// Bytes the read needs at its peak at 1/`n`: every photograph kept,
    /// and the last ones still being decoded.
    pub fn needed(&self, n: u32) -> u64 {
        bytes_held(self.pixels, n) + self.decoding()
    }
}

/// Why `photos` read at 1/`n` do not fit `available` bytes, if they do
/// not: what they would hold, and the smallest `--downscale` that leaves
/// half the memory free for the rest of the run (or, where the images
/// decoded at once are what does not fit, fewer reading threads).
pub fn problem(photos: PhotoSizes, n: u32, available: u64) -> Option<String> {
    let needed = photos.needed(n);
    if needed <= available {
        return None;
    }
    let fit = |p: PhotoSizes| {
        (n..=super::downscale::MAX_DOWNSCALE).find(|&m| 2 * p.needed(m) <= available)
    };
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    // The most reading threads that fit at this downscale, else at any.
    let fewer_readers = || {
        let with = |readers| PhotoSizes { readers, ..photos };
        (1..photos.readers)
            .rev()
            .find(|&r| 2 * with(r).needed(n) <= available)
            .map(|r| (r, n, with(r).needed(n)))
            .or_else(|| {
                (1..photos.readers)
                    .rev()
                    .find_map(|r| fit(with(r)).map(|m| (r, m, with(r).needed(m))))
            })
    };
    let advice = match (fit(photos), fewer_readers()) {
        (Some(m), _) => format!(
            "--downscale {m} reads them at 1/{m} of their width and height ({:.1} GiB)",
            gib(photos.needed(m))
        ),
        (None, Some((readers, m, needed))) => format!(
            "the {} images decoded at once (one a reading thread) hold {:.1} GiB at full size \
             whatever the downscale: RAYON_NUM_THREADS={readers}{} fits ({:.1} GiB)",
            photos.readers,
            gib(photos.decoding()),
            if m > 1 {
                format!(" with --downscale {m}")
            } else {
                String::new()
            },
            gib(needed)
        ),
        (None, None) => "fewer frames would".into(),
    };
    Some(format!(
        "{} pixels{} hold about {:.1} GiB once read and pooled for training, and this \
         machine has {:.1} GiB available: {advice}",
        photos.pixels,
        if n > 1 {
            format!(" at --downscale {n}")
        } else {
            String::new()
        },
        gib(needed),
        gib(available),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hundred 12-megapixel photographs do not fit 16 GiB; the factor
    /// named leaves half of it free, and fits. The images being decoded
    /// count at full size.
    #[test]
    fn photographs_that_do_not_fit_name_the_downscale_that_does() {
        let gib = 1u64 << 30;
        let photos = PhotoSizes {
            pixels: 100 * 4000 * 3000,
            largest: 4000 * 3000,
            readers: 2,
        };
        assert_eq!(photos.decoding(), 2 * 40 * 12_000_000);
        assert_eq!(problem(photos, 1, 64 * gib), None);
        let p = problem(photos, 1, 16 * gib).unwrap();
        assert!(
            p.contains("about 36.7 GiB") && p.contains("--downscale 3 "),
            "{p}"
        );
        assert!(2 * photos.needed(3) <= 16 * gib && 2 * photos.needed(2) > 16 * gib);
        assert_eq!(problem(photos, 3, 16 * gib), None);
        // Sixty-four threads each decoding a 12-megapixel image need 29
        // GiB whatever the downscale: on 16 GiB the threads are named.
        let many = PhotoSizes {
            readers: 64,
            ..photos
        };
        let p = problem(many, 8, 16 * gib).unwrap();
        assert!(p.contains("64 images decoded at once"), "{p}");
        assert!(p.contains("hold 28.6 GiB"), "{p}");
        assert!(
            p.contains("RAYON_NUM_THREADS=16 with --downscale 8 fits"),
            "{p}"
        );
        let p16 = PhotoSizes {
            readers: 16,
            ..photos
        };
        assert!(2 * p16.needed(8) <= 16 * gib);
        assert!(
            2 * PhotoSizes {
                readers: 17,
                ..photos
            }
            .needed(8)
                > 16 * gib
        );
        // Nothing fits a machine with no memory to spare.
        let p = problem(photos, 1, 1000).unwrap();
        assert!(p.ends_with("fewer frames would"), "{p}");
    }
}

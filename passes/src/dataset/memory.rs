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

/// The bytes `pixels` photographs' pixels hold read at 1/`n` of their
/// width and height (a close upper bound: the blocks a side leaves out are
/// counted).
pub fn bytes_held(pixels: u64, n: u32) -> u64 {
    BYTES_PER_PIXEL * pixels / (n as u64 * n as u64)
}

/// Why `pixels` pixels read at 1/`n` do not fit `available` bytes, if they
/// do not: what they would hold, and the smallest `--downscale` that
/// leaves half the memory free for the rest of the run.
pub fn problem(pixels: u64, n: u32, available: u64) -> Option<String> {
    let held = bytes_held(pixels, n);
    if held <= available {
        return None;
    }
    let fits =
        (n..=super::downscale::MAX_DOWNSCALE).find(|&m| 2 * bytes_held(pixels, m) <= available);
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    Some(format!(
        "{pixels} pixels{} hold about {:.1} GiB once read and pooled for training, and this \
         machine has {:.1} GiB available: {}",
        if n > 1 {
            format!(" at --downscale {n}")
        } else {
            String::new()
        },
        gib(held),
        gib(available),
        match fits {
            Some(m) => format!(
                "--downscale {m} reads them at 1/{m} of their width and height ({:.1} GiB)",
                gib(bytes_held(pixels, m))
            ),
            None => "fewer frames would".into(),
        }
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hundred 12-megapixel photographs do not fit 16 GiB; the factor
    /// named leaves half of it free, and fits.
    #[test]
    fn photographs_that_do_not_fit_name_the_downscale_that_does() {
        let gib = 1u64 << 30;
        let pixels = 100 * 4000 * 3000;
        assert_eq!(problem(pixels, 1, 64 * gib), None);
        let p = problem(pixels, 1, 16 * gib).unwrap();
        assert!(
            p.contains("about 35.8 GiB") && p.contains("--downscale 3 "),
            "{p}"
        );
        assert!(2 * bytes_held(pixels, 3) <= 16 * gib && 2 * bytes_held(pixels, 2) > 16 * gib);
        assert_eq!(problem(pixels, 3, 16 * gib), None);
        // Nothing fits a machine with no memory to spare.
        let p = problem(pixels, 1, 1000).unwrap();
        assert!(p.ends_with("fewer frames would"), "{p}");
    }
}

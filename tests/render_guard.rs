//! The guard for changes that must not change what inlay renders: compares
//! two folders written by `tools/guard-renders.sh` (one before the change,
//! one after). Every EXR must match within 1e-6 relative per channel, every
//! text file (the profiler's passes and skip reasons) exactly. Ignored by
//! default: it needs the two folders.
//!
//! ```text
//! tools/guard-renders.sh /tmp/before   # on the old build
//! tools/guard-renders.sh /tmp/after    # on the new one
//! INLAY_GUARD_BEFORE=/tmp/before INLAY_GUARD_AFTER=/tmp/after \
//!   cargo test --release --test render_guard -- --ignored
//! ```

use std::path::{Path, PathBuf};

use inlay_engine::HdrImage;

/// Relative tolerance per channel.
const RELATIVE: f32 = 1e-6;
/// Below this both values count as equal (denormal-scale noise).
const FLOOR: f32 = 1e-12;

/// The worst relative channel difference between two images and where it
/// is, or why they cannot be compared.
fn worst_difference(a: &HdrImage, b: &HdrImage) -> Result<(f32, usize), String> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(format!(
            "sizes differ: {}x{} against {}x{}",
            a.width, a.height, b.width, b.height
        ));
    }
    let mut worst = (0.0f32, 0usize);
    for (i, (p, q)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        for (x, y) in p.iter().zip(q) {
            if x.is_nan() != y.is_nan() {
                return Err(format!("pixel {i}: {x} against {y}"));
            }
            let scale = x.abs().max(y.abs());
            let d = if scale < FLOOR {
                0.0
            } else {
                (x - y).abs() / scale
            };
            if d > worst.0 {
                worst = (d, i);
            }
        }
    }
    Ok(worst)
}

fn files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    v.sort();
    v
}

#[test]
fn the_tolerance_catches_a_change() {
    let a = HdrImage {
        width: 2,
        height: 1,
        pixels: vec![[1.0, 0.5, 0.0, 1.0], [2.0, 1e-20, 0.0, 1.0]],
    };
    let mut b = a.clone();
    assert_eq!(worst_difference(&a, &b), Ok((0.0, 0)));
    b.pixels[1][1] = 2e-20;
    assert_eq!(worst_difference(&a, &b), Ok((0.0, 0)), "below the floor");
    b.pixels[1][0] = 2.0 * (1.0 + 4.0 * RELATIVE);
    let (d, at) = worst_difference(&a, &b).unwrap();
    assert!(d > RELATIVE && at == 1, "{d} at {at}");
}

#[test]
#[ignore = "needs two folders from tools/guard-renders.sh"]
fn renders_match_before_and_after() {
    let before = PathBuf::from(std::env::var("INLAY_GUARD_BEFORE").expect("INLAY_GUARD_BEFORE"));
    let after = PathBuf::from(std::env::var("INLAY_GUARD_AFTER").expect("INLAY_GUARD_AFTER"));
    let names = |d: &Path| -> Vec<_> {
        files(d)
            .iter()
            .map(|p| p.file_name().unwrap().to_owned())
            .collect()
    };
    assert_eq!(
        names(&before),
        names(&after),
        "the folders hold different files"
    );
    let mut failures = Vec::new();
    let mut compared = 0;
    for path in files(&before) {
        let other = after.join(path.file_name().unwrap());
        let name = path.display().to_string();
        if path.extension().is_some_and(|e| e == "exr") {
            let a = HdrImage::load_exr(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
            let b =
                HdrImage::load_exr(&other).unwrap_or_else(|e| panic!("{}: {e}", other.display()));
            match worst_difference(&a, &b) {
                Ok((d, _)) if d <= RELATIVE => {}
                Ok((d, i)) => failures.push(format!("{name}: pixel {i} differs by {d:e} relative")),
                Err(e) => failures.push(format!("{name}: {e}")),
            }
        } else if std::fs::read(&path).unwrap() != std::fs::read(&other).unwrap() {
            failures.push(format!("{name}: the text differs"));
        }
        compared += 1;
    }
    assert!(compared > 0, "nothing to compare in {}", before.display());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    println!("{compared} files match");
}

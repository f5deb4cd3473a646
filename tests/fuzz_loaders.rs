//! Structure-aware fuzzing of every loader: scene TOML, `.inlayfield`,
//! `.inlayssdf`, environment files, glTF/glb (with its `.bin` buffers and
//! PNG textures) and EXR environment maps.
//!
//! Each case takes a seed from the corpus (the bundled scenes and objects,
//! and the small files in `tests/fuzz-corpus/`), mutates it the way a
//! damaged or hostile file differs from a good one, and loads it: binary
//! seeds get bit flips, header words set to boundary values (0, 1, −1,
//! 2³¹, NaN, ±∞, 1e30), truncation, insertion and removal; text seeds get
//! numbers replaced by boundary values, lines deleted, duplicated or
//! swapped, and keys renamed. The property: the loader returns a value or
//! an error, never panics, and a value it returns holds what the format
//! promises (finite, in range). A failing case proptest shrinks is kept in
//! `tests/fuzz_loaders.proptest-regressions` (replayed first on every run); a file
//! worth keeping as a seed goes into `tests/fuzz-corpus/`.
//!
//! Cases per loader: `INLAY_FUZZ_CASES` (default 1000, what CI runs;
//! `INLAY_FUZZ_CASES=20000 cargo test --release --test fuzz_loaders` for a
//! longer hunt). The seed files are written by
//! `cargo test --test fuzz_loaders -- --ignored write_the_seed_corpus`.

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use proptest::test_runner::{Config, FileFailurePersistence, TestRunner};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn corpus_dir(kind: &str) -> PathBuf {
    repo().join("tests/fuzz-corpus").join(kind)
}

/// The files of `dir` whose names end with one of `extensions`, sorted.
fn seeds_in(dir: &Path, extensions: &[&str]) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let name = p.file_name().unwrap().to_string_lossy();
            extensions.iter().any(|x| name.ends_with(x))
        })
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no seeds in {}", dir.display());
    files
}

fn cases() -> u32 {
    std::env::var("INLAY_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1000)
}

fn runner() -> TestRunner {
    TestRunner::new(Config {
        cases: cases(),
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource(
            "proptest-regressions",
        ))),
        source_file: Some(file!()),
        ..Config::default()
    })
}

/// A scratch directory for this process and `name`.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("inlay-fuzz-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

// ---------------------------------------------------------------------------
// Mutations.

/// 32-bit words a header field is most likely to be wrong with.
const BOUNDARY_WORDS: [u32; 12] = [
    0,
    1,
    2,
    0xffff_ffff,
    0x8000_0000,
    0x7fff_ffff,
    0x7fc0_0000, // NaN
    0x7f80_0000, // +inf
    0xff80_0000, // -inf
    0x7149_f2ca, // 1e30
    0xbf80_0000, // -1.0
    1025,
];

/// Numbers a text field is most likely to be wrong with.
const BOUNDARY_NUMBERS: [&str; 16] = [
    "0",
    "-0.0",
    "-1",
    "1e-320",
    "1e308",
    "1e400",
    "nan",
    "inf",
    "-inf",
    "4294967296",
    "18446744073709551616",
    "2147483648",
    "0.5",
    "[1, 2]",
    "\"x\"",
    "[]",
];

/// One change to a binary file.
#[derive(Debug, Clone)]
enum ByteEdit {
    Flip { at: usize, bit: u8 },
    Word { at: usize, word: u32 },
    Truncate { at: usize },
    Insert { at: usize, bytes: Vec<u8> },
    Remove { at: usize, len: usize },
}

fn byte_edit() -> impl Strategy<Value = ByteEdit> {
    prop_oneof![
        (any::<usize>(), 0u8..8).prop_map(|(at, bit)| ByteEdit::Flip { at, bit }),
        (any::<usize>(), prop::sample::select(&BOUNDARY_WORDS[..]))
            .prop_map(|(at, word)| ByteEdit::Word { at, word }),
        any::<usize>().prop_map(|at| ByteEdit::Truncate { at }),
        (any::<usize>(), prop::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(at, bytes)| ByteEdit::Insert { at, bytes }),
        (any::<usize>(), 1usize..64).prop_map(|(at, len)| ByteEdit::Remove { at, len }),
    ]
}

/// `seed` with `edits` applied. Header words are hit most often: half the
/// positions fall in the first 64 bytes, aligned to a word.
fn apply_bytes(seed: &[u8], edits: &[ByteEdit]) -> Vec<u8> {
    let mut b = seed.to_vec();
    let pos = |at: usize, len: usize| -> usize {
        if len == 0 {
            0
        } else if at % 2 == 0 {
            ((at / 2) % 16 * 4).min(len - 1)
        } else {
            (at / 2) % len
        }
    };
    for e in edits {
        match e {
            ByteEdit::Flip { at, bit } if !b.is_empty() => {
                let i = pos(*at, b.len());
                b[i] ^= 1 << bit;
            }
            ByteEdit::Word { at, word } if b.len() >= 4 => {
                let i = pos(*at, b.len() - 3);
                b[i..i + 4].copy_from_slice(&word.to_le_bytes());
            }
            ByteEdit::Truncate { at } => b.truncate(at % (b.len() + 1)),
            ByteEdit::Insert { at, bytes } => {
                let i = at % (b.len() + 1);
                b.splice(i..i, bytes.iter().copied());
            }
            ByteEdit::Remove { at, len } if !b.is_empty() => {
                let i = at % b.len();
                b.drain(i..(i + len).min(b.len()));
            }
            _ => {}
        }
    }
    b
}

/// One change to a text file.
#[derive(Debug, Clone)]
enum TextEdit {
    Number { nth: usize, to: &'static str },
    DeleteLine { at: usize },
    DuplicateLine { at: usize },
    SwapLines { a: usize, b: usize },
    RenameKey { at: usize, suffix: char },
    Bytes(ByteEdit),
}

fn text_edit() -> impl Strategy<Value = TextEdit> {
    prop_oneof![
        4 => (any::<usize>(), prop::sample::select(&BOUNDARY_NUMBERS[..]))
            .prop_map(|(nth, to)| TextEdit::Number { nth, to }),
        1 => any::<usize>().prop_map(|at| TextEdit::DeleteLine { at }),
        1 => any::<usize>().prop_map(|at| TextEdit::DuplicateLine { at }),
        1 => (any::<usize>(), any::<usize>()).prop_map(|(a, b)| TextEdit::SwapLines { a, b }),
        1 => (any::<usize>(), prop::char::range('a', 'z'))
            .prop_map(|(at, suffix)| TextEdit::RenameKey { at, suffix }),
        1 => byte_edit().prop_map(TextEdit::Bytes),
    ]
}

/// The byte ranges of the numbers in `text`.
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts =
            b[i].is_ascii_digit() || (b[i] == b'-' && b.get(i + 1).is_some_and(u8::is_ascii_digit));
        let inside_word = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if starts && !inside_word {
            let mut j = i + 1;
            while j < b.len() && (b[j].is_ascii_alphanumeric() || b"._+-".contains(&b[j])) {
                j += 1;
            }
            spans.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    spans
}

fn apply_text(seed: &str, edits: &[TextEdit]) -> Vec<u8> {
    let mut text = seed.to_owned();
    for e in edits {
        let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
        let n = lines.len().max(1);
        match e {
            TextEdit::Number { nth, to } => {
                let spans = number_spans(&text);
                if let Some(&(a, b)) = spans.get(nth % spans.len().max(1)) {
                    text.replace_range(a..b, to);
                }
                continue;
            }
            TextEdit::DeleteLine { at } if !lines.is_empty() => {
                lines.remove(at % n);
            }
            TextEdit::DuplicateLine { at } if !lines.is_empty() => {
                let l = lines[at % n].clone();
                lines.insert(at % n, l);
            }
            TextEdit::SwapLines { a, b } if !lines.is_empty() => lines.swap(a % n, b % n),
            TextEdit::RenameKey { at, suffix } if !lines.is_empty() => {
                let l = &mut lines[at % n];
                if let Some(eq) = l.find(" =") {
                    l.insert(eq, *suffix);
                }
            }
            TextEdit::Bytes(b) => {
                text =
                    String::from_utf8_lossy(&apply_bytes(text.as_bytes(), std::slice::from_ref(b)))
                        .into_owned();
                continue;
            }
            _ => {}
        }
        text = lines.join("\n");
    }
    text.into_bytes()
}

/// Runs `check` on mutated copies of `seeds`: binary mutations when
/// `binary`, else text ones. `check` gets the mutated bytes and the seed's
/// path; it returns whether the loader accepted them, and fails the case
/// by returning an error.
fn fuzz(
    name: &str,
    seeds: &[PathBuf],
    binary: bool,
    check: impl Fn(&[u8], &Path) -> Result<bool, String>,
) {
    let contents: Vec<Vec<u8>> = seeds.iter().map(|p| std::fs::read(p).unwrap()).collect();
    // Every seed loads as it is (so mutations start from deep inside).
    for (bytes, path) in contents.iter().zip(seeds) {
        match check(bytes, path) {
            Ok(true) => {}
            Ok(false) => panic!("seed {} does not load", path.display()),
            Err(e) => panic!("seed {}: {e}", path.display()),
        }
    }
    let accepted = std::cell::Cell::new(0u32);
    let strategy = (
        0..seeds.len(),
        prop::collection::vec(byte_edit(), 1..4),
        prop::collection::vec(text_edit(), 1..4),
    );
    let mut runner = runner();
    let result = runner.run(&strategy, |(i, bytes_edits, text_edits)| {
        let mutated = if binary {
            apply_bytes(&contents[i], &bytes_edits)
        } else {
            apply_text(&String::from_utf8_lossy(&contents[i]), &text_edits)
        };
        let loaded =
            check(&mutated, &seeds[i]).map_err(|e| TestCaseError::fail(format!("{name}: {e}")))?;
        accepted.set(accepted.get() + loaded as u32);
        Ok(())
    });
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
    eprintln!(
        "{name}: {} mutated cases, {} accepted",
        cases(),
        accepted.get()
    );
}

// ---------------------------------------------------------------------------
// The loaders.

#[test]
fn field_files() {
    let seeds = seeds_in(&corpus_dir("field"), &[".inlayfield"]);
    fuzz("field", &seeds, true, |bytes, path| {
        if let Ok(f) = inlay_passes::field::parse_field(path, bytes) {
            let n = f.resolution.x as usize * f.resolution.y as usize * f.resolution.z as usize;
            if f.nodes.len() != n {
                return Err(format!("{} nodes for {n}", f.nodes.len()));
            }
            // A density may be negative (clamped after interpolation); a
            // colour may not.
            if !f
                .nodes
                .iter()
                .all(|n| n.iter().all(|v| v.is_finite()) && n[..3].iter().all(|c| *c >= 0.0))
            {
                return Err("a loaded field holds a non-finite value or a negative colour".into());
            }
            if !f.bounds.is_valid() {
                return Err("a loaded field has invalid bounds".into());
            }
            return Ok(true);
        }
        Ok(false)
    });
}

#[test]
fn ssdf_files() {
    let seeds = seeds_in(&corpus_dir("ssdf"), &[".inlayssdf"]);
    fuzz("ssdf", &seeds, true, |bytes, path| {
        if let Ok(f) = inlay_passes::ssdf::parse_ssdf(bytes, path) {
            let texels = (f.directions * f.directions) as usize;
            let k = f.components as usize;
            if f.texel_rows.len() != texels * (k + 1)
                || f.coefficients.len() != (f.grid.nodes as usize).pow(3) * k
            {
                return Err("a loaded SSDF's arrays do not match its header".into());
            }
            let values = f.texel_rows.iter().chain(&f.coefficients);
            if !values.clone().all(|v| v.is_finite())
                || f.grid.radius.is_nan()
                || f.grid.radius <= 0.0
            {
                return Err("a loaded SSDF holds a non-finite value".into());
            }
            return Ok(true);
        }
        Ok(false)
    });
}

#[test]
fn environment_files() {
    let seeds = seeds_in(&corpus_dir("env"), &[".toml"]);
    fuzz("environment", &seeds, false, |bytes, path| {
        let Ok(text) = std::str::from_utf8(bytes) else {
            return Ok(false);
        };
        if let Ok(light) = inlay_passes::envest::parse_environment_file(path, text) {
            for l in &light.lobes {
                let ok = l.direction.is_finite()
                    && (l.direction.length() - 1.0).abs() < 1e-6
                    && l.sharpness.is_finite()
                    && l.sharpness > 0.0
                    && l.amplitude.is_finite()
                    && l.amplitude.min_element() >= 0.0;
                if !ok {
                    return Err(format!("a loaded lobe is out of range: {l:?}"));
                }
            }
            for p in &light.lights {
                if !(p.position.is_finite() && p.intensity.is_finite()) {
                    return Err(format!("a loaded light is not finite: {p:?}"));
                }
            }
            return Ok(true);
        }
        Ok(false)
    });
}

/// Datasets (`transforms.json`): mutated files beside the two small frames
/// and the mask they name; whatever loads has finite, usable cameras and
/// radiance, and what does not names the file.
#[test]
fn transforms_files() {
    use inlay_passes::dataset::{load_dataset, LoadOptions};
    let dir = scratch("transforms");
    image::RgbaImage::from_pixel(5, 4, image::Rgba([200, 120, 255, 180]))
        .save(dir.join("a.png"))
        .unwrap();
    image::GrayImage::from_fn(5, 4, |x, _| image::Luma([(x > 0) as u8 * 255]))
        .save(dir.join("m.png"))
        .unwrap();
    let exr = inlay_engine::HdrImage {
        width: 5,
        height: 4,
        pixels: (0..20).map(|i| [i as f32, f32::NAN, 0.5, 1.0]).collect(),
    };
    exr.write_file(&dir.join("b.exr"), 1.0).unwrap();
    let seeds = seeds_in(&corpus_dir("transforms"), &[".json"]);
    let file = dir.join("transforms.json");
    fuzz("transforms", &seeds, false, |bytes, _| {
        std::fs::write(&file, bytes).map_err(|e| e.to_string())?;
        match load_dataset(&dir, &LoadOptions::default()) {
            Ok(d) => {
                if d.frames.is_empty() || !d.bounds.is_valid() {
                    return Err(format!("loaded without frames or bounds: {:?}", d.bounds));
                }
                for f in &d.frames {
                    if f.intrinsics.problem().is_some() || !f.pose.matrix.is_finite() {
                        return Err(format!("frame {} loaded unusable", f.index));
                    }
                    let finite = f
                        .image
                        .radiance
                        .iter()
                        .flatten()
                        .all(|v| v.is_finite() && *v >= 0.0);
                    if !finite {
                        return Err(format!("frame {} holds a bad pixel", f.index));
                    }
                }
                Ok(true)
            }
            Err(e) if e.to_string().contains("transforms.json") => Ok(false),
            Err(e) => Err(format!("an error that does not name the file: {e}")),
        }
    });
}

/// Copies `scenes/objects` and the corpus's scene directory into a scratch
/// directory, so that mutated scene files resolve what they name.
fn scene_workspace() -> PathBuf {
    let dir = scratch("scenes");
    for (from, to) in [
        (repo().join("scenes/objects"), dir.join("objects")),
        (corpus_dir("scene"), dir.clone()),
        (corpus_dir("field"), dir.join("field")),
        (corpus_dir("exr"), dir.join("exr")),
        (corpus_dir("env"), dir.join("env")),
    ] {
        std::fs::create_dir_all(&to).unwrap();
        for e in std::fs::read_dir(&from).unwrap() {
            let p = e.unwrap().path();
            if p.is_file() {
                std::fs::copy(&p, to.join(p.file_name().unwrap())).unwrap();
            }
        }
    }
    dir
}

#[test]
fn scene_files() {
    let mut seeds = seeds_in(&repo().join("scenes"), &[".toml"]);
    seeds.extend(seeds_in(&corpus_dir("scene"), &[".toml"]));
    let work = scene_workspace();
    fuzz("scene", &seeds, false, |bytes, _| {
        let path = work.join("case.toml");
        std::fs::write(&path, bytes).unwrap();
        if let Ok(scene) = inlay_passes::scene::load_scene(&path) {
            for o in &scene.objects {
                if let Some((k, m)) = o.pose.problem() {
                    return Err(format!("a loaded object's pose `{k}`: {m}"));
                }
            }
            for c in &scene.cameras {
                if let Some(m) = c.problem() {
                    return Err(format!("a loaded camera: {m}"));
                }
            }
            if let Err((k, m)) = scene.march.check() {
                return Err(format!("loaded march knob `{k}`: {m}"));
            }
            return Ok(true);
        }
        Ok(false)
    });
}

/// Loads `bytes` as the file `name` next to copies of the other object
/// files (so a mutated `.gltf` finds its `.bin` and textures, and a mutated
/// `.bin` or `.png` is found by its `.gltf`), then the glTF `gltf`.
fn load_object_case(work: &Path, name: &str, bytes: &[u8], gltf: &str) -> Result<bool, String> {
    let target = work.join(name);
    std::fs::write(&target, bytes).unwrap();
    let result = inlay_passes::object::load_gltf(&work.join(gltf));
    // Restore the pristine file for the next case.
    std::fs::copy(repo().join("scenes/objects").join(name), &target).unwrap();
    if let Ok(mesh) = result {
        let n = mesh.vertices.len() as u32;
        if mesh.indices.len() % 3 != 0 || mesh.indices.iter().any(|&i| i >= n) {
            return Err("a loaded mesh indexes past its vertices".into());
        }
        let finite = mesh
            .vertices
            .iter()
            .all(|v| v.position.is_finite() && v.normal.is_finite());
        if !finite {
            return Err("a loaded mesh has a non-finite vertex".into());
        }
        return Ok(true);
    }
    Ok(false)
}

#[test]
fn gltf_and_glb_objects() {
    let objects = repo().join("scenes/objects");
    let work = scratch("objects");
    for e in std::fs::read_dir(&objects).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, work.join(p.file_name().unwrap())).unwrap();
    }
    let glb = seeds_in(&objects, &[".glb"]);
    fuzz("glb", &glb, true, |bytes, seed| {
        let name = seed.file_name().unwrap().to_string_lossy().into_owned();
        load_object_case(&work, &name, bytes, &name)
    });
    let gltf = seeds_in(&objects, &[".gltf"]);
    fuzz("gltf", &gltf, false, |bytes, seed| {
        let name = seed.file_name().unwrap().to_string_lossy().into_owned();
        load_object_case(&work, &name, bytes, &name)
    });
    // The checker cube's buffer and textures, reached through its .gltf.
    let parts = seeds_in(
        &objects,
        &["checker-cube.bin", "checker.png", "checker-mr.png"],
    );
    fuzz("gltf parts", &parts, true, |bytes, seed| {
        let name = seed.file_name().unwrap().to_string_lossy().into_owned();
        load_object_case(&work, &name, bytes, "checker-cube.gltf")
    });
}

#[test]
fn exr_environment_maps() {
    let seeds = seeds_in(&corpus_dir("exr"), &[".exr"]);
    let work = scratch("exr");
    fuzz("exr", &seeds, true, |bytes, _| {
        let path = work.join("case.exr");
        std::fs::write(&path, bytes).unwrap();
        if let Ok(map) = inlay_passes::scene::EquirectMap::load(&path, 1.0) {
            let probe = map.eval(glam::DVec3::Y);
            if !probe.is_finite() || probe.min_element() < 0.0 {
                return Err(format!("a loaded map has radiance {probe}"));
            }
            return Ok(true);
        }
        Ok(false)
    });
}

// ---------------------------------------------------------------------------
// The seed corpus.

/// Writes the binary seeds of `tests/fuzz-corpus/` (small, valid files).
#[test]
#[ignore = "writes the committed seed corpus; run by hand when a format changes"]
fn write_the_seed_corpus() {
    use glam::{DVec3, UVec3};
    use inlay_passes::geometry::Aabb;
    let res = UVec3::new(3, 4, 2);
    let nodes: Vec<[f32; 4]> = (0..24)
        .map(|i| {
            let v = i as f32 / 24.0;
            [v, 1.0 - v, 0.25, if i % 3 == 0 { 0.0 } else { 4.0 * v }]
        })
        .collect();
    let field = inlay_passes::field::GridField::new(
        res,
        Aabb::new(DVec3::splat(-1.0), DVec3::new(1.0, 2.0, 0.5)),
        nodes,
        inlay_passes::field::DEFAULT_OCCUPANCY_BLOCK,
    );
    let dir = corpus_dir("field");
    std::fs::create_dir_all(&dir).unwrap();
    inlay_passes::field::save_field(&dir.join("tiny.inlayfield"), &field).unwrap();

    let directions = 4u32;
    let texels = (directions * directions) as usize;
    let grid = inlay_passes::ssdf::SsdfGrid {
        centre: DVec3::new(0.0, 0.5, 0.0),
        radius: 0.5,
        nodes: 2,
    };
    let ssdf = inlay_passes::ssdf::SsdfField {
        grid,
        directions,
        components: 2,
        texel_rows: (0..texels * 3).map(|i| (i as f32 * 0.37).sin()).collect(),
        coefficients: (0..8 * 2).map(|i| (i as f32 * 0.21).cos()).collect(),
        object: 0x1234_5678_9abc_def0,
    };
    let dir = corpus_dir("ssdf");
    std::fs::create_dir_all(&dir).unwrap();
    inlay_passes::ssdf::save_ssdf(&ssdf, &dir.join("tiny.inlayssdf")).unwrap();

    let sky = inlay_engine::HdrImage {
        width: 8,
        height: 4,
        pixels: (0..32)
            .map(|i| {
                let v = if i == 9 { 40.0 } else { 0.2 + 0.01 * i as f32 };
                [v, v * 0.9, v * 0.8, 1.0]
            })
            .collect(),
    };
    let dir = corpus_dir("exr");
    std::fs::create_dir_all(&dir).unwrap();
    sky.save(&dir.join("sky.exr"), 1.0).unwrap();
}

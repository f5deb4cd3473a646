//! The loader on each dialect, written out as small datasets, and on the
//! committed Cycles training set.

use std::path::{Path, PathBuf};

use glam::DVec3;

use super::*;

/// A fresh folder for one test's dataset.
fn folder(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("inlay-dataset-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A camera-to-world matrix looking from `eye` at the origin, as rows.
fn pose_rows(eye: DVec3) -> Vec<Vec<f64>> {
    let m = Pose::looking_at(eye, DVec3::ZERO, DVec3::Y).matrix;
    (0..4).map(|r| m.row(r).to_array().to_vec()).collect()
}

fn write_png_rgba(path: &Path, w: u32, h: u32, px: impl Fn(u32, u32) -> [u8; 4]) {
    let mut bytes = Vec::new();
    for y in 0..h {
        for x in 0..w {
            bytes.extend_from_slice(&px(x, y));
        }
    }
    image::save_buffer(path, &bytes, w, h, image::ExtendedColorType::Rgba8).unwrap();
}

fn write_exr(path: &Path, w: u32, h: u32, px: impl Fn(u32, u32) -> [f32; 3]) {
    let img = inlay_engine::HdrImage {
        width: w,
        height: h,
        pixels: (0..w * h)
            .map(|i| {
                let c = px(i % w, i / w);
                [c[0], c[1], c[2], 1.0]
            })
            .collect(),
    };
    img.write_file(path, 1.0).unwrap();
}

/// The dataset in `dir`, its bad frames left out.
fn load_skipping_bad_frames(dir: &Path) -> Dataset {
    let options = LoadOptions {
        skip_bad_frames: true,
        ..LoadOptions::default()
    };
    load_dataset(dir, &options).unwrap()
}

fn eyes() -> [DVec3; 4] {
    [
        DVec3::new(3.0, 1.0, 0.0),
        DVec3::new(0.0, 1.0, 3.0),
        DVec3::new(-3.0, 1.0, 0.0),
        DVec3::new(0.0, 1.5, -3.0),
    ]
}

#[test]
fn the_committed_cycles_training_set_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/cycles/dog/training");
    let d = load_dataset(&dir, &LoadOptions::default()).unwrap();
    assert_eq!(d.dialect, Dialect::Nerfstudio);
    assert_eq!(d.frames.len(), 32);
    assert_eq!(d.bounds_source, BoundsSource::AabbKey);
    assert!((d.bounds.min - DVec3::new(-0.9, -0.1, -0.9)).length() < 1e-12);
    let f = &d.frames[0];
    assert_eq!((f.intrinsics.width, f.intrinsics.height), (96, 96));
    assert_eq!(f.intrinsics.distortion, Distortion::None);
    assert_eq!(d.counts, PixelCounts::default());
    // Every camera looks towards the field.
    for f in &d.frames {
        let to_field = (d.bounds.center() - f.pose.origin()).normalize();
        assert!(f.pose.forward().dot(to_field) > 0.8, "frame {}", f.index);
    }
}

/// Cycles draws every primitive whole, so each committed Cycles set's
/// `aabb` must hold what its photographs show: the recipe's bounds, widened
/// to CUPS' and PLANTS' walls, which reach past them (a field in the
/// recipe's bounds cannot hold their tops, and the views that see them
/// missed 30 dB by them alone).
#[test]
fn the_committed_cycles_training_sets_hold_what_their_photographs_show() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    for (name, top) in [
        ("dog", 0.9),
        ("cups", 1.1),
        ("books", 1.0),
        ("plants", 1.25),
        ("room", 1.4),
        ("dog-checker", 0.9),
    ] {
        let d = load_dataset(
            &root.join(format!("docs/cycles/{name}/training")),
            &LoadOptions::default(),
        )
        .unwrap();
        let scene = crate::scene::load_scene(&root.join(format!("scenes/{name}.toml"))).unwrap();
        let recipe = scene.recipe().unwrap();
        assert_eq!(recipe.crossing(d.bounds).len(), 0, "{name}");
        assert!(
            (d.bounds.min - recipe.bounds.min).length() < 1e-12,
            "{name}"
        );
        assert!(
            (d.bounds.max.y - top).abs() < 1e-12,
            "{name}: {:?}",
            d.bounds
        );
        let (m, r) = (d.bounds.max, recipe.bounds.max);
        assert!((m.x - r.x).abs() + (m.z - r.z).abs() < 1e-12, "{name}");
        // The same views with alpha (`--what alpha`): the same cameras and
        // box, and where a pixel is wholly the scene's, the photograph's
        // radiance (half floats: 2⁻¹¹ of it).
        let a = load_dataset(
            &root.join(format!("docs/cycles/{name}/training/alpha")),
            &LoadOptions::default(),
        )
        .unwrap();
        assert_eq!(a.bounds, d.bounds, "{name}");
        assert_eq!(a.frames.len(), d.frames.len(), "{name}");
        assert!(a.counts.transparent > 0, "{name}");
        for (fa, fd) in a.frames.iter().zip(&d.frames) {
            assert_eq!(fa.pose, fd.pose, "{name}");
            let opaque = (0..fa.image.radiance.len()).filter(|&i| fa.image.alpha_at(i) >= 1.0);
            for i in opaque {
                let (ca, cd) = (fa.image.radiance[i], fd.image.radiance[i]);
                for c in 0..3 {
                    assert!(
                        (ca[c] - cd[c]).abs() <= 1e-3 * cd[c].abs() + 1e-6,
                        "{name} frame {} pixel {i}",
                        fa.index
                    );
                }
            }
        }
    }
}

#[test]
fn blender_synthetic_frames_are_composited_and_saturation_is_a_lower_bound() {
    let dir = folder("blender");
    std::fs::create_dir_all(dir.join("train")).unwrap();
    let frames: Vec<_> = eyes()
        .iter()
        .enumerate()
        .map(|(i, e)| {
            write_png_rgba(&dir.join(format!("train/r_{i}.png")), 8, 6, |x, _| match x {
                0 => [255, 255, 255, 255],
                1 => [128, 128, 128, 0],
                2 => [188, 188, 188, 128],
                _ => [100, 150, 200, 255],
            });
            serde_json::json!({ "file_path": format!("./train/r_{i}"), "transform_matrix": pose_rows(*e) })
        })
        .collect();
    let text = serde_json::json!({ "camera_angle_x": 0.69, "frames": frames }).to_string();
    std::fs::write(dir.join("transforms_train.json"), text).unwrap();
    let bg = [0.25f32, 0.5, 0.75];
    let d = load_dataset(
        &dir,
        &LoadOptions {
            background: bg,
            ..LoadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(d.dialect, Dialect::BlenderSynthetic);
    assert_eq!(d.frames.len(), 4);
    assert_eq!(d.bounds_source, BoundsSource::Cameras);
    let f = &d.frames[0];
    let k = f.intrinsics;
    assert!((k.fx - 4.0 / (0.345f64).tan()).abs() < 1e-9 && k.fy == k.fx);
    assert_eq!((k.cx, k.cy), (4.0, 3.0));
    let img = &f.image;
    // Saturated white: a lower bound; transparent: the background; half
    // covered: the mix in linear light.
    assert_eq!(img.state[0], PixelState::LowerBound);
    assert_eq!(img.radiance[1], bg);
    let a = 128.0 / 255.0;
    let c = pixels::srgb_to_linear(188.0 / 255.0);
    for (got, b) in img.radiance[2].iter().zip(bg) {
        assert!((got - (a * c + (1.0 - a) * b)).abs() < 1e-5);
    }
    assert_eq!(d.counts.saturated, 4 * 6);
    assert_eq!(d.counts.transparent, 4 * 6 * 2);
    // The alpha is kept, so that a trainer can put another background
    // behind the pixel.
    assert_eq!(
        (img.alpha_at(0), img.alpha_at(1), img.alpha_at(2)),
        (1.0, 0.0, a)
    );
    // The cameras look at the origin from 3 m: the common view is there.
    assert!(d.bounds.center().length() < 1e-6, "{:?}", d.bounds);
}

#[test]
fn instant_ngp_exr_frames_mask_bad_pixels_and_take_aabb_scale() {
    let dir = folder("ngp");
    let mut frames = Vec::new();
    for (i, e) in eyes().iter().enumerate() {
        let name = format!("f{i}.exr");
        write_exr(&dir.join(&name), 5, 4, |x, y| match (x, y) {
            (0, 0) => [f32::NAN, 1.0, 1.0],
            (1, 0) => [1.0, -0.5, 1.0],
            (2, 0) => [f32::INFINITY, 0.0, 0.0],
            _ => [40.0, 2.0, 0.5],
        });
        let mut f = serde_json::json!({ "file_path": name, "transform_matrix": pose_rows(*e) });
        if i == 2 {
            f["fl_x"] = 9.0.into();
            f["exposure_time"] = 0.01.into();
        }
        frames.push(f);
    }
    let text = serde_json::json!({
        "fl_x": 6.0, "fl_y": 6.5, "cx": 2.4, "cy": 2.1, "w": 5, "h": 4,
        "aabb_scale": 2, "scale": 0.5, "offset": [0.5, 0.5, 0.5],
        "frames": frames
    })
    .to_string();
    std::fs::write(dir.join("transforms.json"), text).unwrap();
    let d = load_dataset(&dir, &LoadOptions::default()).unwrap();
    assert_eq!(d.dialect, Dialect::InstantNgp);
    assert_eq!(d.bounds_source, BoundsSource::NgpAabbScale);
    assert!((d.bounds.size() - DVec3::splat(4.0)).length() < 1e-12);
    assert_eq!(d.counts.non_finite, 2 * 4);
    assert_eq!(d.counts.negative, 4);
    assert_eq!(d.frames[0].image.radiance[3], [40.0, 2.0, 0.5]);
    assert_eq!(d.frames[0].image.state[0], PixelState::Masked);
    assert_eq!(
        (d.frames[0].intrinsics.fx, d.frames[2].intrinsics.fx),
        (6.0, 9.0)
    );
    assert_eq!(d.frames[2].intrinsics.fy, 6.5);
    assert_eq!(d.frames[2].exposure_time, Some(0.01));
}

/// An EXR's alpha is premultiplied (OpenEXR's convention): its radiance
/// plus 1 − alpha of the background, the alpha kept; an EXR without
/// transparent pixels keeps none; a NaN alpha masks the pixel.
#[test]
fn exr_alpha_composites_premultiplied_radiance_over_the_background() {
    let dir = folder("exr-alpha");
    let path = dir.join("a.exr");
    let pixels = vec![
        [0.5, 1.0, 2.0, 1.0],
        [0.0, 0.0, 0.0, 0.0],
        [0.2, 0.4, 0.6, 0.25],
        [1.0, 1.0, 1.0, f32::NAN],
    ];
    inlay_engine::HdrImage {
        width: 4,
        height: 1,
        pixels,
    }
    .write_file(&path, 1.0)
    .unwrap();
    let bg = [0.25f32, 0.5, 0.75];
    let img = pixels::load_image(&path, bg).unwrap();
    assert_eq!(img.radiance[0], [0.5, 1.0, 2.0]);
    assert_eq!(img.radiance[1], bg);
    for k in 0..3 {
        let want = [0.2, 0.4, 0.6][k] + 0.75 * bg[k];
        assert!(
            (img.radiance[2][k] - want).abs() < 1e-6,
            "{:?}",
            img.radiance[2]
        );
    }
    assert_eq!(img.state[3], PixelState::Masked);
    assert_eq!(
        (img.alpha_at(0), img.alpha_at(1), img.alpha_at(2)),
        (1.0, 0.0, 0.25)
    );
    assert_eq!(img.counts.transparent, 2);
    let opaque = dir.join("b.exr");
    write_exr(&opaque, 2, 1, |_, _| [1.0, 2.0, 3.0]);
    let img = pixels::load_image(&opaque, bg).unwrap();
    assert!(img.alpha.is_empty());
    assert_eq!(img.radiance[1], [1.0, 2.0, 3.0]);
}

#[test]
fn every_bad_frame_is_reported_and_can_be_skipped() {
    let dir = folder("bad");
    let mut frames = Vec::new();
    for (i, e) in eyes().iter().enumerate() {
        let name = format!("f{i}.png");
        let (w, h) = if i == 2 { (7, 6) } else { (8, 6) };
        if i != 1 {
            write_png_rgba(&dir.join(&name), w, h, |_, _| [90, 90, 90, 255]);
        }
        let mut rows = pose_rows(*e);
        if i == 3 {
            for r in rows.iter_mut().take(3) {
                r[0] *= 1.5;
            }
        }
        frames.push(serde_json::json!({ "file_path": name, "transform_matrix": rows }));
    }
    frames.push(serde_json::json!({ "file_path": "f0.png", "transform_matrix": pose_rows(DVec3::new(2.0, 2.0, 2.0)) }));
    let text = serde_json::json!({ "fl_x": 8.0, "w": 8, "h": 6, "aabb": [[-1, -1, -1], [1, 1, 1]], "frames": frames }).to_string();
    std::fs::write(dir.join("transforms.json"), text).unwrap();
    let e = load_dataset(&dir, &LoadOptions::default()).unwrap_err();
    let keys: Vec<&str> = e.frames.iter().map(|p| p.key.as_str()).collect();
    assert_eq!(keys, ["frames[1]", "frames[2]", "frames[3]"], "{e}");
    let text = e.to_string();
    assert!(
        text.contains("transforms.json: frames: 3 of 5 frames cannot be used"),
        "{text}"
    );
    assert!(text.contains("missing") && text.contains("is 7x6, the file says w = 8, h = 6"));
    assert!(text.contains("not rigid"), "{text}");
    let d = load_skipping_bad_frames(&dir);
    assert_eq!(d.frames.iter().map(|f| f.index).collect::<Vec<_>>(), [0, 4]);
    assert_eq!(d.skipped.len(), 3);
}

#[test]
fn nerfstudio_opencv_frames_are_undistorted_and_masked_and_fisheye_is_refused() {
    let dir = folder("nerfstudio");
    let mut frames = Vec::new();
    for (i, e) in eyes().iter().enumerate() {
        let name = format!("f{i}.jpg");
        let img = image::RgbImage::from_pixel(8, 6, image::Rgb([120, 60, 30]));
        img.save(dir.join(&name)).unwrap();
        let mask = format!("m{i}.png");
        image::GrayImage::from_fn(8, 6, |x, _| image::Luma([if x < 2 { 0 } else { 255 }]))
            .save(dir.join(&mask))
            .unwrap();
        frames.push(serde_json::json!({
            "file_path": name, "mask_path": mask, "transform_matrix": pose_rows(*e),
            "fl_x": 7.0, "fl_y": 7.0, "cx": 4.0, "cy": 3.0, "w": 8, "h": 6,
            "k1": -0.2, "k2": 0.03, "p1": 0.001, "p2": -0.002
        }));
    }
    let doc = serde_json::json!({ "camera_model": "OPENCV", "frames": frames });
    std::fs::write(dir.join("transforms.json"), doc.to_string()).unwrap();
    let d = load_dataset(&dir, &LoadOptions::default()).unwrap();
    assert_eq!(d.dialect, Dialect::Nerfstudio);
    assert_eq!(d.counts.masked, 4 * 2 * 6);
    let k = d.frames[0].intrinsics;
    assert!(matches!(k.distortion, Distortion::OpenCv { .. }));
    // The corner pixel's ray passes through the lens onto the corner.
    let dir0 = k.direction(0.5, 0.5).unwrap();
    let (u, v) = k.project(dir0).unwrap();
    assert!((u - 0.5).abs() < 1e-9 && (v - 0.5).abs() < 1e-9);
    let mut fisheye = doc.clone();
    fisheye["camera_model"] = "OPENCV_FISHEYE".into();
    std::fs::write(dir.join("transforms.json"), fisheye.to_string()).unwrap();
    let e = load_dataset(&dir, &LoadOptions::default()).unwrap_err();
    assert_eq!(e.key, "camera_model");
    assert!(
        e.to_string().contains("OPENCV_FISHEYE is not supported"),
        "{e}"
    );
}

/// `path`'s JPEG with an EXIF block recording `seconds` as num/den (an
/// APP1 segment after the start-of-image marker, as cameras write it).
fn add_exif(path: &Path, num: u32, den: u32) {
    add_exif_block(path, &super::exif::tests::exif_block(false, num, den));
}

/// Puts the TIFF block `block` into the JPEG at `path` as its APP1 EXIF.
fn add_exif_block(path: &Path, block: &[u8]) {
    let jpeg = std::fs::read(path).unwrap();
    assert_eq!(&jpeg[..2], &[0xFF, 0xD8]);
    let payload = [b"Exif\0\0".as_slice(), block].concat();
    let mut out = jpeg[..2].to_vec();
    out.extend_from_slice(&[0xFF, 0xE1]);
    out.extend_from_slice(&((payload.len() + 2) as u16).to_be_bytes());
    out.extend_from_slice(&payload);
    out.extend_from_slice(&jpeg[2..]);
    std::fs::write(path, out).unwrap();
}

/// Writes an 8 × 6 JPEG of one colour at `path`.
fn plain_jpeg(path: &Path) {
    image::RgbImage::from_pixel(8, 6, image::Rgb([120, 60, 30]))
        .save(path)
        .unwrap();
}

/// JPEG frames whose EXIF records their exposure time take it when the
/// file gives none (and become brackets); the file's key wins over EXIF;
/// a frame with neither has none.
#[test]
fn exposure_times_come_from_exif_where_the_file_gives_none() {
    let dir = folder("exif");
    let mut frames = Vec::new();
    for (i, e) in eyes().iter().enumerate() {
        let name = format!("f{i}.jpg");
        plain_jpeg(&dir.join(&name));
        if i < 3 {
            add_exif(&dir.join(&name), 1, [250, 60, 30][i]);
        }
        let mut f = serde_json::json!({ "file_path": name, "transform_matrix": pose_rows(*e) });
        if i == 2 {
            f["exposure_time"] = 0.5.into();
        }
        frames.push(f);
    }
    let doc = serde_json::json!({ "fl_x": 7.0, "frames": frames });
    std::fs::write(dir.join("transforms.json"), doc.to_string()).unwrap();
    let d = load_dataset(&dir, &LoadOptions::default()).unwrap();
    let got: Vec<(Option<f64>, bool)> = d
        .frames
        .iter()
        .map(|f| (f.exposure_time, f.exif_exposure.is_some()))
        .collect();
    assert_eq!(
        got,
        vec![
            (Some(0.004), true),
            (Some(1.0 / 60.0), true),
            (Some(0.5), false),
            (None, false)
        ]
    );
    assert!(crate::train::pixels::is_bracket(&d.frames[0]));
}

/// A big-endian TIFF block whose first directory records EXIF
/// orientation `o` (tag 0x0112, one SHORT).
fn orientation_block(o: u16) -> Vec<u8> {
    let mut b = b"MM\0\x2a".to_vec();
    b.extend_from_slice(&8u32.to_be_bytes());
    b.extend_from_slice(&1u16.to_be_bytes());
    for v in [0x0112u16, 3] {
        b.extend_from_slice(&v.to_be_bytes());
    }
    b.extend_from_slice(&1u32.to_be_bytes());
    b.extend_from_slice(&o.to_be_bytes());
    b.extend_from_slice(&[0, 0, 0, 0, 0, 0]);
    b
}

/// JPEG frames whose EXIF records an orientation are read as stored and
/// named in a warning; one whose stored size is the file's w and h
/// swapped, and whose orientation turns it a quarter, is reported with
/// that reason and the fix (the poses were made on the turned image).
#[test]
fn frames_with_an_exif_orientation_are_named() {
    let dir = folder("exif-orientation");
    let mut frames = Vec::new();
    for (i, e) in eyes().iter().enumerate() {
        let name = format!("f{i}.jpg");
        plain_jpeg(&dir.join(&name));
        match i {
            1 => add_exif_block(&dir.join(&name), &orientation_block(6)),
            2 => add_exif_block(&dir.join(&name), &orientation_block(3)),
            3 => add_exif_block(&dir.join(&name), &orientation_block(1)),
            _ => {}
        }
        frames.push(serde_json::json!({ "file_path": name, "transform_matrix": pose_rows(*e) }));
    }
    let doc = serde_json::json!({ "fl_x": 7.0, "w": 8, "h": 6, "frames": frames.clone() });
    std::fs::write(dir.join("transforms.json"), doc.to_string()).unwrap();
    let d = load_dataset(&dir, &LoadOptions::default()).unwrap();
    use image::metadata::Orientation;
    assert_eq!(
        d.turned_frames(),
        vec![(1, Orientation::Rotate90), (2, Orientation::Rotate180)]
    );
    let w = d.turned_frames_warning().unwrap();
    assert!(
        w.starts_with("2 of 4 frames (frame 1 first: turned 90° clockwise)")
            && w.contains("mogrify -auto-orient"),
        "{w}"
    );
    // The pixels as stored: 8 wide.
    assert_eq!(d.frames[1].intrinsics.width, 8);
    // Frame 1's entry says 6 × 8, as a viewer shows it.
    frames[1]["w"] = 6.into();
    frames[1]["h"] = 8.into();
    let doc = serde_json::json!({ "fl_x": 7.0, "w": 8, "h": 6, "frames": frames });
    std::fs::write(dir.join("transforms.json"), doc.to_string()).unwrap();
    let e = load_dataset(&dir, &LoadOptions::default()).unwrap_err();
    assert_eq!(e.frames.len(), 1, "{e}");
    assert!(
        e.frames[0].problem.contains(
            "is 8x6, the file says w = 6, h = 8: its EXIF orientation (turned 90° clockwise) \
             shows it 6x8"
        ),
        "{e}"
    );
}

/// A phone's bracket: equal times, ISO 100, 400 and 1600 in the frames'
/// EXIF, and f/2.8 against f/5.6: the exposures follow the light each
/// recorded (the median ISO and f-number the reference), not the times.
#[test]
fn exif_exposures_follow_the_iso_and_the_aperture() {
    let dir = folder("exif-iso");
    let settings = [
        (Some((56, 10)), 100),
        (Some((56, 10)), 400),
        (Some((28, 10)), 1600),
    ];
    let mut frames = Vec::new();
    for (i, (e, (f_number, iso))) in eyes().iter().zip(settings).enumerate() {
        let name = format!("f{i}.jpg");
        plain_jpeg(&dir.join(&name));
        add_exif_block(
            &dir.join(&name),
            &super::exif::tests::exif_block_with(i % 2 == 0, (1, 100), f_number, Some(iso)),
        );
        frames.push(serde_json::json!({ "file_path": name, "transform_matrix": pose_rows(*e) }));
    }
    let doc = serde_json::json!({ "fl_x": 7.0, "frames": frames });
    std::fs::write(dir.join("transforms.json"), doc.to_string()).unwrap();
    let d = load_dataset(&dir, &LoadOptions::default()).unwrap();
    let t: Vec<f64> = d.frames.iter().map(|f| f.exposure_time.unwrap()).collect();
    // References: ISO 400, f/5.6.
    let want = [0.01 / 4.0, 0.01, 0.01 * 4.0 * 4.0];
    for (got, want) in t.iter().zip(want) {
        assert!((got / want - 1.0).abs() < 1e-9, "{t:?}");
    }
}

/// Frames' depth maps (nerfstudio's `depth_file_path`) are read in the
/// file's `depth_unit_scale_factor`, a frame without one has none, and a
/// missing depth map or one of another size than its image is reported
/// with the rest of the bad frames.
#[test]
fn depth_maps_are_read_in_the_files_unit_and_bad_ones_reported() {
    let dir = folder("depth");
    let mut frames = Vec::new();
    for (i, e) in eyes().iter().enumerate() {
        let name = format!("f{i}.png");
        write_png_rgba(&dir.join(&name), 8, 6, |_, _| [90, 90, 90, 255]);
        let depth = format!("d{i}.png");
        // Pixel p records p + 1 in the file's unit; frame 2's map is 8x5.
        let h = if i == 2 { 5 } else { 6 };
        let z: Vec<f32> = (0..8 * h).map(|p| (p + 1) as f32 * 1e-3).collect();
        if i != 1 {
            let png = super::depth::depth_png(&z, 8, h, super::depth::PNG_DEPTH_UNIT);
            std::fs::write(dir.join(&depth), png).unwrap();
        }
        let mut f = serde_json::json!({ "file_path": name, "transform_matrix": pose_rows(*e) });
        if i != 3 {
            f["depth_file_path"] = depth.into();
        }
        frames.push(f);
    }
    let doc = serde_json::json!({
        "camera_model": "PINHOLE", "fl_x": 8.0, "fl_y": 8.0, "w": 8, "h": 6,
        "depth_unit_scale_factor": 0.01, "frames": frames,
    });
    std::fs::write(dir.join("transforms.json"), doc.to_string()).unwrap();
    let e = load_dataset(&dir, &LoadOptions::default()).unwrap_err();
    let keys: Vec<&str> = e.frames.iter().map(|p| p.key.as_str()).collect();
    assert_eq!(keys, ["frames[1]", "frames[2]"], "{e}");
    let text = e.to_string();
    assert!(
        text.contains("depth map") && text.contains("d1.png is missing"),
        "{text}"
    );
    assert!(text.contains("depth map is 8x5, the image 8x6"), "{text}");
    let d = load_skipping_bad_frames(&dir);
    assert_eq!(d.frames.iter().map(|f| f.index).collect::<Vec<_>>(), [0, 3]);
    // Code p + 1 at 0.01 a unit.
    assert!(
        (d.frames[0].depth[4] - 0.05).abs() < 1e-7,
        "{}",
        d.frames[0].depth[4]
    );
    assert!(d.frames[1].depth.is_empty());
    let counts = super::depth::DepthCounts::of(&d.frames);
    assert_eq!((counts.frames, counts.pixels, counts.recorded), (1, 48, 48));
}

#[test]
fn errors_in_the_file_name_the_key() {
    let dir = folder("keys");
    let cases = [
        (r#"{"frames": []}"#, "frames"),
        (
            r#"{"frames": [{"file_path": "a.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]}"#,
            "frames[0].fl_x",
        ),
        (
            r#"{"fl_x": 5, "frames": [{"file_path": "a.png", "transform_matrix": [[1,0,0]]}]}"#,
            "frames[0].transform_matrix",
        ),
        (r#"{"fl_x": "5", "frames": [{}]}"#, "fl_x"),
        (
            r#"{"camera_angle_x": 4.0, "frames": [{"file_path": "a.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]}"#,
            "frames[0].camera_angle_x",
        ),
        (
            r#"{"fl_x": 5, "frames": [{"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]}"#,
            "frames[0].file_path",
        ),
        (
            r#"{"fl_x": 5, "frames": [{"file_path": "a.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0]], "exposure_time": -1}]}"#,
            "frames[0].exposure_time",
        ),
        (
            r#"{"fl_x": 5, "depth_unit_scale_factor": 0, "frames": [{"file_path": "a.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]}"#,
            "depth_unit_scale_factor",
        ),
        (r#"[1, 2]"#, ""),
    ];
    for (text, key) in cases {
        std::fs::write(dir.join("transforms.json"), text).unwrap();
        let e = load_dataset(&dir, &LoadOptions::default()).unwrap_err();
        assert_eq!(e.key, key, "{text}: {e}");
        assert!(e.to_string().contains("transforms.json"), "{e}");
    }
    let e = load_dataset(&dir.join("nowhere"), &LoadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("no such file"), "{e}");
}

/// Poses written in OpenCV's camera convention look away from the field:
/// the read stops before any training, naming the frames and the
/// convention; one frame looking away from it is named in a warning, and
/// most frames looking away are refused unless they may be left out.
#[test]
fn poses_in_opencv_convention_are_refused_and_a_frame_looking_away_named() {
    let write = |dir: &Path, flip: &dyn Fn(usize) -> bool| {
        let mut frames = Vec::new();
        for (i, e) in eyes().iter().enumerate() {
            let name = format!("f{i}.exr");
            write_exr(&dir.join(&name), 8, 6, |_, _| [0.5, 0.4, 0.3]);
            let mut rows = pose_rows(*e);
            if flip(i) {
                for r in rows.iter_mut().take(3) {
                    r[1] = -r[1];
                    r[2] = -r[2];
                }
            }
            frames.push(serde_json::json!({ "file_path": name, "transform_matrix": rows }));
        }
        let text = serde_json::json!({
            "camera_angle_x": 0.8, "aabb": [[-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]],
            "frames": frames
        });
        std::fs::write(dir.join("transforms.json"), text.to_string()).unwrap();
    };
    let dir = folder("opencv");
    write(&dir, &|_| true);
    let e = load_dataset(&dir, &LoadOptions::default()).unwrap_err();
    assert_eq!(e.key, "frames");
    assert!(
        e.message.contains("4 of the 4 frames' cameras see none")
            && e.message.contains("4 would see them read in OpenCV's"),
        "{e}"
    );
    // Without an `aabb` the bounds are the cameras' common view, and the
    // error says what that means for cameras looking out from inside.
    let file = dir.join("transforms.json");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    json.as_object_mut().unwrap().remove("aabb");
    std::fs::write(&file, json.to_string()).unwrap();
    let e = load_dataset(&dir, &LoadOptions::default()).unwrap_err();
    assert!(e.message.contains("from the cameras' common view"), "{e}");
    assert!(e.message.contains("look out from inside the scene"), "{e}");
    let dir = folder("one-away");
    write(&dir, &|i| i == 1);
    let d = load_dataset(&dir, &LoadOptions::default()).unwrap();
    assert_eq!(d.blind_frames(), vec![1]);
    let w = d.blind_frames_warning().unwrap();
    assert!(w.starts_with("frames 1 (1 of 4) see none"), "{w}");
    // Three of four looking away: refused, unless the frames that see
    // none may be left out.
    let dir = folder("three-away");
    write(&dir, &|i| i != 2);
    let e = load_dataset(&dir, &LoadOptions::default()).unwrap_err();
    assert!(
        e.message.contains("3 of the 4 frames' cameras see none")
            && e.message
                .contains("--skip-bad-frames trains on those that see them"),
        "{e}"
    );
    let d = load_skipping_bad_frames(&dir);
    assert_eq!(d.frames.len(), 1);
    assert_eq!(d.frames[0].index, 2);
    let skipped: Vec<usize> = d.skipped.iter().map(|p| p.index).collect();
    assert_eq!(skipped, vec![0, 1, 3]);
    assert!(d.skipped[0]
        .problem
        .contains("sees none of the field's bounds"));
    let dir = folder("all-see");
    write(&dir, &|_| false);
    let d = load_dataset(&dir, &LoadOptions::default()).unwrap();
    assert_eq!(d.blind_frames_warning(), None);
}

/// Frames whose every usable pixel is black are named (a lit pixel that is
/// masked does not count), and a set of lit frames has none.
#[test]
fn frames_that_record_no_light_are_named() {
    let dir = folder("dark-frames");
    let frames: Vec<_> = eyes()
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let name = format!("f{i}.exr");
            write_exr(&dir.join(&name), 8, 6, |x, y| match (i, x, y) {
                (0, 3, 2) => [0.0, 0.2, 0.0],
                (2, 1, 1) => [f32::NAN, 5.0, 5.0],
                (1 | 2, _, _) => [0.0; 3],
                _ => [0.5, 0.4, 0.3],
            });
            serde_json::json!({ "file_path": name, "transform_matrix": pose_rows(*e) })
        })
        .collect();
    let doc = serde_json::json!({ "fl_x": 7.0, "w": 8, "h": 6, "frames": frames });
    std::fs::write(dir.join("transforms.json"), doc.to_string()).unwrap();
    let d = load_dataset(&dir, &LoadOptions::default()).unwrap();
    assert!(d.records_light());
    assert_eq!(d.dark_frames(), vec![1, 2]);
    let w = d.dark_frames_warning().unwrap();
    assert!(w.starts_with("frames 1, 2 (2 of 4) record no light"), "{w}");
    for i in [1, 2] {
        write_exr(&dir.join(format!("f{i}.exr")), 8, 6, |_, _| [0.1; 3]);
    }
    let d = load_dataset(&dir, &LoadOptions::default()).unwrap();
    assert_eq!(d.dark_frames_warning(), None);
}

/// `--downscale 2` reads each 2 × 2 block as one pixel, its mean, with the
/// intrinsics scaled to match (its rays those through the blocks' centres
/// at full size) and its depth map reduced alike; a factor the images are
/// smaller than is reported with the frames; a dataset too large for the
/// memory given is refused before any pixel is read, naming the factor
/// that fits.
#[test]
fn downscale_reads_blocks_and_photographs_past_the_memory_are_refused() {
    let dir = folder("downscale");
    let mut frames = Vec::new();
    for (i, e) in eyes().iter().enumerate() {
        let name = format!("f{i}.exr");
        write_exr(&dir.join(&name), 9, 6, |x, y| {
            [(x + 10 * y) as f32, 1.0, 2.0]
        });
        let z: Vec<f32> = (0..54).map(|p| 4.0 + (p % 9) as f32 * 0.01).collect();
        std::fs::write(
            dir.join(format!("d{i}.png")),
            depth::depth_png(&z, 9, 6, 0.001),
        )
        .unwrap();
        frames.push(serde_json::json!({
            "file_path": name, "depth_file_path": format!("d{i}.png"),
            "transform_matrix": pose_rows(*e)
        }));
    }
    let text = serde_json::json!({
        "camera_model": "OPENCV", "fl_x": 8.0, "fl_y": 8.5, "cx": 4.3, "cy": 2.9,
        "k1": -0.05, "k2": 0.01, "p1": 0.0, "p2": 0.0,
        "aabb": [[-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]], "frames": frames
    });
    std::fs::write(dir.join("transforms.json"), text.to_string()).unwrap();
    let full = load_dataset(&dir, &LoadOptions::default()).unwrap();
    let options = LoadOptions {
        downscale: 2,
        ..LoadOptions::default()
    };
    let half = load_dataset(&dir, &options).unwrap();
    let (f, h) = (&full.frames[1], &half.frames[1]);
    assert_eq!((h.image.width, h.image.height), (4, 3));
    assert_eq!((h.intrinsics.fx, h.intrinsics.cx), (4.0, 2.15));
    // Block (1, 2): pixels (2..4, 4..6) of the original.
    assert_eq!(h.image.radiance[2 * 4 + 1], [47.5, 1.0, 2.0]);
    let ray = |fr: &Frame, u: f64, v: f64| fr.pose.to_world(fr.intrinsics.direction(u, v).unwrap());
    assert!((ray(h, 1.5, 2.5) - ray(f, 3.0, 5.0)).length() < 1e-12);
    // The depth: the block's median (4.02 or 4.03 mm-rounded), in metres.
    assert!((h.depth[2 * 4 + 1] - 4.03).abs() < 1e-3, "{}", h.depth[9]);
    let tiny = LoadOptions {
        downscale: 7,
        ..LoadOptions::default()
    };
    let e = load_dataset(&dir, &tiny).unwrap_err();
    assert!(e.to_string().contains("smaller than --downscale 7"), "{e}");
    let e = load_dataset(
        &dir,
        &LoadOptions {
            downscale: 0,
            ..LoadOptions::default()
        },
    )
    .unwrap_err();
    assert_eq!(e.key, "--downscale");
    // 4 frames of 54 pixels hold 6912 bytes, and each reading thread
    // decodes one at full size (2160 bytes). With one thread 8000 bytes
    // leave half free at --downscale 2 (1728 + 2160).
    let in_threads = |threads: usize, options: &LoadOptions| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| load_dataset(&dir, options))
    };
    let tight = LoadOptions {
        memory_available: Some(8000),
        ..LoadOptions::default()
    };
    let e = in_threads(1, &tight).unwrap_err();
    assert_eq!(e.key, "frames");
    assert!(
        e.message.contains("216 pixels") && e.message.contains("--downscale 2 "),
        "{e}"
    );
    // Two threads decoding at once need 4320 bytes whatever the
    // downscale: one thread is what fits.
    let e = in_threads(2, &tight).unwrap_err();
    assert!(
        e.message
            .contains("RAYON_NUM_THREADS=1 with --downscale 2 fits"),
        "{e}"
    );
    let fits = LoadOptions {
        memory_available: Some(8000),
        downscale: 2,
        ..LoadOptions::default()
    };
    assert!(in_threads(1, &fits).is_ok());
}

//! Posed photographs as users have them: a `transforms.json` in one of its
//! three common dialects, read into frames of linear radiance with a pose,
//! intrinsics (with the lens' distortion inverted exactly) and what each
//! pixel can tell a trainer.
//!
//! - **Blender synthetic** (the NeRF paper's datasets): a folder with
//!   `transforms_{train,val,test}.json`, `camera_angle_x`, paths without an
//!   extension (`.png` added), RGBA PNGs composited over a stated
//!   background.
//! - **instant-ngp**: one `transforms.json`; `fl_x`/`fl_y`/`cx`/`cy`/`w`/`h`
//!   or `camera_angle_x`/`camera_angle_y`, globally or per frame;
//!   `k1`/`k2`/`p1`/`p2`; `aabb_scale` with `scale` and `offset`; EXR frames
//!   as linear HDR.
//! - **nerfstudio**: `camera_model` PINHOLE or OPENCV (k1, k2, p1, p2,
//!   undistorted exactly); per-frame intrinsics; `mask_path`. Fisheye and
//!   other models are refused with a message that says so.
//!
//! In every dialect: an `aabb` key (`[[min], [max]]`, world units) gives the
//! field's bounds, a frame's `exposure_time` (seconds) is kept for
//! exposure brackets, and a frame's `depth_file_path` names its depth map
//! (nerfstudio's key; z-depths, [`depth`], in units of the file's
//! `depth_unit_scale_factor`). Poses are camera-to-world in the OpenGL convention
//! (x right, y up, looking along −z) and must be rigid. Frames whose image
//! is missing, unreadable or of the wrong size, or whose pose is not rigid,
//! are all reported together; NaN, infinite and negative pixels are masked
//! and counted, saturated LDR pixels kept as lower bounds.
//! Cameras that see none of the field's bounds are named, and a dataset
//! whose cameras look away from them is refused ([`sight`]).

pub mod bounds;
pub mod capture;
pub mod depth;
pub mod downscale;
pub mod exif;
pub mod intrinsics;
mod json;
pub mod memory;
pub mod pixels;
pub mod pose;
pub mod sight;

use std::path::{Path, PathBuf};

use rayon::prelude::*;

pub use bounds::BoundsSource;
pub use intrinsics::{Distortion, Intrinsics};
pub use pixels::{FrameImage, PixelCounts, PixelState};
pub use pose::Pose;

use crate::geometry::Aabb;
use json::Obj;

/// The dialects of `transforms.json`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dialect {
    /// The NeRF paper's Blender synthetic scenes.
    BlenderSynthetic,
    /// instant-ngp's.
    InstantNgp,
    /// nerfstudio's.
    Nerfstudio,
}

impl std::fmt::Display for Dialect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Dialect::BlenderSynthetic => "Blender synthetic",
            Dialect::InstantNgp => "instant-ngp",
            Dialect::Nerfstudio => "nerfstudio",
        })
    }
}

/// How to read a dataset.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadOptions {
    /// The field's bounds, overriding the file's.
    pub bounds: Option<Aabb>,
    /// Linear RGB that transparent pixels of RGBA images are composited
    /// over (the Blender synthetic scenes are usually trained on white).
    pub background: [f32; 3],
    /// Which Blender synthetic split to read (`train`, `val`, `test`).
    pub split: String,
    /// Leave out the frames that cannot be used (reported) instead of
    /// failing.
    pub skip_bad_frames: bool,
    /// Read each image at 1/n of its width and height ([`downscale`]); 1
    /// reads it as it is.
    pub downscale: u32,
    /// The memory the photographs may hold once read, in bytes: a dataset
    /// that would hold more is refused before any pixel is read
    /// ([`memory`]). None reads it whatever it holds.
    pub memory_available: Option<u64>,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            bounds: None,
            background: [1.0; 3],
            split: "train".into(),
            skip_bad_frames: false,
            downscale: 1,
            memory_available: None,
        }
    }
}

/// One posed photograph.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Its index among the file's frames.
    pub index: usize,
    /// The image file.
    pub image_path: PathBuf,
    /// Where the camera was.
    pub pose: Pose,
    /// The camera's intrinsics.
    pub intrinsics: Intrinsics,
    /// Exposure time in seconds, where given (`exposure_time`), else
    /// where an LDR image's EXIF block records it: then its time scaled
    /// by its ISO and f-number against the dataset's
    /// ([`exif::relative_exposure`]).
    pub exposure_time: Option<f64>,
    /// What the image's EXIF block records, where [`Self::exposure_time`]
    /// came from there.
    pub exif_exposure: Option<exif::ExifExposure>,
    /// Its pixels.
    pub image: FrameImage,
    /// Its depth map, where it has one (`depth_file_path`): each pixel's
    /// z-depth (distance along the camera's viewing direction) in the
    /// scene's units, 0 where it records nothing ([`depth`]); empty where
    /// the frame has none.
    pub depth: Vec<f32>,
}

/// A frame that cannot be used, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameProblem {
    /// Its index among the file's frames.
    pub index: usize,
    /// The key path of the frame (`frames[3]`).
    pub key: String,
    /// What is wrong.
    pub problem: String,
}

/// A dataset read whole.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    /// The `transforms.json` read.
    pub file: PathBuf,
    /// Its dialect.
    pub dialect: Dialect,
    /// The usable frames.
    pub frames: Vec<Frame>,
    /// The field's bounds.
    pub bounds: Aabb,
    /// Where the bounds came from.
    pub bounds_source: BoundsSource,
    /// The pixels that are not values, over all frames.
    pub counts: PixelCounts,
    /// Frames left out (with [`LoadOptions::skip_bad_frames`]).
    pub skipped: Vec<FrameProblem>,
}

impl Dataset {
    /// The file's indices of the frames whose cameras see none of the
    /// bounds ([`sight::sees_bounds`]): they teach the field nothing, only
    /// what lies past it.
    pub fn blind_frames(&self) -> Vec<usize> {
        self.frames_where(|f| !sight::sees_bounds(&f.pose, &f.intrinsics, &self.bounds))
    }

    /// A warning naming the frames that see none of the bounds, if any do.
    pub fn blind_frames_warning(&self) -> Option<String> {
        self.frames_warning(
            &self.blind_frames(),
            "see none of the field's bounds: they teach only the light past them",
        )
    }

    /// Whether any usable pixel of any frame records light (a channel
    /// above 0): photographs that record none teach an empty field.
    pub fn records_light(&self) -> bool {
        self.frames.iter().any(|f| f.image.records_light())
    }

    /// The file's indices of the frames none of whose usable pixels records
    /// light.
    pub fn dark_frames(&self) -> Vec<usize> {
        self.frames_where(|f| !f.image.records_light())
    }

    /// A warning naming the frames that record no light, if any do: each
    /// teaches that its cameras see nothing.
    pub fn dark_frames_warning(&self) -> Option<String> {
        self.frames_warning(
            &self.dark_frames(),
            "record no light (every usable pixel black): each teaches that nothing lies \
             in its view (a covered lens, images written in other units, or an \
             exposure_time that reads them as none?); a short exposure bracket may be black \
             where nothing is bright",
        )
    }

    /// The file's indices of the frames `keep` holds for.
    fn frames_where(&self, keep: impl Fn(&Frame) -> bool) -> Vec<usize> {
        self.frames
            .iter()
            .filter(|f| keep(f))
            .map(|f| f.index)
            .collect()
    }

    /// "frames 3, 7 (2 of 40) `what`", where any frames are named.
    fn frames_warning(&self, indices: &[usize], what: &str) -> Option<String> {
        (!indices.is_empty()).then(|| format!("{} {what}", self.frame_list(indices)))
    }

    /// "frames 3, 7 (2 of 40)": up to eight of `indices` by name.
    fn frame_list(&self, indices: &[usize]) -> String {
        let list: Vec<String> = indices.iter().take(8).map(|i| i.to_string()).collect();
        let more = if indices.len() > list.len() {
            ", …"
        } else {
            ""
        };
        format!(
            "frames {}{more} ({} of {})",
            list.join(", "),
            indices.len(),
            self.frames.len()
        )
    }

    /// The file's indices of the frames whose images record an EXIF
    /// orientation other than upright ([`exif::orientation_of`]), with it.
    pub fn turned_frames(&self) -> Vec<(usize, image::metadata::Orientation)> {
        self.frames
            .iter()
            .filter_map(|f| exif::orientation_of(&f.image_path).map(|o| (f.index, o)))
            .collect()
    }

    /// A warning naming the frames whose images record an EXIF orientation,
    /// if any do: their pixels are read as stored, and poses made on the
    /// images as a viewer shows them would not match.
    pub fn turned_frames_warning(&self) -> Option<String> {
        let turned = self.turned_frames();
        let (first, o) = *turned.first()?;
        Some(format!(
            "{} of {} frames (frame {first} first: {}) record an EXIF orientation that a \
             viewer applies; their pixels are read as stored, as COLMAP, instant-ngp and \
             nerfstudio read them. Poses made on the images as a viewer shows them would not \
             match: turn the pixels and clear the tag (`exiftran -ai`, `mogrify -auto-orient`) \
             and make the poses again",
            turned.len(),
            self.frames.len(),
            exif::orientation_words(o)
        ))
    }

    /// The frames [`LoadOptions::skip_bad_frames`] left out, a line each
    /// under a heading, if any were.
    pub fn skipped_report(&self) -> Option<String> {
        (!self.skipped.is_empty()).then(|| {
            let mut r = format!(
                "{} frames left out (--skip-bad-frames):",
                self.skipped.len()
            );
            for p in &self.skipped {
                r.push_str(&format!("\n  {}: {}", p.key, p.problem));
            }
            r
        })
    }
}

/// Why a dataset cannot be read: the file, the key and what is wrong, and
/// every frame that cannot be used.
#[derive(Debug, Clone, PartialEq)]
pub struct DatasetError {
    /// The file.
    pub file: PathBuf,
    /// The key path ("" for the file as a whole).
    pub key: String,
    /// What is wrong.
    pub message: String,
    /// The frames that cannot be used, all of them.
    pub frames: Vec<FrameProblem>,
}

impl DatasetError {
    /// An error at `key` of `file`.
    pub fn at(file: &Path, key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            file: file.to_path_buf(),
            key: key.into(),
            message: message.into(),
            frames: Vec::new(),
        }
    }
}

impl std::fmt::Display for DatasetError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.file.display())?;
        if !self.key.is_empty() {
            write!(f, ": {}", self.key)?;
        }
        write!(f, ": {}", self.message)?;
        for p in &self.frames {
            write!(f, "\n  {}: {}", p.key, p.problem)?;
        }
        Ok(())
    }
}

impl std::error::Error for DatasetError {}

/// The `transforms.json` that `path` names: the file itself, or in a
/// folder `transforms.json`, else `transforms_<split>.json`.
pub fn transforms_file(path: &Path, split: &str) -> Result<PathBuf, DatasetError> {
    if path.is_file() {
        return Ok(path.to_path_buf());
    }
    if !path.is_dir() {
        return Err(DatasetError::at(path, "", "no such file or folder"));
    }
    let plain = path.join("transforms.json");
    if plain.is_file() {
        return Ok(plain);
    }
    let split_file = path.join(format!("transforms_{split}.json"));
    if split_file.is_file() {
        return Ok(split_file);
    }
    Err(DatasetError::at(
        path,
        "",
        format!("holds neither transforms.json nor transforms_{split}.json"),
    ))
}

/// Reads the dataset at `path` (a `transforms.json`, or a folder holding
/// one).
pub fn load_dataset(path: &Path, options: &LoadOptions) -> Result<Dataset, DatasetError> {
    let Transforms {
        file,
        map,
        dialect,
        specs,
    } = read_transforms(path, &options.split)?;
    let top = Obj {
        map: &map,
        file: &file,
        at: "",
    };
    let n = options.downscale;
    if !(1..=downscale::MAX_DOWNSCALE).contains(&n) {
        return Err(top.error(
            "--downscale",
            format!("{n}: must be 1 to {}", downscale::MAX_DOWNSCALE),
        ));
    }
    // The cameras from the images' headers alone, so that the bounds, the
    // cameras' sight of them and the memory the pixels will hold are
    // checked before any pixel is read (a frame that cannot be used is
    // reported with the others below).
    let headers: Vec<Result<FrameCamera, String>> =
        specs.par_iter().map(|s| frame_camera(s, options)).collect();
    let cameras: Vec<(usize, Pose, Intrinsics)> = headers
        .iter()
        .enumerate()
        .filter_map(|(i, c)| c.as_ref().ok().map(|(p, _, k)| (i, *p, *k)))
        .collect();
    // With no usable camera, the frames' problems are the error (below).
    let mut problems = Vec::new();
    let mut blind = Vec::new();
    let checked = if cameras.is_empty() {
        None
    } else {
        let poses: Vec<(Pose, Intrinsics)> = cameras.iter().map(|(_, p, k)| (*p, *k)).collect();
        let (bounds, source) = dataset_bounds(top, dialect, &poses, options)?;
        let sight = sight::Sight::of(poses.iter().map(|(p, k)| (p, k)), &bounds);
        if let Some(p) = sight.problem() {
            // Under --skip-bad-frames the frames that see none are left
            // out, as long as one sees them.
            if !options.skip_bad_frames || sight.blind.len() == cameras.len() {
                let (lo, hi) = (bounds.min, bounds.max);
                return Err(top.error(
                    "frames",
                    format!(
                        "{p} (bounds {:.3} {:.3} {:.3} to {:.3} {:.3} {:.3}, from {source}){}{}",
                        lo.x,
                        lo.y,
                        lo.z,
                        hi.x,
                        hi.y,
                        hi.z,
                        if sight.blind.len() < cameras.len() {
                            "; --skip-bad-frames trains on those that see them"
                        } else {
                            ""
                        },
                        if source == BoundsSource::Cameras {
                            ". With no `aabb`, the bounds lie where the cameras' optical axes \
                             meet, which for cameras that look out from inside the scene (a \
                             room photographed from its middle) is behind them: give the \
                             bounds (`aabb`, --bounds)"
                        } else {
                            ""
                        }
                    ),
                ));
            }
            blind = sight.blind.iter().map(|&b| cameras[b].0).collect();
        }
        Some((bounds, source))
    };
    if let Some(available) = options.memory_available {
        let sizes: Vec<u64> = cameras
            .iter()
            .filter(|(i, _, _)| !blind.contains(i))
            .map(|(_, _, k)| k.width as u64 * k.height as u64)
            .collect();
        let photos = memory::PhotoSizes {
            pixels: sizes.iter().sum(),
            largest: sizes.iter().copied().max().unwrap_or(0),
            readers: rayon::current_num_threads().min(sizes.len()) as u64,
        };
        if let Some(p) = memory::problem(photos, n, available) {
            return Err(top.error("frames", p));
        }
    }
    let mut read = Vec::with_capacity(specs.len());
    for (i, (s, camera)) in specs.into_iter().zip(headers).enumerate() {
        if blind.contains(&i) {
            problems.push(FrameProblem {
                index: s.index,
                key: s.key,
                problem: "its camera sees none of the field's bounds".into(),
            });
        } else {
            read.push((s, camera));
        }
    }
    let results: Vec<Result<Frame, FrameProblem>> = read
        .into_par_iter()
        .map(|(s, camera)| read_frame(s, camera, options))
        .collect();
    let mut frames = Vec::new();
    for r in results {
        match r {
            Ok(f) => frames.push(f),
            Err(p) => problems.push(p),
        }
    }
    problems.sort_by_key(|p| p.index);
    if !problems.is_empty() && (!options.skip_bad_frames || frames.is_empty()) {
        let n = problems.len();
        let mut e = top.error(
            "frames",
            format!(
                "{n} of {} frames cannot be used{}",
                n + frames.len(),
                if frames.is_empty() {
                    ""
                } else {
                    " (--skip-bad-frames trains on the rest)"
                }
            ),
        );
        e.frames = problems;
        return Err(e);
    }
    // Exposures read from EXIF, in seconds at the dataset's ISO and
    // aperture: a bracket that varies the ISO with the time.
    let from_exif: Vec<usize> = (0..frames.len())
        .filter(|&i| frames[i].exif_exposure.is_some())
        .collect();
    let exposures: Vec<exif::ExifExposure> = from_exif
        .iter()
        .filter_map(|&i| frames[i].exif_exposure)
        .collect();
    for (&i, e) in from_exif.iter().zip(exif::relative_exposure(&exposures)) {
        frames[i].exposure_time = Some(e);
    }
    let Some((bounds, bounds_source)) = checked else {
        return Err(top.error("frames", "no frame can be used"));
    };
    let mut counts = PixelCounts::default();
    for f in &frames {
        counts += f.image.counts;
    }
    Ok(Dataset {
        file,
        dialect,
        frames,
        bounds,
        bounds_source,
        counts,
        skipped: problems,
    })
}

/// A `transforms.json` read and its frames' keys checked: the file, its
/// top-level object, its dialect and each frame's spec (errors in the file
/// stop everything; problems with frames travel in the specs).
struct Transforms {
    file: PathBuf,
    map: serde_json::Map<String, serde_json::Value>,
    dialect: Dialect,
    specs: Vec<FrameSpec>,
}

/// Reads the `transforms.json` `path` names ([`transforms_file`]).
fn read_transforms(path: &Path, split: &str) -> Result<Transforms, DatasetError> {
    let file = transforms_file(path, split)?;
    let text = std::fs::read_to_string(&file)
        .map_err(|e| DatasetError::at(&file, "", format!("unreadable: {e}")))?;
    let map = json::parse_object(&file, &text)?;
    let top = Obj {
        map: &map,
        file: &file,
        at: "",
    };
    let dialect = dialect_of(&file, top)?;
    let folder = file.parent().unwrap_or(Path::new(".")).to_path_buf();
    let frames = map
        .get("frames")
        .and_then(|v| v.as_array())
        .ok_or_else(|| top.error("frames", "expected a list of frames"))?;
    if frames.is_empty() {
        return Err(top.error("frames", "no frames"));
    }
    let mut specs = Vec::with_capacity(frames.len());
    for (i, v) in frames.iter().enumerate() {
        let key = format!("frames[{i}]");
        let Some(m) = v.as_object() else {
            return Err(top.error(&key, "expected an object"));
        };
        let obj = Obj {
            map: m,
            file: &file,
            at: &key,
        };
        specs.push(frame_spec(i, top, obj, dialect, &folder)?);
    }
    Ok(Transforms {
        file,
        map,
        dialect,
        specs,
    })
}

/// The cameras of the dataset at `path`, one per frame (its image's file
/// stem as its name), without reading any pixels (an image's header gives
/// its size where the file does not). Every frame must be usable.
pub fn load_cameras(
    path: &Path,
    split: &str,
) -> Result<Vec<(String, Pose, Intrinsics)>, DatasetError> {
    let Transforms {
        file, map, specs, ..
    } = read_transforms(path, split)?;
    let top = Obj {
        map: &map,
        file: &file,
        at: "",
    };
    let total = specs.len();
    let mut out = Vec::with_capacity(total);
    let mut problems = Vec::new();
    for s in specs {
        let (i, key) = (s.index, s.key.clone());
        let fail = |problem: String| FrameProblem {
            index: i,
            key: key.clone(),
            problem,
        };
        let camera = (|| {
            let pose = s.pose.clone()?;
            let image = s.image.clone()?;
            let (w, h) = match s.camera.size {
                [Some(w), Some(h)] if w >= 1.0 && h >= 1.0 => (w as u32, h as u32),
                _ => pixels::image_size(&image).map_err(|e| format!("{}: {e}", image.display()))?,
            };
            let k = intrinsics_for(&s.camera, w, h);
            if let Some(p) = k.problem() {
                return Err(p);
            }
            let name = image
                .file_stem()
                .and_then(|n| n.to_str())
                .unwrap_or("frame")
                .to_string();
            Ok((name, pose, k))
        })();
        match camera {
            Ok(c) => out.push(c),
            Err(p) => problems.push(fail(p)),
        }
    }
    if !problems.is_empty() {
        let mut e = top.error(
            "frames",
            format!(
                "{} of {} frames' cameras cannot be used",
                problems.len(),
                total
            ),
        );
        e.frames = problems;
        return Err(e);
    }
    Ok(out)
}

/// A dataset camera as a scene camera.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneCamera {
    /// Its pose, and the vertical field of view of its focal length.
    pub spec: crate::camera::CameraSpec,
    /// Its principal point is more than a pixel off the image's centre
    /// (a scene camera is centred, so its view is shifted by that much).
    pub off_centre: bool,
    /// Its image's size in pixels (width, height).
    pub size: (u32, u32),
}

/// The cameras of the dataset at `path` as scene cameras, one per frame
/// ([`load_cameras`]).
pub fn scene_cameras(path: &Path, split: &str) -> Result<Vec<SceneCamera>, DatasetError> {
    Ok(load_cameras(path, split)?
        .into_iter()
        .map(|(name, pose, k)| SceneCamera {
            off_centre: (k.cx - 0.5 * k.width as f64).abs() > 1.0
                || (k.cy - 0.5 * k.height as f64).abs() > 1.0,
            size: (k.width, k.height),
            spec: crate::camera::CameraSpec {
                name: Some(name),
                position: pose.origin(),
                look_at: pose.origin() + pose.forward(),
                up: pose.to_world(glam::DVec3::Y),
                fov_y: 2.0 * (0.5 * k.height as f64 / k.fy).atan().to_degrees(),
            },
        })
        .collect())
}

/// Which dialect the file is in.
fn dialect_of(file: &Path, top: Obj) -> Result<Dialect, DatasetError> {
    if let Some(model) = top.string("camera_model")? {
        return match model {
            "PINHOLE" | "OPENCV" => Ok(Dialect::Nerfstudio),
            other => Err(top.error(
                "camera_model",
                format!(
                    "{other} is not supported: only PINHOLE and OPENCV (k1, k2, p1, p2) are; \
                     undistort fisheye or other images to a pinhole first (e.g. COLMAP's image_undistorter)"
                ),
            )),
        };
    }
    let name = file.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let blender_name = name.starts_with("transforms_") && name.ends_with(".json");
    if blender_name && top.has("camera_angle_x") && !top.has("fl_x") {
        return Ok(Dialect::BlenderSynthetic);
    }
    Ok(Dialect::InstantNgp)
}

/// What a frame's keys say, before its image is read.
struct FrameSpec {
    index: usize,
    key: String,
    pose: Result<Pose, String>,
    image: Result<PathBuf, String>,
    mask: Option<PathBuf>,
    /// The depth map and the file's `depth_unit_scale_factor`.
    depth: Option<(PathBuf, Option<f64>)>,
    exposure_time: Option<f64>,
    camera: CameraKeys,
}

/// The intrinsics keys a frame sees (its own over the file's).
#[derive(Debug, Clone, Copy)]
struct CameraKeys {
    fl: [Option<f64>; 2],
    angle: [Option<f64>; 2],
    centre: [Option<f64>; 2],
    size: [Option<f64>; 2],
    distortion: Distortion,
}

fn frame_spec(
    index: usize,
    top: Obj,
    obj: Obj,
    dialect: Dialect,
    folder: &Path,
) -> Result<FrameSpec, DatasetError> {
    let pick = |key: &str| -> Result<Option<f64>, DatasetError> {
        Ok(obj.number(key)?.or(top.number(key)?))
    };
    let camera = CameraKeys {
        fl: [pick("fl_x")?, pick("fl_y")?],
        angle: [pick("camera_angle_x")?, pick("camera_angle_y")?],
        centre: [pick("cx")?, pick("cy")?],
        size: [pick("w")?, pick("h")?],
        distortion: {
            let k = [pick("k1")?, pick("k2")?, pick("p1")?, pick("p2")?].map(|v| v.unwrap_or(0.0));
            let pinhole = dialect == Dialect::BlenderSynthetic
                || top.string("camera_model")? == Some("PINHOLE");
            if pinhole || k.iter().all(|&v| v == 0.0) {
                Distortion::None
            } else {
                Distortion::OpenCv {
                    k1: k[0],
                    k2: k[1],
                    p1: k[2],
                    p2: k[3],
                }
            }
        },
    };
    if camera.fl[0].is_none() && camera.angle[0].is_none() {
        return Err(obj.error(
            "fl_x",
            "no focal length: give fl_x (pixels) or camera_angle_x (radians), for the file or the frame",
        ));
    }
    for (k, v) in [
        ("camera_angle_x", camera.angle[0]),
        ("camera_angle_y", camera.angle[1]),
    ] {
        if v.is_some_and(|a| !(a > 0.0 && a < std::f64::consts::PI)) {
            return Err(obj.error(k, "must be in (0, π) radians"));
        }
    }
    let path = obj
        .string("file_path")?
        .ok_or_else(|| obj.error("file_path", "missing"))?;
    let matrix = obj
        .matrix("transform_matrix")?
        .ok_or_else(|| obj.error("transform_matrix", "missing"))?;
    let exposure_time = obj.number("exposure_time")?;
    if exposure_time.is_some_and(|t| t <= 0.0) {
        return Err(obj.error("exposure_time", "must be positive (seconds)"));
    }
    let mask = obj.string("mask_path")?.map(|m| folder.join(m));
    let unit = top.number("depth_unit_scale_factor")?;
    if unit.is_some_and(|u| !(u > 0.0 && u.is_finite())) {
        return Err(top.error(
            "depth_unit_scale_factor",
            "must be a positive number (the depth maps' unit in the scene's units)",
        ));
    }
    let depth = obj
        .string("depth_file_path")?
        .map(|d| (folder.join(d), unit));
    Ok(FrameSpec {
        index,
        key: obj.at.to_string(),
        pose: Pose::new(matrix).map_err(|e| format!("transform_matrix is not rigid: {e}")),
        image: image_file(folder, path),
        mask,
        depth,
        exposure_time,
        camera,
    })
}

/// The image a `file_path` names: as written, or with `.png`, `.exr`,
/// `.jpg` or `.jpeg` added when it has no extension (the Blender synthetic
/// scenes leave it out).
fn image_file(folder: &Path, path: &str) -> Result<PathBuf, String> {
    let p = folder.join(path);
    if p.extension().is_some() {
        return if p.is_file() {
            Ok(p)
        } else {
            Err(format!("image {} is missing", p.display()))
        };
    }
    for ext in ["png", "exr", "jpg", "jpeg"] {
        let q = p.with_extension(ext);
        if q.is_file() {
            return Ok(q);
        }
    }
    Err(format!(
        "image {}(.png|.exr|.jpg|.jpeg) is missing",
        p.display()
    ))
}

/// A frame's pose, image and intrinsics at full size.
type FrameCamera = (Pose, PathBuf, Intrinsics);

/// A frame's camera as its image's header gives it, or why it cannot be
/// used.
fn frame_camera(s: &FrameSpec, options: &LoadOptions) -> Result<FrameCamera, String> {
    let pose = s.pose.clone()?;
    let path = s.image.clone()?;
    let (w, h) = pixels::image_size(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    if let [Some(fw), Some(fh)] = s.camera.size {
        if (fw, fh) != (w as f64, h as f64) {
            let turned = exif::orientation_of(&path)
                .filter(|o| exif::turns_quarter(*o) && (fw, fh) == (h as f64, w as f64));
            return Err(format!(
                "{} is {w}x{h}, the file says w = {fw}, h = {fh}{}",
                path.display(),
                match turned {
                    Some(o) => format!(
                        ": its EXIF orientation ({}) shows it {h}x{w}, so the poses were made \
                         on it as a viewer shows it; turn its pixels and clear the tag \
                         (`exiftran -ai`, `mogrify -auto-orient`)",
                        exif::orientation_words(o)
                    ),
                    None => String::new(),
                }
            ));
        }
    }
    let intrinsics = intrinsics_for(&s.camera, w, h);
    if let Some(p) = intrinsics.problem() {
        return Err(p);
    }
    if w < options.downscale || h < options.downscale {
        return Err(format!(
            "{} is {w}x{h}, smaller than --downscale {}",
            path.display(),
            options.downscale
        ));
    }
    Ok((pose, path, intrinsics))
}

/// Reads the image of frame `s`, whose camera its header gave
/// ([`frame_camera`]).
fn read_frame(
    s: FrameSpec,
    camera: Result<FrameCamera, String>,
    options: &LoadOptions,
) -> Result<Frame, FrameProblem> {
    let fail = |problem: String| FrameProblem {
        index: s.index,
        key: s.key.clone(),
        problem,
    };
    let (pose, path, intrinsics) = camera.map_err(&fail)?;
    let (w, h) = (intrinsics.width, intrinsics.height);
    let mut image = pixels::load_image(&path, options.background)
        .map_err(|e| fail(format!("{}: {e}", path.display())))?;
    if let Some(m) = &s.mask {
        pixels::apply_mask(&mut image, m).map_err(|e| fail(format!("{}: {e}", m.display())))?;
    }
    let depth = match &s.depth {
        Some((d, _)) if !d.is_file() => {
            return Err(fail(format!("depth map {} is missing", d.display())))
        }
        Some((d, unit)) => depth::load_depth_map(d, (w, h), *unit)
            .map_err(|e| fail(format!("{}: {e}", d.display())))?,
        None => Vec::new(),
    };
    let n = options.downscale;
    let (image, depth, intrinsics) = if n > 1 {
        (
            downscale::image(&image, n),
            downscale::depth(&depth, w, h, n),
            downscale::intrinsics(&intrinsics, n),
        )
    } else {
        (image, depth, intrinsics)
    };
    // The file's key first; an LDR photograph's own record where it has
    // none (an EXR frame is radiance: no exposure applies).
    let exif = match (s.exposure_time, pixels::image_kind(&path)) {
        (None, Some(pixels::ImageKind::Srgb)) => exif::exposure_of(&path),
        _ => None,
    };
    Ok(Frame {
        index: s.index,
        image_path: path,
        pose,
        intrinsics,
        exposure_time: s.exposure_time.or(exif.map(|e| e.time)),
        exif_exposure: exif,
        image,
        depth,
    })
}

/// The intrinsics `keys` give for an image of `w` × `h`: focal lengths
/// from `fl_x`/`fl_y` or the view angles (fy = fx when neither vertical key
/// is given), the principal point at the centre unless given.
fn intrinsics_for(keys: &CameraKeys, w: u32, h: u32) -> Intrinsics {
    let (wf, hf) = (w as f64, h as f64);
    let fx = keys.fl[0].unwrap_or_else(|| 0.5 * wf / (0.5 * keys.angle[0].unwrap_or(1.0)).tan());
    let fy = keys.fl[1].unwrap_or_else(|| {
        keys.angle[1]
            .map(|a| 0.5 * hf / (0.5 * a).tan())
            .unwrap_or(fx)
    });
    Intrinsics {
        width: w,
        height: h,
        fx,
        fy,
        cx: keys.centre[0].unwrap_or(0.5 * wf),
        cy: keys.centre[1].unwrap_or(0.5 * hf),
        distortion: keys.distortion,
    }
}

/// The field's bounds and where they came from.
fn dataset_bounds(
    top: Obj,
    dialect: Dialect,
    cameras: &[(Pose, Intrinsics)],
    options: &LoadOptions,
) -> Result<(Aabb, BoundsSource), DatasetError> {
    let valid = |b: Aabb, key: &str| {
        if b.is_valid() {
            Ok(b)
        } else {
            Err(top.error(
                key,
                format!("bounds {:?} to {:?} are empty or not finite", b.min, b.max),
            ))
        }
    };
    if let Some(b) = options.bounds {
        return Ok((valid(b, "--bounds")?, BoundsSource::Given));
    }
    if top.has("aabb") {
        let bad = || top.error("aabb", "expected [[min x, y, z], [max x, y, z]]");
        let rows = top.map["aabb"]
            .as_array()
            .filter(|a| a.len() == 2)
            .ok_or_else(bad)?;
        let mut corners = [glam::DVec3::ZERO; 2];
        for (c, row) in corners.iter_mut().zip(rows) {
            let r = row.as_array().filter(|a| a.len() == 3).ok_or_else(bad)?;
            for k in 0..3 {
                c[k] = r[k].as_f64().filter(|v| v.is_finite()).ok_or_else(bad)?;
            }
        }
        return Ok((
            valid(Aabb::new(corners[0], corners[1]), "aabb")?,
            BoundsSource::AabbKey,
        ));
    }
    if dialect == Dialect::InstantNgp {
        if let Some(a) = top.number("aabb_scale")? {
            if a <= 0.0 {
                return Err(top.error("aabb_scale", "must be positive"));
            }
            let scale = top.number("scale")?.unwrap_or(bounds::NGP_DEFAULT_SCALE);
            if scale <= 0.0 {
                return Err(top.error("scale", "must be positive"));
            }
            let offset = match top.numbers("offset", 3)? {
                Some(o) => [o[0], o[1], o[2]],
                None => bounds::NGP_DEFAULT_OFFSET,
            };
            let b = bounds::ngp_bounds(a, scale, offset);
            return Ok((valid(b, "aabb_scale")?, BoundsSource::NgpAabbScale));
        }
    }
    let poses: Vec<Pose> = cameras.iter().map(|(p, _)| *p).collect();
    let half_fovs: Vec<f64> = cameras
        .iter()
        .map(|(_, k)| {
            (0.5 * k.width as f64 / k.fx)
                .atan()
                .min((0.5 * k.height as f64 / k.fy).atan())
        })
        .collect();
    let b = bounds::common_view(&poses, &half_fovs).ok_or_else(|| {
        top.error(
            "aabb",
            "no bounds: the cameras' axes have no common point; give an `aabb` key or --bounds",
        )
    })?;
    Ok((valid(b, "aabb")?, BoundsSource::Cameras))
}

#[cfg(test)]
mod tests;

//! Getting a scene's field: a field file, or its recipe baked (with a
//! progress bar) and kept in a cache so the next run loads it; and the sky
//! learnt with a field file, drawn behind it, and the lights its
//! photographs saw past its bounds, drawn with it.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use indicatif::{ProgressBar, ProgressStyle};
use inlay_engine::DeviceInfo;
use inlay_passes::bake::{bake_grid, BakeKnobs};
use inlay_passes::field::seen_lights::load_seen_lights;
use inlay_passes::field::{
    check_field_may_fit, check_sparse_field_fits, field_bytes, load_field, read_field_header,
    seen_lights_path, sky_path, GridField, NodeStorage, SeenLight, Sky, FIELD_VERSION,
};
use inlay_passes::scene::{FieldSource, Scene};

pub use crate::cache::CACHE_ENV;
use crate::cache::{entry_path, load_or_make, CacheKey};

/// A progress bar on stderr for `total` steps of `what` (hidden when stderr
/// is not a terminal).
pub fn progress_bar(what: &str, total: u64) -> ProgressBar {
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template(
            "{msg:>12} [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta})",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar.set_message(what.to_owned());
    bar
}

/// Bakes a recipe scene's field with `knobs`, showing progress.
pub fn bake_with_progress(scene: &Scene, knobs: &BakeKnobs) -> anyhow::Result<GridField> {
    let recipe = scene.recipe().with_context(|| {
        format!(
            "{}: the scene has no [recipe] to bake",
            scene.path.display()
        )
    })?;
    knobs
        .check()
        .map_err(|(k, m)| anyhow::anyhow!("bake knob `{k}`: {m}"))?;
    let started = Instant::now();
    let res = inlay_passes::bake::grid_resolution(recipe, knobs.resolution);
    let bar = progress_bar("baking", res.z as u64);
    let field = bake_grid(recipe, &scene.environment, knobs, &|done, _| {
        bar.set_position(done)
    });
    bar.finish_and_clear();
    eprintln!(
        "baked {} ({}x{}x{} nodes, {} samples, {} bounces) in {:.2} s",
        scene.name,
        res.x,
        res.y,
        res.z,
        knobs.samples,
        knobs.bounces,
        started.elapsed().as_secs_f64()
    );
    Ok(field)
}

/// The cache entry of `scene`'s recipe baked with `knobs`: its key hashes
/// the scene file's text, the equirect environment it reads, the knobs, the
/// field format's version and the bake's revision.
fn cache_entry(scene: &Scene, knobs: &BakeKnobs) -> anyhow::Result<Option<PathBuf>> {
    let key = CacheKey::new("field")
        .file(&scene.path)?
        .files(&scene.environment_file)?
        .text("knobs", &format!("{knobs:?}"))
        .text(
            "revision",
            &format!("v{FIELD_VERSION} r{}", inlay_passes::bake::BAKE_REVISION),
        );
    Ok(entry_path(&scene.name, key, "inlayfield"))
}

/// Fails unless the field file at `path` may fit `device` (read from its
/// header, before the nodes are): a sparse file's kept bricks in the
/// device's bindings and heap; a dense file's nodes in its heap (whether
/// it needs the sparse layout, the upload finds).
fn check_file_fits(path: &Path, device: Option<&DeviceInfo>) -> anyhow::Result<()> {
    let header = read_field_header(path)?;
    if let Some(info) = device {
        let (res, degree, render) = (header.resolution, header.sh_degree, NodeStorage::Render);
        match header.bricks {
            Some(_) => check_sparse_field_fits(info, res, degree, render, header.stored_nodes()),
            None => check_field_may_fit(info, res, degree, render),
        }
        .with_context(|| format!("{}: resolution", path.display()))?;
    }
    Ok(())
}

/// The scene's field: `override_file` when given, else its field file, else
/// its recipe baked with the scene's knobs (from the cache unless
/// `use_cache` is false). With `device` given, a field too large for it is
/// refused before the file is read or the recipe baked.
pub fn scene_field(
    scene: &Scene,
    override_file: Option<&Path>,
    use_cache: bool,
    device: Option<&DeviceInfo>,
) -> anyhow::Result<GridField> {
    if let Some(f) = override_file {
        check_file_fits(f, device)?;
        return Ok(load_field(f)?);
    }
    match &scene.field {
        FieldSource::File(f) => {
            check_file_fits(f, device)?;
            Ok(load_field(f)?)
        }
        FieldSource::Recipe(recipe) => {
            if let Some(info) = device {
                let res = inlay_passes::bake::grid_resolution(recipe, scene.bake.resolution);
                check_field_may_fit(info, res, 0, NodeStorage::Render).with_context(|| {
                    format!(
                        "{}: [bake] resolution {}",
                        scene.path.display(),
                        scene.bake.resolution
                    )
                })?;
            }
            let entry = if use_cache {
                cache_entry(scene, &scene.bake)?
            } else {
                None
            };
            load_or_make(
                entry.as_deref(),
                "baked field",
                |p| Ok(load_field(p)?),
                || bake_with_progress(scene, &scene.bake),
                field_bytes,
            )
        }
    }
}

/// The sky learnt with the scene's field (`override_file` when given, else
/// its field file): the EXR beside it ([`sky_path`]), None where there is
/// none or the field is baked from a recipe. A sky file that cannot be
/// read, or is not a sky, is an error naming it.
pub fn scene_sky(scene: &Scene, override_file: Option<&Path>) -> anyhow::Result<Option<Sky>> {
    let field = match (override_file, &scene.field) {
        (Some(f), _) => f,
        (None, FieldSource::File(f)) => f.as_path(),
        (None, FieldSource::Recipe(_)) => return Ok(None),
    };
    let file = sky_path(field);
    if !file.exists() {
        return Ok(None);
    }
    let sky = Sky::load(&file)?;
    eprintln!(
        "the sky learnt with the field ({}x{} texels) is drawn behind it: {}",
        sky.width,
        sky.height,
        file.display()
    );
    Ok(Some(sky))
}

/// The lights the scene's trained field saw past its bounds
/// (`override_file` when given, else its field file): the TOML beside it
/// ([`seen_lights_path`]), none where there is none or the field is baked
/// from a recipe. A file that cannot be read is an error naming it and
/// its key.
pub fn scene_seen_lights(
    scene: &Scene,
    override_file: Option<&Path>,
) -> anyhow::Result<Vec<SeenLight>> {
    let field = match (override_file, &scene.field) {
        (Some(f), _) => f,
        (None, FieldSource::File(f)) => f.as_path(),
        (None, FieldSource::Recipe(_)) => return Ok(Vec::new()),
    };
    let file = seen_lights_path(field);
    if !file.exists() {
        return Ok(Vec::new());
    }
    let lights = load_seen_lights(&file)?;
    if !lights.is_empty() {
        let (count, verb) = match lights.len() {
            1 => ("1 light".to_string(), "is"),
            n => (format!("{n} lights"), "are"),
        };
        eprintln!(
            "{count} that its photographs saw past the field's bounds {verb} drawn with it and \
             light{} any objects (an environment file the scene names takes their place, and \
             carries them when `estimate-env` took them as known): {}",
            if lights.len() == 1 { "s" } else { "" },
            file.display()
        );
    }
    Ok(lights)
}

/// Lights `scene`'s objects with `sky` (the one learnt with its field) as
/// their distant light where the scene gives them none: a field file (no
/// recipe, whose known lights stand), a black `[environment]` and no
/// `[lighting] environment` estimate. What the photographs saw past the
/// field is the light that reaches it from there. Returns whether it did.
pub fn light_with_sky(scene: &mut Scene, sky: Option<&Sky>) -> anyhow::Result<bool> {
    let Some(sky) = sky else {
        return Ok(false);
    };
    if scene.recipe().is_some()
        || scene.object_environment.is_some()
        || !scene.environment.is_black()
        || scene.objects.is_empty()
    {
        return Ok(false);
    }
    scene.environment = sky
        .to_environment()
        .map_err(|e| anyhow::anyhow!("{}: the field's sky: {e}", scene.path.display()))?;
    eprintln!(
        "the objects are lit by the sky as their distant light (a scene's [environment] or \
         [lighting] environment takes its place)"
    );
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use inlay_engine::HdrImage;

    /// An edit to the equirect EXR a recipe's environment reads changes
    /// the baked field's cache entry, so the stale field is not loaded.
    #[test]
    fn editing_the_environment_exr_misses_the_cache() {
        let dir = std::env::temp_dir().join(format!("inlay-field-key-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let sky = |v: f32| HdrImage {
            width: 8,
            height: 4,
            pixels: vec![[v, v, v, 1.0]; 32],
        };
        sky(1.0).save(&dir.join("sky.exr"), 1.0).unwrap();
        let text = r#"
name = "keyed"
[recipe]
bounds = { min = [-1.0, -1.0, -1.0], max = [1.0, 1.0, 1.0] }
[[recipe.primitives]]
name = "ball"
type = "sphere"
center = [0.0, 0.0, 0.0]
radius = 0.5
albedo = [0.5, 0.5, 0.5]
[environment]
equirect = "sky.exr"
[[cameras]]
position = [0.0, 0.0, 3.0]
look_at = [0.0, 0.0, 0.0]
"#;
        std::fs::write(dir.join("keyed.toml"), text).unwrap();
        let load = || inlay_passes::scene::load_scene(&dir.join("keyed.toml")).unwrap();
        let scene = load();
        assert_eq!(scene.environment_file, Some(dir.join("sky.exr")));
        let before = cache_entry(&scene, &scene.bake).unwrap();
        assert!(before.is_some());
        assert_eq!(before, cache_entry(&load(), &scene.bake).unwrap());
        sky(2.0).save(&dir.join("sky.exr"), 1.0).unwrap();
        assert_ne!(before, cache_entry(&load(), &scene.bake).unwrap());
    }

    /// A scene file `lit.toml` in a fresh directory (named from `name`):
    /// the field file `f.inlayfield` beside it, a cube, a camera. Returns
    /// the directory and the file's text.
    fn field_file_scene(name: &str) -> (PathBuf, String) {
        let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let cube = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/objects/checker-cube.gltf");
        let text = format!(
            "name = \"lit\"\nfield = \"f.inlayfield\"\n[[objects]]\nname = \"cube\"\nfile = {:?}\n\
             position = [0.0, 0.0, 0.0]\n[[cameras]]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n",
            cube.display().to_string()
        );
        std::fs::write(dir.join("lit.toml"), &text).unwrap();
        (dir, text)
    }

    /// A trained field's sky lights the objects where the scene gives them
    /// no distant light, and only there.
    #[test]
    fn the_sky_lights_the_objects_only_where_nothing_else_does() {
        let (dir, text) = field_file_scene("inlay-sky-light");
        let mut scene = inlay_passes::scene::load_scene(&dir.join("lit.toml")).unwrap();
        let sky = Sky::uniform(4, glam::DVec3::new(0.5, 1.0, 2.0));
        assert!(!light_with_sky(&mut scene, None).unwrap());
        assert!(scene.environment.is_black());
        assert!(light_with_sky(&mut scene, Some(&sky)).unwrap());
        assert_eq!(
            scene.environment.eval(glam::DVec3::Y),
            sky.eval(glam::DVec3::Y)
        );
        // A declared environment stands.
        let declared = format!("{text}[environment]\nlobes = [{{ direction = [0.0, 1.0, 0.0], sharpness = 1.0, amplitude = [1.0, 1.0, 1.0] }}]\n");
        std::fs::write(dir.join("lit.toml"), declared).unwrap();
        let mut scene = inlay_passes::scene::load_scene(&dir.join("lit.toml")).unwrap();
        let before = scene.environment.eval(glam::DVec3::Y);
        assert!(!light_with_sky(&mut scene, Some(&sky)).unwrap());
        assert_eq!(scene.environment.eval(glam::DVec3::Y), before);
        // A recipe's known lights stand.
        let cups = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cups.toml");
        let mut recipe = inlay_passes::scene::load_scene(&cups).unwrap();
        assert!(!light_with_sky(&mut recipe, Some(&sky)).unwrap());
    }
    /// The lights beside a field file are read with it and light its
    /// objects as balls of their size (an environment file's lights stand
    /// in their place); none beside it reads none, and a bad file is an
    /// error naming it and the key.
    #[test]
    fn the_lights_beside_a_field_are_read_and_light_its_objects() {
        use inlay_passes::field::seen_lights::seen_lights_text;
        use inlay_passes::lighting::object_lights;
        let (dir, _) = field_file_scene("inlay-seen-lights");
        let mut scene = inlay_passes::scene::load_scene(&dir.join("lit.toml")).unwrap();
        assert!(scene_seen_lights(&scene, None).unwrap().is_empty());
        let bulb = SeenLight {
            centre: glam::DVec3::new(0.2, 2.9, 0.3),
            radius: 0.03,
            radiance: glam::DVec3::new(8000.0, 7400.0, 6400.0),
            views: 13,
            residual: 0.02,
        };
        let file = dir.join("f.lights.toml");
        std::fs::write(&file, seen_lights_text(&[bulb])).unwrap();
        let lights = scene_seen_lights(&scene, None).unwrap();
        assert_eq!(lights, vec![bulb]);
        scene.seen_lights = lights;
        let (_, local) = object_lights(&scene, glam::DVec3::ZERO, true);
        assert_eq!(local.len(), 1);
        assert_eq!(
            (local[0].centre, local[0].radius),
            (bulb.centre, bulb.radius)
        );
        let emission = local[0].emission.unwrap();
        assert!((emission.intensity - bulb.intensity()).abs().max_element() < 1e-9);
        // Without local lights, a lobe towards it.
        let (lobes, none) = object_lights(&scene, glam::DVec3::ZERO, false);
        assert!(none.is_empty());
        assert_eq!(lobes.len(), 1);
        assert!(lobes[0].direction.angle_between(bulb.centre) < 1e-9);
        // More seen lights than are shaded locally: the brightest are,
        // the rest are lobes.
        scene.seen_lights = (0..10)
            .map(|i| SeenLight {
                centre: glam::DVec3::new(i as f64 - 4.5, 3.0, 0.0),
                radiance: bulb.radiance * (1.0 + i as f64),
                ..bulb
            })
            .collect();
        let (lobes, local) = object_lights(&scene, glam::DVec3::ZERO, true);
        let most = inlay_passes::lighting::local::MAX_LOCAL_LIGHTS as usize;
        assert_eq!((local.len(), lobes.len()), (most, 10 - most));
        assert!(local.iter().all(|l| l.centre.x > 4.5 - most as f64));
        scene.seen_lights = vec![bulb];
        // An environment file lights the objects instead.
        scene.object_environment = Some(inlay_passes::scene::ObjectEnvironment::new(
            dir.join("env.toml"),
            Default::default(),
        ));
        assert!(object_lights(&scene, glam::DVec3::ZERO, true).1.is_empty());
        // One estimated with the seen lights known carries them: they
        // light the objects from it, as balls beside its point lights.
        let light = inlay_passes::envest::EstimatedLight {
            lights: vec![inlay_passes::envest::PointLight {
                position: glam::DVec3::new(0.0, 3.0, 1.0),
                intensity: glam::DVec3::ONE,
            }],
            seen_lights: vec![bulb],
            ..Default::default()
        };
        scene.object_environment = Some(inlay_passes::scene::ObjectEnvironment::new(
            dir.join("env.toml"),
            light,
        ));
        let (lobes, local) = object_lights(&scene, glam::DVec3::ZERO, true);
        assert!(lobes.is_empty() && local.len() == 2);
        assert_eq!(
            (local[1].centre, local[1].radius),
            (bulb.centre, bulb.radius)
        );
        let (lobes, none) = object_lights(&scene, glam::DVec3::ZERO, false);
        assert!(none.is_empty() && lobes.len() == 2);
        // A bad file names itself and its key.
        let bad = seen_lights_text(&[bulb]).replace("radius = 0.03", "radius = 0.0");
        std::fs::write(&file, bad).unwrap();
        let e = scene_seen_lights(&scene, None).unwrap_err().to_string();
        assert!(
            e.contains("f.lights.toml") && e.contains("lights[0].radius"),
            "{e}"
        );
    }
}

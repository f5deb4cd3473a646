//! `inlay bake-scene SCENE`: bakes a recipe into a grid-field file.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;
use glam::DVec3;
use inlay_engine::DeviceInfo;
use inlay_passes::bake::grid_resolution;
use inlay_passes::field::{check_field_may_fit, checked_field_bytes, NodeStorage};
use inlay_passes::scene::load_scene;

use crate::field_source::bake_with_progress;
use crate::outputs::{check_output, Outputs};

/// Options of `bake-scene`.
#[derive(Args, Debug)]
pub struct BakeSceneArgs {
    /// The scene file (TOML with a `[recipe]`).
    pub scene: PathBuf,
    /// Output field file (default: `<scene name>.inlayfield` in the current directory).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Nodes along the longest axis (overrides `[bake] resolution`).
    #[arg(long)]
    pub resolution: Option<u32>,
    /// Path-traced samples per node (overrides `[bake] samples`).
    #[arg(long)]
    pub samples: Option<u32>,
    /// Indirect bounces after direct light; 0 = direct only (overrides `[bake] bounces`).
    #[arg(long)]
    pub bounces: Option<u32>,
    /// Random seed (overrides `[bake] seed`).
    #[arg(long)]
    pub seed: Option<u64>,
}

/// Runs `bake-scene`. The output path, and that `device` can render a
/// field of the asked resolution, are checked before the bake.
pub fn run(device: &DeviceInfo, args: &BakeSceneArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let mut knobs = scene.bake;
    knobs.resolution = args.resolution.unwrap_or(knobs.resolution);
    knobs.samples = args.samples.unwrap_or(knobs.samples);
    knobs.bounces = args.bounces.unwrap_or(knobs.bounces);
    knobs.seed = args.seed.unwrap_or(knobs.seed);
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}.inlayfield", scene.name)));
    check_output("--out", &out, &["inlayfield"])?;
    if let Some(recipe) = scene.recipe() {
        check_field_may_fit(
            device,
            grid_resolution(recipe, knobs.resolution),
            0,
            NodeStorage::Render,
        )
        .with_context(|| format!("--resolution {}", knobs.resolution))?;
    }
    let field = bake_with_progress(&scene, &knobs)?;
    let mut outputs = Outputs::new();
    outputs.bytes(&out, &checked_field_bytes(&out, &field)?)?;
    outputs.commit(None)?;
    let recipe = scene.recipe().expect("baked from a recipe");
    let (inside, outside) = recipe.lights();
    let names = |v: &[&inlay_passes::scene::Primitive]| {
        if v.is_empty() {
            "none".to_owned()
        } else {
            v.iter()
                .map(|p| p.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let occupied: Vec<DVec3> = field
        .nodes
        .iter()
        .filter(|n| n[3] > 0.0)
        .map(|n| DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64))
        .collect();
    let mean =
        occupied.iter().map(|c| c.element_sum() / 3.0).sum::<f64>() / occupied.len().max(1) as f64;
    let brightest = recipe
        .primitives
        .iter()
        .map(|p| p.emission.max_element())
        .fold(0.0, f64::max);
    println!(
        "  {}x{}x{} nodes, {} MiB; {:.0}% of occupancy cells empty",
        field.resolution.x,
        field.resolution.y,
        field.resolution.z,
        (field.nodes.len() * 16) >> 20,
        100.0 * field.occupancy.empty_fraction()
    );
    println!("  lights inside the field: {}", names(&inside));
    println!(
        "  lights outside the field: {}{}",
        names(&outside),
        if scene.environment.is_black() {
            ""
        } else {
            " + the environment"
        }
    );
    println!("  mean radiance of occupied nodes: {mean:.4}");
    if brightest > 0.0 && mean > 0.0 {
        println!(
            "  brightest emitter / mean radiance: {:.3e}",
            brightest / mean
        );
    }
    Ok(())
}

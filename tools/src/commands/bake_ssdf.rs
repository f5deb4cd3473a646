//! `inlay bake-ssdf OBJECT --out FILE`: bakes an object's SSDF field (its
//! visibility from any point around it) on the GPU and writes it.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use inlay_engine::Context;
use inlay_passes::object::load_gltf;
use inlay_passes::ssdf::{ssdf_bytes, SsdfKnobs};

use crate::outputs::{check_output, Outputs};
use crate::ssdf_source::bake_ssdf_with_progress;

/// Options of `bake-ssdf`.
#[derive(Args, Debug)]
pub struct BakeSsdfArgs {
    /// The object (.gltf or .glb).
    pub object: PathBuf,
    /// Output file (default: `<object name>.inlayssdf` in the current directory).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Grid nodes along each axis (the grid spans 3 × the bounding sphere's radius).
    #[arg(long, default_value_t = SsdfKnobs::default().grid)]
    pub grid: u32,
    /// Side of the octahedral direction map (directions² samples per node).
    #[arg(long, default_value_t = SsdfKnobs::default().directions)]
    pub directions: u32,
    /// PCA components kept.
    #[arg(long, default_value_t = SsdfKnobs::default().components)]
    pub components: u32,
    /// A node at distance d from the object is blended from the coarsest
    /// lattice of the grid whose spacing is at most this angle (radians)
    /// times d, instead of baked (0 bakes every node).
    #[arg(long, default_value_t = SsdfKnobs::default().coarse_angle)]
    pub coarse_angle: f64,
}

/// Runs `bake-ssdf`.
pub fn run(ctx: &Arc<Context>, args: &BakeSsdfArgs) -> anyhow::Result<()> {
    let knobs = SsdfKnobs {
        grid: args.grid,
        directions: args.directions,
        components: args.components,
        coarse_angle: args.coarse_angle,
    };
    if let Some((k, m)) = knobs.problem() {
        anyhow::bail!("--{}: {m}", k.replace('_', "-"));
    }
    let out = args.out.clone().unwrap_or_else(|| {
        let stem = args
            .object
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "object".into());
        PathBuf::from(format!("{stem}.inlayssdf"))
    });
    check_output("--out", &out, &["inlayssdf"])?;
    let mesh = Arc::new(load_gltf(&args.object)?);
    let lib = inlay_passes::shaders::library()?;
    let (field, _) = bake_ssdf_with_progress(ctx, &lib, &mesh, &knobs)?;
    let mut outputs = Outputs::new();
    outputs.bytes(&out, &ssdf_bytes(&field))?;
    outputs.commit(Some(ctx))?;
    Ok(())
}

//! The field commands of `inlay`: `bake-scene`, `bake-ssdf`, `estimate-env`, `render`,
//! `reference`, `probe`, `profile`, `dataset`, `render-views`, `train` and the benchmarks.

pub mod auto_value;
pub mod bake_scene;
pub mod bake_ssdf;
pub mod bench_march;
pub mod bench_sg;
pub mod bench_shade;
pub mod crossing_bounds;
pub mod dataset;
pub mod estimate_env;
pub mod fidelity;
pub mod probe;
pub mod profile;
pub mod reference;
pub mod render;
pub mod render_views;
pub mod seen_lights;
pub mod sweep;
pub mod train;

use std::sync::Arc;

use inlay_engine::{Context, ContextOptions};

/// Runs `command` on a device chosen by `options`. Errors the validation
/// layer (when on) reported fail the run even where the command did not
/// check; commands that write outputs check before putting them in place
/// ([`crate::outputs::Outputs::commit`]), so a failing run replaces none.
pub fn on_device(
    options: &ContextOptions,
    command: impl FnOnce(&Arc<Context>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let ctx = Context::new(options, None)?;
    let result = command(&ctx);
    let validated = ctx.check_validation();
    result?;
    Ok(validated?)
}

//! Shared test setup: a Vulkan context with the validation layer on (tests
//! fail on any validation error), on lavapipe in CI.
#![allow(dead_code)]

use std::process::Output;
use std::sync::Arc;

use inlay_engine::{Context, ContextOptions};

/// A validating context. Panics with the engine's message (which says what to
/// install) when Vulkan or the validation layer is missing.
pub fn gpu() -> Arc<Context> {
    let _ = env_logger::builder().is_test(true).try_init();
    match Context::new(&ContextOptions { validate: true, device: None }, None) {
        Ok(c) => c,
        Err(e) => panic!("GPU tests need Vulkan with the validation layer (run tools/test.sh, which installs them): {e}"),
    }
}

/// Fails the test if the validation layer reported any error.
pub fn assert_no_validation_errors(ctx: &Context) {
    if let Err(e) = ctx.check_validation() {
        panic!("{e}");
    }
}

/// A finished process's stdout and stderr as one text, for assertions.
pub fn output_text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

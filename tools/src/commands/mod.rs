//! The field commands of `inlay`: `bake-scene`, `bake-ssdf`, `estimate-env`, `render`,
//! `reference`, `probe`, `profile` and the benchmarks.

pub mod bake_scene;
pub mod bake_ssdf;
pub mod bench_march;
pub mod bench_sg;
pub mod bench_shade;
pub mod estimate_env;
pub mod fidelity;
pub mod probe;
pub mod profile;
pub mod reference;
pub mod render;
pub mod sweep;

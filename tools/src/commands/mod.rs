//! The field commands of `inlay`: `bake-scene`, `render` and `reference`.

pub mod bake_scene;
pub mod bench_march;
pub mod reference;
pub mod render;

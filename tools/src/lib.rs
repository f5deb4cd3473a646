//! The `inlay` program's library: the command-line tools' building blocks
//! (shader library, targets, the engine demo) shared with the tests.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod cache;
pub mod chrome_trace;
pub mod commands;
pub mod demo;
pub mod fidelity;
pub mod field_source;
pub mod gpu_layouts;
pub mod headless;
pub mod insertion_view;
pub mod measure;
pub mod outputs;
pub mod overlay;
pub mod present;
pub mod scene_view;
pub mod ssdf_source;
pub mod sweep;
pub mod table1;
pub mod timings_table;
pub mod view;
pub mod window_app;

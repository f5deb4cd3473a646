//! The `inlay` program's library: the command-line tools' building blocks
//! (shader library, targets, the engine demo) shared with the tests.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod commands;
pub mod demo;
pub mod field_source;
pub mod field_view;
pub mod headless;
pub mod insertion_view;
pub mod present;
pub mod shaders;
pub mod ssdf_source;
pub mod timings_table;
pub mod window_app;

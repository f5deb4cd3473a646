//! The method's passes — NeRF ray march, incident-light probe trace, SG
//! Levenberg–Marquardt fit, object G-buffer and SG shading, compositing and
//! shadows (see `../shared/spec/METHOD.md`) — each with its CPU reference, and
//! the math they share. Every pass is a pass of the engine's frame graph and
//! uses only the engine's safe API.
//!
//! The engine foundation (issue 2) lands first; the passes arrive with the
//! issues that follow it.
#![forbid(unsafe_code)]

//! The speed/accuracy sweep's parts: the knob grid, the Pareto front and
//! the plot (`inlay sweep` runs them, `commands::sweep`).

pub mod grid;
pub mod pareto;
pub mod plot;

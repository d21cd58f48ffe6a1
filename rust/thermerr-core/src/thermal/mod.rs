//! The machine's lumped thermal network: model file, simulation, calibration.

pub mod calibrate;
pub mod diagnose;
pub mod identify;
pub mod machine;
pub mod sim;

pub use machine::Machine;
pub use sim::{simulate, Init, RunView, Simulation};

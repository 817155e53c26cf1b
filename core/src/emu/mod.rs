//! The reference model of the PPMC-104BFP: a discrete-event simulation in
//! virtual time, pure (no clock, file or port), following datasheet chapter 3.

pub mod board;
mod chip;
pub mod config;
pub mod faults;
pub mod hooks;
mod motion;

pub use board::{Board, WiringFaults};
pub use chip::{Chip, ChipError, PA_MAX, PA_MIN};
pub use config::{AccelCurve, ConfigError, ModelConfig};
pub use hooks::ModelFaults;

//! ppmc: a hardware-in-the-loop harness, reference emulator and protocol
//! fuzzer for the PPMC-104BFP stepper-motor pulse controller.
//!
//! Layers, each depending only on the ones before it:
//! [`protocol`] (pure wire types) ← [`emu`] (the chip model) ← [`target`]
//! (one bus abstraction, many backends) ← [`console`] (bus scripts) ← the
//! `ppmc` binary.

pub mod bridge;
pub mod cli;
pub mod compare;
pub mod console;
pub mod fault_matrix;
pub mod faults;
pub mod fuzzing;
pub mod golden;
pub mod report;
pub mod runner;
pub mod scenario;
pub mod target;
pub mod trace;
pub mod vcd_export;

pub use ppmc_core::{bus, emu, protocol, time};

/// The harness's version and git revision, for run records.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
pub const GIT_REV: &str = env!("PPMC_GIT_REV");

//! ppmc: a hardware-in-the-loop harness, reference emulator and protocol
//! fuzzer for the PPMC-104BFP stepper-motor pulse controller.
//!
//! The std half of ppmc: everything that needs an operating system, on top
//! of the portable `ppmc-core` (re-exported here as [`time`], [`protocol`],
//! [`emu`] and [`bus`]). Layers, each depending only on the ones before it:
//! [`stop`], [`files`] ← [`backend`] (targets: a [`backend::TargetSpec`]
//! opened into the emulator or a bridge over a byte link), [`trace`],
//! [`vcd_export`], [`bridge::sim`] ← [`scenario`] (the scenario API) ←
//! [`runner`] (one target or a [`runner::Farm`] of boards), [`golden`],
//! [`compare`], [`selftest`], [`console`], [`chaos`] ← [`report`],
//! [`soak`], [`store`] ← [`fuzzing`] (its oracle in [`invariants`], the second model
//! of the chip in [`plain_model`]) ← [`fault_matrix`] ← [`cli`] (the
//! command line: arguments in, results printed, nothing else).
//! `ARCHITECTURE.md` at the repository root is the map.

pub mod backend;
pub mod bridge;
pub mod chaos;
pub mod compare;
pub mod console;
pub mod fuzzing;
pub mod golden;
pub mod invariants;
pub mod plain_model;
pub mod runner;
pub mod scenario;
pub mod selftest;
pub mod soak;
pub mod stop;
pub mod trace;
pub mod vcd_export;

pub use ppmc_core::emu::faults;
pub use ppmc_core::{bus, emu, protocol, time};
pub use ppmc_files as files;
pub use ppmc_record as record;

/// The harness's version and git revision, for run records.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
pub const GIT_REV: &str = env!("PPMC_GIT_REV");

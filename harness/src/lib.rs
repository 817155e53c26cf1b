//! ppmc: a hardware-in-the-loop harness, reference emulator and protocol
//! fuzzer for the PPMC-104BFP stepper-motor pulse controller.
//!
//! The harness library: everything that needs an operating system to
//! drive a chip, on top of the portable `ppmc-core` (re-exported here as
//! [`time`], [`protocol`], [`emu`] and [`bus`]). Its modules from the
//! lowest up, each naming only those before it (a test holds them to
//! this order): [`stop`]; [`bridge`] (the bridge simulator); [`backend`]
//! (targets: a [`backend::TargetSpec`] opened into the emulator or a
//! bridge over a byte link); [`trace`], [`compare`], [`vcd_export`];
//! [`bus_program`] (the bus-op language the fuzzing rooms speak);
//! [`scenario`] (the scenario language); [`runner`] (one target or a
//! [`runner::Farm`] of boards); [`console`], [`selftest`], [`chaos`],
//! [`golden`]; [`sink`] (a run's results into its [`record::RunRecord`]),
//! [`artifacts`]; [`session`] (a run of a suite on a farm of boards,
//! into its record), [`bench`](mod@bench) (its wall-clock figures);
//! then the three fuzzing rooms, [`invariants`] (the oracle),
//! [`plain_model`] (the second model of the chip) and [`fuzzing`] (the
//! campaign).
//!
//! Reports, the results store, capture readers, the capture judge and the
//! command line are crates of their own above this one (`ppmc-report`,
//! `ppmc-logic`, `ppmc-capture`, `ppmc-cli`), so a library user of the
//! scenario language compiles no SQLite, zip or clap. `ARCHITECTURE.md`
//! at the repository root is the map.

pub mod artifacts;
pub mod backend;
pub mod bench;
pub mod bridge;
pub mod bus_program;
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
pub mod session;
pub mod sink;
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

/// The name this program was run by, for messages that tell the user a
/// command to type: `ppmc`, or a board team's own binary that hands its
/// suite to `ppmc_cli::main` (`board-suite record ...`). `ppmc` where the
/// name cannot be read, is not a plain word, or is a test binary's
/// (`it-0123456789abcdef`).
pub fn program() -> String {
    let arg0 = std::env::args_os().next().unwrap_or_default();
    let stem = std::path::Path::new(&arg0)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or_default();
    let plain = !stem.is_empty()
        && stem
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c));
    let test_binary = stem
        .rsplit_once('-')
        .is_some_and(|(_, h)| h.len() == 16 && h.chars().all(|c| c.is_ascii_hexdigit()));
    if plain && !test_binary {
        stem.to_string()
    } else {
        "ppmc".to_string()
    }
}

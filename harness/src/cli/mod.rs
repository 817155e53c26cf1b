//! The `ppmc` command line, one file per command. [`main`] is the whole
//! tool in one call: a crate with scenarios of its own gets every command
//! (`run`, `list`, `record`, `compare`, `--target`, JUnit and JSON) by
//! handing its suite to it.

pub(crate) mod args;
mod bench;
mod bridge_sim;
mod compare;
mod console;
mod export;
mod fault_matrix;
mod fuzz;
mod list;
mod progress;
mod record;
mod run;

pub use args::{OpenError, TargetArgs};

use crate::scenario::Scenario;
use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Hardware-in-the-loop harness, reference emulator and protocol fuzzer for
/// the PPMC-104BFP stepper-motor pulse controller.
#[derive(Debug, Parser)]
#[command(name = "ppmc", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the conformance suite on a target (the emulator by default) and
    /// grade it: passed, marginal, failed (the device), error (the harness or
    /// link). Exit status 0 when all pass, 1 when any does not, 2 on bad usage.
    Run(run::RunArgs),
    /// List the scenarios with their section, tags and summary.
    List(list::ListArgs),
    /// Run scenarios and write their traces as golden files. Never overwrites
    /// an existing golden file unless --bless is given; writes atomically.
    Record(record::RecordArgs),
    /// Compare a golden trace set with a second trace set (--traces) or with a
    /// fresh run on a target, with tolerances; prints each scenario's verdict
    /// and its first divergence.
    Compare(compare::CompareArgs),
    /// Write a trace as a VCD waveform (POUT, DIR, S1..S5, INT, HOLD, AUX,
    /// BUSY) for GTKWave or PulseView.
    Export(export::ExportArgs),
    /// Run a bus script against a target and print one line per result.
    ///
    /// Reads the script from FILE, from -e, or from standard input. On a
    /// terminal each line runs as you type it; otherwise the whole script is
    /// checked first and nothing runs if a line is wrong. See docs/console.md.
    Console(console::ConsoleArgs),
    /// Serve the bus bridge protocol on a pseudo-terminal with the emulator
    /// behind it, exactly as a board's bridge serves it over USB serial.
    /// Prints the pty path; point `--target serial:<path>` at it.
    BridgeSim(bridge_sim::BridgeSimArgs),
    /// Measure the emulator's speed (maximum-length move, constant-rate
    /// stretches, per-pulse expansion) and print the figures.
    Bench(bench::BenchArgs),
    /// Fuzzing: a differential run against a target (`ppmc fuzz --target
    /// serial:<pty> --seed N`), and findings made into regression tests
    /// (`reproduce`, `minimize`, `to-scenario`).
    Fuzz(fuzz::FuzzArgs),
    /// Run every catalogued board fault (and the clean board) behind
    /// `bridge-sim` on a pty against the conformance suite, the golden
    /// traces and a bounded differential fuzz; print which caught each and
    /// how fast. Exit status 0 when every fault is caught and the clean
    /// board by nothing, 1 otherwise.
    FaultMatrix(fault_matrix::MatrixArgs),
}

/// The whole `ppmc` command line over `suite`: parses the process's
/// arguments, runs the command and gives its exit status (0 all passed, 1
/// a scenario failed or errored, 2 bad usage). A board team's crate calls
/// it with its own scenarios added to the conformance suite:
///
/// ```no_run
/// fn main() -> std::process::ExitCode {
///     let suite: Vec<ppmc::scenario::Scenario> = Vec::new(); // your scenarios
///     ppmc::cli::main(suite)
/// }
/// ```
pub fn main(suite: Vec<Scenario>) -> ExitCode {
    let cli = Cli::parse();
    let suite = &suite;
    match cli.command {
        Command::Run(args) => run::run(args, suite),
        Command::List(args) => list::run(args, suite),
        Command::Record(args) => record::run(args, suite),
        Command::Compare(args) => compare::run(args, suite),
        Command::Export(args) => export::run(args),
        Command::Console(args) => console::run(args),
        Command::Bench(args) => bench::run(args, suite),
        Command::BridgeSim(args) => bridge_sim::run(args),
        Command::Fuzz(args) => fuzz::run(args),
        Command::FaultMatrix(args) => fault_matrix::run(args, suite),
    }
}

/// Exit status 2: bad usage or bad input (the script, an option).
pub(crate) fn usage_error(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("ppmc: {msg}");
    ExitCode::from(2)
}

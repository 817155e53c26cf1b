//! The `ppmc` command line, one file per command. [`main`] is the whole
//! tool in one call: a crate with scenarios of its own gets every command
//! (`run`, `list`, `record`, `compare`, `--target`, JUnit and JSON) by
//! handing its suite to it.

#[macro_use]
pub(crate) mod out;
pub(crate) mod args;
mod bench;
mod bridge_sim;
mod capture_args;
mod chaos_proxy;
mod compare;
mod console;
mod decode;
mod export;
mod fault_matrix;
mod fuzz;
mod history;
mod judge;
mod lines;
mod list;
mod power;
mod progress;
mod record;
mod report;
mod reports;
mod run;
mod selftest;
mod signals;
mod store;
mod suggest;

use clap::{Parser, Subcommand};
use ppmc::scenario::Scenario;
use std::process::ExitCode;

/// Hardware-in-the-loop harness, reference emulator and protocol fuzzer for
/// the PPMC-104BFP stepper-motor pulse controller.
#[derive(Debug, Parser)]
#[command(name = "ppmc", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Colour the verdict words: on a terminal (`auto`, off when NO_COLOR
    /// is set), `always` or `never`.
    #[arg(long, global = true, value_enum, default_value_t = out::ColorChoice::Auto)]
    color: out::ColorChoice,
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
    /// BUSY; with --bus the host's bus too and every pin at its level, the
    /// phases under the output logic and chopped) for GTKWave or
    /// PulseView, or a scenario run on the emulator as a logic analyzer
    /// would record it.
    Export(export::ExportArgs),
    /// Print the register accesses of a logic-analyzer capture of the
    /// chip's bus, in the bus console's language (docs/capture.md).
    Decode(decode::DecodeArgs),
    /// Judge a board from a logic-analyzer capture of its bus and pins:
    /// the captured writes replayed into the reference model, the chip's
    /// answers, pulses and outputs compared (docs/capture.md). Exit
    /// status: 0 passed; 1 the board diverged; 3 the board passed but the
    /// host firmware broke a rule of chapter 3; 4 the capture cannot be
    /// judged; 2 a file that does not read, or bad usage.
    Judge(judge::JudgeArgs),
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
    /// Test a bus bridge's capture with its own pulse generator, no jumper
    /// and no chip output needed: POUT's and INT*'s capture inputs, driven
    /// at the chip's slowest and fastest rates, in bursts, and beyond what
    /// the capture keeps; prints each check's measured timestamp offset and
    /// jitter. The first step of a new bridge's bring-up
    /// (docs/bridge-hardware.md). Exit status 0 when every check passes, 1
    /// when one fails or the bridge cannot be reached, 2 on bad usage.
    Selftest(selftest::SelftestArgs),
    /// Serve a misbehaving TCP proxy in front of a bridge (dropped
    /// connections, floods, stalls, wrong replies), to check that a link
    /// that fails never turns into a verdict on the board. Prints where it
    /// listens; runs until SIGINT.
    ChaosProxy(chaos_proxy::ChaosProxyArgs),
    /// Draw run records, or a results store's history (`--store`), as one
    /// offline HTML page: every verdict, each
    /// measurement against its Table 3-3 band, each move's speed profile
    /// over the golden one with the first divergence marked, the pins
    /// around each failure (docs/reports.md).
    Report(report::ReportArgs),
    /// What a results store (`ppmc run --store FILE`) says across runs:
    /// yield per revision, the scenarios with the lowest pass rate, each
    /// measurement's spread and Cpk per revision (docs/results-store.md).
    History(history::HistoryArgs),
    /// A results store by hand: `ppmc store push RECORD...` sends run
    /// records it did not take (its server was out of reach), each run
    /// kept once however often it is sent (docs/results-store.md).
    Store(store::StoreArgs),
}

/// The whole `ppmc` command line over `suite`: parses the process's
/// arguments, runs the command and gives its exit status (0 all passed, 1
/// a scenario failed or errored, 2 bad usage). A board team's crate calls
/// it with its own scenarios added to the conformance suite:
///
/// ```no_run
/// fn main() -> std::process::ExitCode {
///     let suite: Vec<ppmc::scenario::Scenario> = Vec::new(); // your scenarios
///     ppmc_cli::main(suite)
/// }
/// ```
pub fn main(suite: Vec<Scenario>) -> ExitCode {
    // Held until the command's handlers are in (signals.rs); a binary
    // holds them itself first thing (hold_signals), before building its
    // suite.
    signals::hold();
    let cli: Cli = suggest::parse();
    // Only these install handlers (and let the signals go as they do).
    if !matches!(
        cli.command,
        Command::Run(_) | Command::Selftest(_) | Command::BridgeSim(_) | Command::ChaosProxy(_)
    ) {
        signals::release();
    }
    out::set_color(cli.color);
    let suite = &suite;
    let done = match cli.command {
        Command::Run(args) => run::run(args, suite),
        Command::List(args) => list::run(args, suite),
        Command::Record(args) => record::run(args, suite),
        Command::Compare(args) => compare::run(args, suite),
        Command::Export(args) => export::run(args, suite),
        Command::Decode(args) => decode::run(args),
        Command::Judge(args) => judge::run(args),
        Command::Console(args) => console::run(args),
        Command::Bench(args) => bench::run(args, suite),
        Command::BridgeSim(args) => bridge_sim::run(args),
        Command::Fuzz(args) => fuzz::run(args, suite),
        Command::FaultMatrix(args) => fault_matrix::run(args, suite),
        Command::ChaosProxy(args) => chaos_proxy::run(args),
        Command::Selftest(args) => selftest::run(args),
        Command::Report(args) => report::run(args),
        Command::History(args) => history::run(args),
        Command::Store(args) => store::run(args),
    };
    match done {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => e.exit(),
    }
}

/// Holds SIGINT and SIGTERM from a binary's first instruction until the
/// command's handlers are in place, so that a run stopped at once still
/// writes its reports: call it first in `main`, before the suite is built
/// and [`main`] runs.
pub fn hold_signals() {
    signals::hold();
}

/// Why a command did not end in success. Every command returns it, and
/// [`CliError::exit`] is the one place that turns it into the exit status:
/// 2 for the user's input, 1 for everything else.
#[derive(Debug)]
pub(crate) enum CliError {
    /// An option, or a file or script the user gave, is wrong (exit 2).
    Usage(String),
    /// Like [`CliError::Usage`], with a message that already says where
    /// (`script.ppmc: line 3: ...`), printed as it is (exit 2).
    BadInput(String),
    /// The board, the bridge or the link is not there or not healthy: not
    /// the device's fault, and not the user's typing either (exit 1).
    Infrastructure(String),
    /// The command could not do its work (exit 1).
    Failed(String),
    /// A file could not be read or written; the error names it and says
    /// what failed (exit 2 when it is the user's file or path that is wrong,
    /// 1 when the system failed a write).
    File(ppmc_files::FileError),
    /// SIGINT or SIGTERM, or standard output closed, stopped the command
    /// before its end; it has written what it had (exit 130).
    Interrupted,
    /// The command ran and its verdict is negative (a scenario failed, an
    /// input breaks an invariant, a fault went undetected); it has said
    /// why (exit 1).
    Verdict,
    /// The command ran and its verdict's kind is this exit status (`ppmc
    /// judge`: 3 the host firmware, 4 the capture); it has said why.
    Code(u8),
}

impl CliError {
    /// Reports the error on standard error and gives the exit status.
    fn exit(self) -> ExitCode {
        match self {
            CliError::Usage(m) => {
                errln!("ppmc: {m}");
                ExitCode::from(2)
            }
            CliError::BadInput(m) => {
                errln!("{m}");
                ExitCode::from(2)
            }
            CliError::Infrastructure(m) => {
                errln!("ppmc: infrastructure error: {m}");
                ExitCode::from(1)
            }
            CliError::Failed(m) => {
                errln!("ppmc: {m}");
                ExitCode::from(1)
            }
            CliError::File(e) => {
                use ppmc_files::{Action, FileError};
                errln!("ppmc: {e}");
                let users = match &e {
                    // A file the user gave that cannot be read, or an
                    // output folder found unusable before the run.
                    FileError::Io { action, .. } => matches!(
                        action,
                        Action::Reading | Action::Probing | Action::PreparingFolder
                    ),
                    _ => true,
                };
                ExitCode::from(if users { 2 } else { 1 })
            }
            CliError::Verdict => ExitCode::from(1),
            CliError::Code(c) => ExitCode::from(c),
            CliError::Interrupted => ExitCode::from(130),
        }
    }
}

impl From<ppmc_files::FileError> for CliError {
    fn from(e: ppmc_files::FileError) -> Self {
        CliError::File(e)
    }
}

/// A usage error: an option or an input the user gave is wrong.
pub(crate) fn usage(msg: impl std::fmt::Display) -> CliError {
    CliError::Usage(msg.to_string())
}

//! `ppmc fuzz`: turning fuzz findings into something people can read and
//! keep, and differential runs against a target.

mod campaign;
mod corpus;
mod coverage;
mod departure;
mod inputs;
mod minimize;
mod replay;
mod reproduce;
mod run;
mod seeds;
mod to_scenario;
mod triage;
mod twin;

use crate::CliError;
use clap::{Args, Subcommand};
use inputs::{InputArgs, Kind, ModelArgs};
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct FuzzArgs {
    #[command(subcommand)]
    command: Option<FuzzCommand>,
    /// Without a subcommand: a differential run (see `ppmc fuzz run --help`).
    #[command(flatten)]
    run: run::DiffArgs,
}

#[derive(Debug, Subcommand)]
enum FuzzCommand {
    /// Print a fuzz input (a crash file from fuzz/artifacts/, or a corpus
    /// entry) as a bus script in the console language, with the invariant
    /// it breaks on the emulator. Paste it into `ppmc console` to replay it.
    /// Exit status 1 when the input breaks an invariant, 0 when it breaks
    /// none, 2 when the file cannot be read.
    Reproduce {
        #[command(flatten)]
        input: InputArgs,
    },
    /// Shrink a fuzz input while the same invariant still breaks: drop ops,
    /// merge and shorten waits, zero data bytes. Writes the result as a
    /// `bus_bytes` input (`<file>.min` unless -o) and prints its bus
    /// script. Exit status 0 when minimized, 1 when the input breaks no
    /// invariant, 2 on a usage or file error.
    Minimize {
        #[command(flatten)]
        input: InputArgs,
        /// Where to write the minimized input.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Write a fuzz input (best minimized first) as a Rust scenario file in
    /// scenarios/src/, named after the invariant it breaks
    /// (`fuzz_<invariant>_<n>.rs`; never overwrites). The scenario replays
    /// the bus ops and fails while the invariant breaks. Exit status 0 when
    /// written, 1 when the input breaks no invariant, 2 on a usage or file
    /// error.
    ToScenario {
        #[command(flatten)]
        input: InputArgs,
        /// The scenario directory.
        #[arg(long, default_value = "scenarios/src")]
        dir: PathBuf,
    },
    /// Bucket findings by the invariant each breaks: a thousand crashes of
    /// one bug are one line, with the shortest input to minimize. Takes
    /// files and directories (e.g. fuzz/artifacts/bus_bytes/). Exit status
    /// 1 when any input breaks an invariant.
    Triage {
        /// Input files or directories of inputs.
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        #[command(flatten)]
        model: ModelArgs,
    },
    /// Domain coverage of a corpus: which commands were written in which
    /// chip state, which error codes and finish causes were reached, which
    /// inputs changed during a move; and what never was. Markdown on
    /// standard output.
    Coverage {
        /// Corpus files or directories (e.g. fuzz/corpus/bus_bytes/).
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Which fuzz target the inputs are for.
        #[arg(long, value_enum, default_value = "bus-bytes")]
        kind: Kind,
    },
    /// Run a `bus_bytes` input (a crash file from fuzz/artifacts/model_twin/,
    /// or any corpus entry) on the emulator and on the plain model, the
    /// second model written from the datasheet alone, and show where they
    /// first differ. When they do, the input is shrunk to the fewest ops
    /// that still differ, written as `<file>.min` (unless -o) and printed as
    /// a bus script. Exit status 0 when they agree, 1 when they differ, 2
    /// on a usage or file error.
    Twin {
        /// The input file.
        file: PathBuf,
        /// Where to write the shrunk input.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Write the fuzz targets' seed corpora, made from the bridge protocol
    /// and the conformance suite, after a protocol or scenario change;
    /// a seed that is already as made is left alone.
    Seeds {
        /// The corpus folder: one folder per target under it.
        #[arg(long, default_value = "fuzz/corpus")]
        out: PathBuf,
    },
    /// A differential run: a seeded stream of protocol-respecting actions
    /// against a target and the emulator side by side (the default when no
    /// subcommand is given).
    Run(run::DiffArgs),
    /// A guided campaign against any target: `bus_bytes` inputs (protocol
    /// violations included) run from a chip reset, each judged by the
    /// datasheet's invariants on what the board answered, with the
    /// reference model's coverage of the same input as the feedback, on a
    /// budget of board time. Exit status 1 when an invariant broke and
    /// broke again when run once more.
    Campaign(campaign::CampaignArgs),
    /// Replay a finding of a campaign (any `bus_bytes` input) on any
    /// target, bit for bit as the campaign ran it (a chip reset, then its
    /// ops with a status read around each), judged by the invariants on
    /// what the target answered; with --shrink, shrink it. Exit status 1
    /// when it breaks an invariant there, 0 when it breaks none.
    Replay(replay::ReplayArgs),
}

pub fn run(args: FuzzArgs, suite: &[ppmc::scenario::Scenario]) -> Result<(), CliError> {
    match args.command {
        Some(FuzzCommand::Seeds { out }) => seeds::run(&out, suite),
        None => run::run(args.run),
        Some(FuzzCommand::Run(a)) => run::run(a),
        Some(FuzzCommand::Campaign(a)) => campaign::run(a, suite),
        Some(FuzzCommand::Replay(a)) => replay::run(a),
        Some(FuzzCommand::Triage { paths, model }) => triage::run(&paths, &model),
        Some(FuzzCommand::Coverage { paths, kind }) => coverage::run(&paths, kind.into()),
        Some(FuzzCommand::Reproduce { input }) => reproduce::run(&input),
        Some(FuzzCommand::Minimize { input, output }) => minimize::run(&input, output),
        Some(FuzzCommand::ToScenario { input, dir }) => to_scenario::run(&input, &dir),
        Some(FuzzCommand::Twin { file, output }) => twin::run(&file, output),
    }
}

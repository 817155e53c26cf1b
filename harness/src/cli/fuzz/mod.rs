//! `ppmc fuzz`: turning fuzz findings into something people can read and
//! keep, and differential runs against a target.

mod run;

use crate::emu::ModelConfig;
use crate::fuzzing::finding::{self, InputKind};
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

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
        kind: InputKind,
    },
    /// A differential run: a seeded stream of protocol-respecting actions
    /// against a target and the emulator side by side (the default when no
    /// subcommand is given).
    Run(run::DiffArgs),
}

#[derive(Debug, Args)]
struct ModelArgs {
    /// Which fuzz target the inputs are for.
    #[arg(long, value_enum, default_value = "bus-bytes")]
    kind: InputKind,
    /// Judge on an emulator with this board fault (`ppmc fault-matrix
    /// --list`); repeat to combine. Default: the clean emulator.
    #[arg(long = "chip-fault", value_name = "FAULT")]
    chip_faults: Vec<String>,
}

impl ModelArgs {
    fn model(&self) -> Result<ModelConfig, ExitCode> {
        let mut cfg = ModelConfig::default();
        crate::faults::apply_all(&self.chip_faults, &mut cfg)
            .map_err(|e| crate::cli::usage_error(format!("--chip-fault: {e}")))?;
        Ok(cfg)
    }
}

/// The inputs under `paths` (files, or the files of directories, sorted),
/// as bus ops.
fn load_inputs(
    paths: &[PathBuf],
    kind: InputKind,
    cfg: &ModelConfig,
) -> Result<Vec<(String, Vec<crate::fuzzing::bus::BusOp>)>, ExitCode> {
    let mut files = Vec::new();
    for p in paths {
        if p.is_dir() {
            let rd = std::fs::read_dir(p).map_err(|e| {
                crate::cli::usage_error(format!("cannot read {}: {e}", p.display()))
            })?;
            let mut v: Vec<PathBuf> = rd
                .filter_map(Result::ok)
                .map(|e| e.path())
                .filter(|f| f.is_file())
                .collect();
            v.sort();
            files.extend(v);
        } else {
            files.push(p.clone());
        }
    }
    files
        .into_iter()
        .map(|f| {
            let data = std::fs::read(&f).map_err(|e| {
                crate::cli::usage_error(format!("cannot read {}: {e}", f.display()))
            })?;
            Ok((f.display().to_string(), finding::ops_of(&data, kind, cfg)))
        })
        .collect()
}

#[derive(Debug, Args)]
struct InputArgs {
    /// The input file.
    file: PathBuf,
    #[command(flatten)]
    model: ModelArgs,
}

impl InputArgs {
    /// The model, the input's bytes and its bus ops.
    fn load(&self) -> Result<(ModelConfig, Vec<crate::fuzzing::bus::BusOp>), ExitCode> {
        let cfg = self.model.model()?;
        let data = std::fs::read(&self.file).map_err(|e| {
            crate::cli::usage_error(format!("cannot read {}: {e}", self.file.display()))
        })?;
        let ops = finding::ops_of(&data, self.model.kind, &cfg);
        Ok((cfg, ops))
    }
}

pub fn run(args: FuzzArgs) -> ExitCode {
    match args.command {
        None => run::run(args.run),
        Some(FuzzCommand::Run(a)) => run::run(a),
        Some(FuzzCommand::Triage { paths, model }) => {
            let cfg = match model.model() {
                Ok(c) => c,
                Err(code) => return code,
            };
            let inputs = match load_inputs(&paths, model.kind, &cfg) {
                Ok(v) => v,
                Err(code) => return code,
            };
            let (buckets, clean) = crate::fuzzing::campaign::triage(&inputs, &cfg);
            println!("| invariant | inputs | shortest input | its ops | break |\n|---|---:|---|---:|---|");
            for b in &buckets {
                let (name, n, v) = &b.smallest;
                println!(
                    "| {} | {} | {name} | {n} | after op {}: {} |",
                    b.invariant,
                    b.inputs.len(),
                    v.op,
                    v.detail
                );
            }
            println!(
                "\n{} inputs: {} findings in {} buckets, {} break nothing",
                inputs.len(),
                inputs.len() - clean.len(),
                buckets.len(),
                clean.len()
            );
            if buckets.is_empty() {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(1)
            }
        }
        Some(FuzzCommand::Coverage { paths, kind }) => {
            let cfg = ModelConfig::default();
            let inputs = match load_inputs(&paths, kind, &cfg) {
                Ok(v) => v,
                Err(code) => return code,
            };
            let ops: Vec<_> = inputs.into_iter().map(|(_, o)| o).collect();
            print!("{}", crate::fuzzing::campaign::Coverage::of(&ops).render());
            ExitCode::SUCCESS
        }
        Some(FuzzCommand::Reproduce { input }) => {
            let (cfg, ops) = match input.load() {
                Ok(x) => x,
                Err(code) => return code,
            };
            let data = finding::to_bytes(&ops);
            let source = input.file.display().to_string();
            let (script, found) = crate::fuzzing::reproducer_with(&data, &source, cfg);
            print!("{script}");
            if found.is_some() {
                ExitCode::from(1)
            } else {
                ExitCode::SUCCESS
            }
        }
        Some(FuzzCommand::Minimize { input, output }) => {
            let (cfg, ops) = match input.load() {
                Ok(x) => x,
                Err(code) => return code,
            };
            let Some(v) = finding::first_break(&ops, &cfg) else {
                eprintln!(
                    "ppmc fuzz minimize: {} breaks no invariant on this model; nothing to minimize",
                    input.file.display()
                );
                return ExitCode::from(1);
            };
            let Some(m) = finding::minimize(&ops, &cfg, v.invariant) else {
                eprintln!(
                    "ppmc fuzz minimize: the break of {} is not reproducible",
                    v.invariant
                );
                return ExitCode::from(1);
            };
            let out = output.unwrap_or_else(|| with_suffix(&input.file, "min"));
            let bytes = finding::to_bytes(&m.ops);
            if let Err(e) = crate::golden::write_atomic(&out, &bytes) {
                return crate::cli::usage_error(format!("cannot write {}: {e}", out.display()));
            }
            eprintln!(
                "ppmc fuzz minimize: {} ops -> {} ops ({} oracle runs), invariant {} still breaks; wrote {}",
                ops.len(),
                m.ops.len(),
                m.tries,
                m.violation.invariant,
                out.display()
            );
            let (script, _) =
                crate::fuzzing::reproducer_with(&bytes, &out.display().to_string(), cfg);
            print!("{script}");
            ExitCode::SUCCESS
        }
        Some(FuzzCommand::ToScenario { input, dir }) => {
            let (cfg, ops) = match input.load() {
                Ok(x) => x,
                Err(code) => return code,
            };
            let Some(v) = finding::first_break(&ops, &cfg) else {
                eprintln!(
                    "ppmc fuzz to-scenario: {} breaks no invariant on this model; \
                     a regression scenario would pass already",
                    input.file.display()
                );
                return ExitCode::from(1);
            };
            if !dir.is_dir() {
                return crate::cli::usage_error(format!(
                    "{} is not a directory: run from the repository root or give --dir",
                    dir.display()
                ));
            }
            let (stem, path) = (1..)
                .map(|n| {
                    let stem = finding::scenario_stem(v.invariant, n);
                    let path = dir.join(format!("{stem}.rs"));
                    (stem, path)
                })
                .find(|(_, p)| !p.exists())
                .unwrap_or_default();
            let text = finding::scenario_file(
                &stem,
                &ops[..=v.op.min(ops.len().saturating_sub(1))],
                &v,
                &input.file.display().to_string(),
            );
            if let Err(e) = crate::golden::write_atomic(&path, text.as_bytes()) {
                return crate::cli::usage_error(format!("cannot write {}: {e}", path.display()));
            }
            println!(
                "wrote {} (scenario {stem}, invariant {}, {} ops); add `{stem}` to the \
                 suite! list in scenarios/src/lib.rs, and `cargo test` runs it",
                path.display(),
                v.invariant,
                v.op + 1
            );
            ExitCode::SUCCESS
        }
    }
}

fn with_suffix(p: &Path, suffix: &str) -> PathBuf {
    let mut s = p.as_os_str().to_owned();
    s.push(".");
    s.push(suffix);
    PathBuf::from(s)
}

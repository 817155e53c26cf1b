//! `ppmc fuzz`: turning fuzz findings into something people can read.

use clap::{Args, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, Args)]
pub struct FuzzArgs {
    #[command(subcommand)]
    command: FuzzCommand,
}

#[derive(Debug, Subcommand)]
enum FuzzCommand {
    /// Print a `bus_bytes` input (a crash file from fuzz/artifacts/, or a
    /// corpus entry) as a bus script in the console language, with the
    /// invariant it breaks on the emulator. Paste it into `ppmc console` to
    /// replay it. Exit status 1 when the input breaks an invariant, 0 when
    /// it breaks none, 2 when the file cannot be read.
    Reproduce {
        /// The input file.
        file: PathBuf,
    },
}

pub fn run(args: FuzzArgs) -> ExitCode {
    match args.command {
        FuzzCommand::Reproduce { file } => {
            let data = match std::fs::read(&file) {
                Ok(d) => d,
                Err(e) => {
                    return crate::usage_error(format!("cannot read {}: {e}", file.display()))
                }
            };
            let (script, found) = ppmc::fuzzing::reproducer(&data, &file.display().to_string());
            print!("{script}");
            if found.is_some() {
                ExitCode::from(1)
            } else {
                ExitCode::SUCCESS
            }
        }
    }
}

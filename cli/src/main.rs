//! `ppmc`: the command line over the conformance suite.

use std::process::ExitCode;

fn main() -> ExitCode {
    ppmc_cli::main(ppmc_scenarios::all())
}

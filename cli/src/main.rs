//! `ppmc`: the command line over the conformance suite.

use std::process::ExitCode;

fn main() -> ExitCode {
    // First: a signal from here on waits for the command's handler.
    ppmc_cli::hold_signals();
    ppmc_cli::main(ppmc_scenarios::all())
}

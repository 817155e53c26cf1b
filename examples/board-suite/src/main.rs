//! `board-suite`: ppmc's conformance suite plus this board's own
//! scenarios, with every `ppmc` command (`run`, `list`, `record`,
//! `compare`, `--target`, JUnit and JSON reports).
//!
//! ```sh
//! cargo run -p board-suite -- list --tag board
//! cargo run -p board-suite -- run --junit report.xml
//! cargo run -p board-suite -- run --target serial:/dev/ttyACM0 --tag board
//! ```

mod x_axis;

use std::process::ExitCode;

fn main() -> ExitCode {
    // First: SIGINT and SIGTERM wait for the run's handlers, so a run
    // stopped at once still writes its reports.
    ppmc_cli::hold_signals();
    let mut suite = ppmc_scenarios::all();
    suite.extend(x_axis::scenarios());
    ppmc_cli::main(suite)
}

//! `ppmc fault-matrix`: every catalogued board fault against the suite,
//! the golden traces, a bounded differential fuzz and the fuzz oracle,
//! over the pty, and judged from logic-analyzer captures of the suite
//! (made in process: a capture is the analyzer's, not the link's).

use crate::{usage, CliError};
use clap::Args;
use ppmc::emu::ModelConfig;
use ppmc::faults::{self, CATALOGUE};
use ppmc::scenario::Scenario;
use ppmc_capture::fault_matrix::{self, FuzzBudget, Row};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct MatrixArgs {
    /// List the board faults with what each does and the datasheet section
    /// it breaks, and exit.
    #[arg(long)]
    list: bool,
    /// Only these faults (repeatable); the clean board is always a row.
    #[arg(long = "fault", value_name = "NAME")]
    only: Vec<String>,
    /// Run each board in process instead of behind `bridge-sim` on a pty.
    #[arg(long)]
    in_process: bool,
    /// Fuzz seeds per board (the differential fuzz and the oracle run the
    /// same programs).
    #[arg(long, default_value_t = 8)]
    fuzz_seeds: u64,
    /// Actions per fuzz seed.
    #[arg(long, default_value_t = 300)]
    fuzz_actions: usize,
    /// Golden trace directory.
    #[arg(long, default_value = "golden")]
    golden: PathBuf,
    /// Also write the matrix and what each check saw first (Markdown).
    #[arg(short, long)]
    output: Option<PathBuf>,
}

pub fn run(args: MatrixArgs, suite: &[Scenario]) -> Result<(), CliError> {
    if args.list {
        outln!("| fault | section | what the board does |\n|---|---|---|");
        for f in CATALOGUE {
            outln!("| `{}` | {} | {} |", f.name, f.section, f.what);
        }
        return Ok(());
    }
    if !args.golden.is_dir() {
        return Err(usage(format!(
            "{} is not a directory: run from the repository root or give --golden",
            args.golden.display()
        )));
    }
    // Tried before the matrix runs, not found unusable after it.
    if let Some(path) = &args.output {
        ppmc_files::check_writable(path)?;
    }
    let mut boards: Vec<(String, ModelConfig)> = vec![("clean".into(), ModelConfig::default())];
    for f in CATALOGUE {
        if args.only.is_empty() || args.only.iter().any(|n| n == f.name) {
            boards.push((f.name.to_string(), f.model()));
        }
    }
    if let Some(unknown) = args.only.iter().find(|n| faults::find(n).is_none()) {
        return Err(usage(format!(
            "--fault {unknown}: not in the catalogue (see --list)"
        )));
    }
    let budget = FuzzBudget {
        seeds: args.fuzz_seeds,
        actions: args.fuzz_actions,
    };
    let mut rows: Vec<Row> = Vec::new();
    let total = boards.len();
    for (i, (name, model)) in boards.into_iter().enumerate() {
        {
            use std::io::Write;
            let _ = write!(std::io::stderr(), "[{}/{total}] {name} ... ", i + 1);
        }
        let row =
            fault_matrix::board_row(&name, model, args.in_process, suite, &args.golden, budget);
        let row = match row {
            Ok(r) => r,
            Err(e) => {
                errln!("infrastructure error");
                errln!("ppmc fault-matrix: {name}: {e}");
                return Err(CliError::Verdict);
            }
        };
        errln!("{}", if row.caught() { "caught" } else { "not caught" });
        rows.push(row);
    }
    let table = fault_matrix::render(&rows);
    let notes = fault_matrix::capture::notes(&rows);
    outln!("{}", table.trim_end_matches('\n'));
    outln!("\n{}", notes.trim_end_matches('\n'));
    if let Some(path) = &args.output {
        let mut text = table.clone();
        text.push('\n');
        text.push_str(&notes);
        text.push_str("\nWhat each check saw first:\n\n");
        text.push_str(&fault_matrix::first_seen(&rows));
        ppmc_files::write_report(path, text.as_bytes())?;
    }
    if fault_matrix::all_as_expected(&rows) {
        outln!("\nevery fault caught, no false alarm on the clean board");
        Ok(())
    } else {
        outln!("\nthe matrix is NOT as it must be (see MISSED / FALSE ALARM above)");
        Err(CliError::Verdict)
    }
}

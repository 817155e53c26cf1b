//! `ppmc history`: what a results store says across runs, as text.

use crate::CliError;
use clap::Args;
use ppmc_record::printable as p;
use ppmc_report::store::Store;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct HistoryArgs {
    /// The results store (`ppmc run --store FILE` makes and fills it).
    #[arg(long, value_name = "FILE")]
    store: PathBuf,
    /// Scenarios listed at most, lowest pass rate first (0: all).
    #[arg(long, value_name = "N", default_value_t = 10)]
    scenarios: usize,
}

pub fn run(args: HistoryArgs) -> Result<(), CliError> {
    let store =
        Store::open_existing(&args.store).map_err(|e| CliError::BadInput(format!("ppmc: {e}")))?;
    let h = store
        .history()
        .map_err(|e| CliError::Failed(e.to_string()))?;
    // Every text of the store printed through `p`: a label a lab script
    // planted may hold a terminal's escape sequences.
    outln!(
        "{}: {} runs, {} boards{}",
        args.store.display(),
        h.runs,
        h.boards,
        h.span
            .as_ref()
            .map_or(String::new(), |(a, b)| format!(", {} to {}", p(a), p(b)))
    );
    outln!("yield per revision (a board test passes when none of its scenarios failed, erred or was not run):");
    for r in &h.revisions {
        outln!(
            "  {:<12} {:>6.1}%  {} of {} board tests passed, {} boards{}",
            p(&r.rev),
            r.rate() * 100.0,
            r.passed,
            r.tests,
            r.boards,
            if r.flaky > 0 {
                format!(", {} flaky results", r.flaky)
            } else {
                String::new()
            }
        );
    }
    let shown = match args.scenarios {
        0 => h.scenarios.len(),
        n => n.min(h.scenarios.len()),
    };
    outln!(
        "scenarios, lowest pass rate first ({shown} of {}):",
        h.scenarios.len()
    );
    for s in &h.scenarios[..shown] {
        outln!(
            "  {:>6.1}%  {} (section {}): {} results, {} failed, {} errors, {} flaky, {} not run, {} boards",
            s.rate() * 100.0,
            p(&s.scenario),
            p(&s.section),
            s.results,
            s.failed,
            s.errors,
            s.flaky,
            s.not_run,
            s.boards
        );
    }
    outln!("measurements by scenario and revision (Cpk of each value's place in its band; none where they all sit at one place):");
    for d in &h.measurements {
        outln!(
            "  {} in {} on {}: n={} mean={:.3}us sd={:.1}ns min={:.3}us max={:.3}us Cpk={}",
            p(&d.name),
            p(&d.scenario),
            p(&d.rev),
            d.values.len(),
            d.mean_ns / 1e3,
            d.sd_ns(),
            d.min_ns as f64 / 1e3,
            d.max_ns as f64 / 1e3,
            d.cpk().map_or("none".to_string(), |c| format!("{c:.2}"))
        );
    }
    Ok(())
}

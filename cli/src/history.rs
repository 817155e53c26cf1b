//! `ppmc history`: what a results store says across runs, as text.

use crate::CliError;
use clap::Args;
use ppmc_record::printable as p;
use ppmc_report::store::Store;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct HistoryArgs {
    /// The results store (`ppmc run --store FILE` makes and fills it): a
    /// file, or a PostgreSQL database (`postgres://user@host/db`).
    #[arg(
        long,
        value_name = "FILE|URL",
        env = "PPMC_STORE",
        hide_env_values = true
    )]
    store: PathBuf,
    /// Scenarios listed at most, lowest pass rate first (0: all).
    #[arg(long, value_name = "N", default_value_t = 10)]
    scenarios: usize,
}

/// Nanoseconds as microseconds, as every figure of this listing is.
fn us(ns: f64) -> String {
    format!("{:.3}us", ns / 1e3)
}

fn plural<'a>(n: u64, one: &'a str, many: &'a str) -> &'a str {
    if n == 1 {
        one
    } else {
        many
    }
}

pub fn run(args: HistoryArgs) -> Result<(), CliError> {
    let mut store = Store::open_existing(&args.store).map_err(crate::store::store_error)?;
    let h = store.history().map_err(crate::store::store_error)?;
    // Every text of the store printed through `p`: a label a lab script
    // planted may hold a terminal's escape sequences.
    outln!(
        "{}: {} runs, {} boards{}",
        p(&store.shown()),
        h.runs,
        h.boards,
        h.span
            .as_ref()
            .map_or(String::new(), |(a, b)| format!(", {} to {}", p(a), p(b)))
    );
    outln!("yield per revision (a board test passes when none of its scenarios failed, erred or was not run):");
    for r in &h.revisions {
        outln!(
            "  {:<12} {:>6.1}%  {} of {} {} passed, on {} {}{}",
            p(&r.rev),
            r.rate() * 100.0,
            r.passed,
            r.tests,
            plural(r.tests, "board test", "board tests"),
            r.boards,
            plural(r.boards, "board", "boards"),
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
    // Out of band first (most values out first), then the least capable.
    let mut ds: Vec<_> = h.measurements.iter().collect();
    ds.sort_by(|a, b| {
        b.out_of_band().cmp(&a.out_of_band()).then(
            a.cpk()
                .unwrap_or(f64::INFINITY)
                .total_cmp(&b.cpk().unwrap_or(f64::INFINITY)),
        )
    });
    outln!("measurements by scenario and revision, out of band first, then lowest Cpk (of each value's place in its own band; none where they all sit at one place):");
    for d in ds {
        let out = d.out_of_band();
        let flag = match out {
            0 => "          ".to_string(),
            n => format!("OUT {n:>2}/{:<2} ", d.values.len()),
        };
        let band = match (d.bands_differ, d.hi_ns) {
            (true, _) => "band per board (straps differ)".to_string(),
            (false, Some(hi)) => format!("band {} to {}", us(d.lo_ns as f64), us(hi as f64)),
            (false, None) => format!("band from {}", us(d.lo_ns as f64)),
        };
        outln!(
            "  {flag}{} in {} on {}: n={} mean={} sd={} min={} max={}, {band}, Cpk={}",
            p(&d.name),
            p(&d.scenario),
            p(&d.rev),
            d.values.len(),
            us(d.mean_ns),
            us(d.sd_ns()),
            us(d.min_ns as f64),
            us(d.max_ns as f64),
            d.cpk().map_or("none".to_string(), |c| format!("{c:.2}"))
        );
    }
    Ok(())
}

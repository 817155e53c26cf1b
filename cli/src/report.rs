//! `ppmc report`: the HTML report of run records, or of a results store.

use crate::{usage, CliError};
use clap::Args;
use ppmc_files as files;
use ppmc_record::RunRecord;
use ppmc_report as report;
use ppmc_report::store::Store;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct ReportArgs {
    /// Run records (`ppmc run --json`, `ppmc compare --json`), drawn in
    /// the order given.
    #[arg(
        value_name = "RECORD",
        required_unless_present = "store",
        conflicts_with = "store"
    )]
    records: Vec<PathBuf>,
    /// Draw a results store's history instead (`--store` of `ppmc run`):
    /// yield per revision, each measurement's distribution per revision
    /// against its band with its Cpk, each scenario's pass rate across
    /// boards, the trend over time. A file, or a PostgreSQL database
    /// (`postgres://user@host/db`).
    #[arg(long, value_name = "FILE|URL")]
    store: Option<PathBuf>,
    /// Where to write the page (replaced if it is there); `-` for
    /// standard output.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    output: PathBuf,
    /// The page's title.
    #[arg(long, default_value = "ppmc report")]
    title: String,
}

pub fn run(args: ReportArgs) -> Result<(), CliError> {
    files::check_writable(&args.output)?;
    if let Some(path) = &args.store {
        if files::same_file(path, &args.output) {
            return Err(usage(format!(
                "-o {}: that is the store to draw; name another file",
                args.output.display()
            )));
        }
        let mut store = Store::open_existing(path).map_err(crate::store::store_error)?;
        let history = store.history().map_err(crate::store::store_error)?;
        let page = report::history_html(&history, &args.title, &store.shown());
        files::write_report(&args.output, page.as_bytes())?;
        if args.output.as_os_str() != "-" {
            outln!(
                "wrote {} ({} runs, {} boards, {} KB)",
                args.output.display(),
                history.runs,
                history.boards,
                page.len().div_ceil(1024)
            );
        }
        return Ok(());
    }
    if args.records.is_empty() {
        return Err(usage(
            "give one or more run records (ppmc run --json FILE makes one), or --store FILE",
        ));
    }
    let mut records = Vec::with_capacity(args.records.len());
    for path in &args.records {
        if files::same_file(path, &args.output) {
            return Err(usage(format!(
                "-o {}: that is a run record given to draw; name another file",
                args.output.display()
            )));
        }
        records.push(RunRecord::read(path).map_err(|e| CliError::BadInput(format!("ppmc: {e}")))?);
    }
    let page = report::html(&records, &args.title);
    files::write_report(&args.output, page.as_bytes())?;
    if args.output.as_os_str() != "-" {
        outln!(
            "wrote {} ({} run record{}, {} KB)",
            args.output.display(),
            records.len(),
            if records.len() == 1 { "" } else { "s" },
            page.len().div_ceil(1024)
        );
    }
    Ok(())
}

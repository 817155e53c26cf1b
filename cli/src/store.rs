//! `ppmc store`: a results store by hand. `push` sends run records a store
//! did not take when they were made (its server out of reach), or records
//! of runs made without `--store`; each run is kept once, however often it
//! is sent.

use crate::CliError;
use clap::{Args, Subcommand};
use ppmc_record::RunRecord;
use ppmc_report::store::{Added, Fault, Store, StoreError};
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
pub struct StoreArgs {
    #[command(subcommand)]
    command: StoreCommand,
}

#[derive(Debug, Subcommand)]
enum StoreCommand {
    /// Send run records to a store: `--json` records of run, compare and
    /// judge, and the `ppmc-unsent-*.json` a run keeps when its store is
    /// out of reach. A run already in the store (the same run id) is not
    /// added again. Exit status 0 when every record is in the store, 1
    /// when the store failed, 2 when a record cannot be read (the others
    /// are still sent).
    Push {
        /// The results store: a file, or `postgres://user@host/db`.
        #[arg(
            long,
            value_name = "FILE|URL",
            env = "PPMC_STORE",
            hide_env_values = true
        )]
        store: PathBuf,
        /// The run records to send.
        #[arg(value_name = "RECORD", required = true)]
        records: Vec<PathBuf>,
    },
}

pub fn run(args: StoreArgs) -> Result<(), CliError> {
    let StoreCommand::Push { store, records } = args.command;
    let mut store = Store::open(&store).map_err(store_error)?;
    let (mut kept, mut already, mut unreadable) = (0, 0, 0);
    for path in &records {
        let record = match RunRecord::read(path) {
            Ok(r) => r,
            Err(e) => {
                errln!("ppmc: {e}: not sent");
                unreadable += 1;
                continue;
            }
        };
        match store.add(&record).map_err(store_error)? {
            Added::New(id) => {
                kept += 1;
                outln!("{}: kept, run {id} of {}", path.display(), store.shown());
            }
            Added::Already => {
                already += 1;
                outln!("{}: in the store already: not added again", path.display());
            }
        }
    }
    outln!(
        "store push: {kept} kept, {already} already there, {unreadable} unreadable, into {}",
        store.shown()
    );
    match unreadable {
        0 => Ok(()),
        n => Err(CliError::BadInput(format!(
            "ppmc: store push: {n} record{} could not be read (named above)",
            if n == 1 { "" } else { "s" }
        ))),
    }
}

/// A store's trouble as the command's: the store's own damage or a path
/// or URL that cannot be one is the user's input (exit 2), wherever it
/// was found; a server out of reach is the lab's (exit 1).
pub(super) fn store_error(e: StoreError) -> CliError {
    match e.fault {
        Fault::Store => CliError::BadInput(format!("ppmc: {e}")),
        Fault::Link => CliError::Infrastructure(e.to_string()),
        Fault::Other => CliError::Failed(e.to_string()),
    }
}

/// Opens the results store a run will keep its record in, before the run:
/// a store that cannot be used is found before the boards' time is spent.
pub(super) fn open_store(path: Option<&Path>) -> Result<Option<Store>, CliError> {
    path.map(|p| {
        Store::open(p).map_err(|e| match e.fault {
            Fault::Link => CliError::Infrastructure(format!("ppmc: --store {e}")),
            _ => CliError::BadInput(format!("ppmc: --store {e}")),
        })
    })
    .transpose()
}

/// The run's record is not in the store: where it is kept instead.
pub(super) fn unsent(record: &RunRecord, json: Option<&Path>, e: &StoreError) -> String {
    match ppmc_report::store::keep_unsent(record, json) {
        Ok(path) => format!(
            "--store {e}: the run's record was not kept in the store; it is in {}: `ppmc store push {}` sends it when the store is back",
            path.display(),
            path.display()
        ),
        Err(why) => format!(
            "--store {e}: the run's record was not kept in the store, nor on disk ({why}): give --json FILE to keep the next one"
        ),
    }
}

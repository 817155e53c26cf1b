//! `ppmc store`: a results store by hand. `push` sends run records a store
//! did not take when they were made (its server out of reach), or records
//! of runs made without `--store`; each run is kept once, however often it
//! is sent.

use crate::CliError;
use clap::{Args, Subcommand};
use ppmc_record::RunRecord;
use ppmc_report::store::{Added, Store};
use std::path::PathBuf;

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
        #[arg(long, value_name = "FILE|URL", env = "PPMC_STORE")]
        store: PathBuf,
        /// The run records to send.
        #[arg(value_name = "RECORD", required = true)]
        records: Vec<PathBuf>,
    },
}

pub fn run(args: StoreArgs) -> Result<(), CliError> {
    let StoreCommand::Push { store, records } = args.command;
    let mut store = Store::open(&store).map_err(crate::reports::store_error)?;
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
        match store.add(&record).map_err(crate::reports::store_error)? {
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

//! The results store: every run record kept in one SQLite file
//! (`--store results.db`), keyed by board serial, revision, bridge, ppmc
//! version, commit and time, for `ppmc history` and `ppmc report --store`
//! (`docs/results-store.md`).
//!
//! `mod.rs` opens a store (made new, or an older one brought up to this
//! schema) and adds run records to it; `stats.rs` asks it what a lab
//! wants to know: yield per revision, each scenario's pass rate, each
//! measurement's spread and Cpk, revision against revision, the trend.
//!
//! The schema is versioned by SQLite's `user_version`: [`SCHEMA`] is this
//! ppmc's; an older store is migrated in place, in one transaction, by
//! [`MIGRATIONS`]; a newer one is refused, never written.

mod stats;

pub use stats::{
    mean_sd, BoardRecord, Distribution, History, RevisionYield, ScenarioRate, TrendPoint,
};

use ppmc_record::RunRecord;
use rusqlite::{params, Connection, OpenFlags, Transaction, TransactionBehavior};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// This ppmc's store schema.
pub const SCHEMA: u32 = 1;

/// Each schema from the first, as the statements that make it from the one
/// before (`MIGRATIONS[0]` makes schema 1 from an empty file). A store at
/// schema N runs `MIGRATIONS[N..]`. Never edit one that has shipped: add
/// the next.
pub const MIGRATIONS: [&str; 1] = [r#"
CREATE TABLE runs (
    id              INTEGER PRIMARY KEY,
    started         TEXT    NOT NULL,  -- RFC 3339, UTC
    harness_version TEXT    NOT NULL,
    git_revision    TEXT    NOT NULL,
    host            TEXT    NOT NULL,
    source          TEXT    NOT NULL,  -- 'boards' or 'capture'
    wall_s          REAL    NOT NULL,
    passed          INTEGER NOT NULL,
    marginal        INTEGER NOT NULL,
    flaky           INTEGER NOT NULL,
    failed          INTEGER NOT NULL,
    errors          INTEGER NOT NULL,
    not_run         INTEGER NOT NULL,
    record          TEXT    NOT NULL   -- the JSON run record, without its figures
);
CREATE TABLE boards (
    id              INTEGER PRIMARY KEY,
    run_id          INTEGER NOT NULL REFERENCES runs(id),
    name            TEXT    NOT NULL,
    target          TEXT    NOT NULL,
    board_serial    TEXT,
    board_rev       TEXT,
    bridge_firmware TEXT,
    bridge_serial   TEXT,
    reached         INTEGER NOT NULL   -- 0: the board took no part
);
CREATE TABLE results (
    id         INTEGER PRIMARY KEY,
    run_id     INTEGER NOT NULL REFERENCES runs(id),
    board_id   INTEGER REFERENCES boards(id),
    scenario   TEXT    NOT NULL,
    section    TEXT    NOT NULL,
    pass       INTEGER,
    verdict    TEXT    NOT NULL,  -- passed, marginal, flaky, failed, error, not_run
    blame      TEXT,              -- judged from a capture: board, host or capture
    attempts   INTEGER NOT NULL,  -- how many times it ran
    elapsed_ns INTEGER NOT NULL,
    detail     TEXT
);
CREATE TABLE measurements (
    result_id      INTEGER NOT NULL REFERENCES results(id),
    name           TEXT    NOT NULL,
    value_ns       INTEGER NOT NULL,
    lo_ns          INTEGER NOT NULL,
    hi_ns          INTEGER,          -- NULL: no upper limit
    marginal_lo_ns INTEGER NOT NULL,
    marginal_hi_ns INTEGER,
    grade          TEXT    NOT NULL
);
CREATE INDEX boards_run ON boards(run_id);
CREATE INDEX boards_rev ON boards(board_rev, board_serial);
CREATE INDEX results_run ON results(run_id);
CREATE INDEX results_board ON results(board_id);
CREATE INDEX results_scenario ON results(scenario);
CREATE INDEX measurements_result ON measurements(result_id);
CREATE INDEX measurements_name ON measurements(name);
"#];

/// A store that could not be opened, read or written: the file, and why.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {why}")]
pub struct StoreError {
    pub path: PathBuf,
    pub why: String,
}

/// An open results store.
#[derive(Debug)]
pub struct Store {
    conn: Connection,
    path: PathBuf,
    /// The migrated copy an older store is read through, removed on drop.
    _copy: Option<tempfile::NamedTempFile>,
}

impl Store {
    /// Opens the store at `path`, made new when nothing is there, an older
    /// one migrated to [`SCHEMA`]. A symlink, a folder, a file that is not
    /// SQLite, or a store of a newer ppmc is refused by name.
    pub fn open(path: &Path) -> Result<Store, StoreError> {
        Store::open_with(path, true)
    }

    /// Opens an existing store to read it, changing nothing in it: a store
    /// of an older schema is migrated in a temporary copy, so that an
    /// archived store, read-only or shared, reads as it is.
    pub fn open_existing(path: &Path) -> Result<Store, StoreError> {
        Store::open_existing_with(path, &MIGRATIONS)
    }

    /// [`Store::open_existing`] with `migrations` as this ppmc's (its
    /// schema their count): a test brings a store to a schema to come.
    fn open_existing_with(path: &Path, migrations: &[&str]) -> Result<Store, StoreError> {
        let err = |why: String| StoreError {
            path: path.to_path_buf(),
            why,
        };
        // Not there at all; a dangling link is named as a link below.
        if std::fs::symlink_metadata(path).is_err() {
            return Err(err(
                "no results store here (ppmc run --store FILE makes one)".into(),
            ));
        }
        ppmc_files::check_replaceable(path).map_err(|e| err(e.to_string()))?;
        let flags = OpenFlags::SQLITE_OPEN_READ_ONLY
            | OpenFlags::SQLITE_OPEN_NOFOLLOW
            | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let conn = Connection::open_with_flags(path, flags).map_err(|e| err(e.to_string()))?;
        conn.busy_timeout(Duration::from_secs(30))
            .map_err(|e| err(e.to_string()))?;
        let store = Store {
            conn,
            path: path.to_path_buf(),
            _copy: None,
        };
        let (at, schema) = (store.schema()?, migrations.len() as u32);
        if at == schema {
            return Ok(store);
        }
        if at == 0 {
            return Err(err(
                "not a ppmc results store: it has no schema version (an empty file, or another program's SQLite file)".into(),
            ));
        }
        if at > schema {
            return Err(err(newer(at, schema)));
        }
        let copying = |e: &dyn std::fmt::Display| {
            err(format!(
                "copying the store to read it at schema {schema}: {e}"
            ))
        };
        let copy = tempfile::Builder::new()
            .prefix("ppmc-store-")
            .suffix(".db")
            .tempfile()
            .map_err(|e| copying(&e))?;
        // SQLite's own copy, consistent even while another ppmc writes; it
        // must make the file itself.
        let target = copy.path().to_path_buf();
        std::fs::remove_file(&target).map_err(|e| copying(&e))?;
        store
            .conn
            .execute("VACUUM INTO ?1", [target.to_string_lossy()])
            .map_err(|e| copying(&e))?;
        let flags = OpenFlags::SQLITE_OPEN_READ_WRITE | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let conn = Connection::open_with_flags(&target, flags).map_err(|e| err(e.to_string()))?;
        let mut s = Store {
            conn,
            path: path.to_path_buf(),
            _copy: Some(copy),
        };
        s.migrate_with(migrations)?;
        Ok(s)
    }

    fn open_with(path: &Path, create: bool) -> Result<Store, StoreError> {
        let err = |why: String| StoreError {
            path: path.to_path_buf(),
            why,
        };
        ppmc_files::check_replaceable(path).map_err(|e| err(e.to_string()))?;
        // A store in a folder not there yet: the folder is made, as a
        // report's would be.
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent)
                .map_err(|e| err(format!("making its folder {}: {e}", parent.display())))?;
        }
        let mut flags = OpenFlags::SQLITE_OPEN_READ_WRITE
            | OpenFlags::SQLITE_OPEN_NOFOLLOW
            | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        if create {
            flags |= OpenFlags::SQLITE_OPEN_CREATE;
        }
        let conn = Connection::open_with_flags(path, flags).map_err(|e| err(e.to_string()))?;
        // Two CI jobs writing one store wait for each other, briefly.
        conn.busy_timeout(Duration::from_secs(30))
            .map_err(|e| err(e.to_string()))?;
        let mut store = Store {
            conn,
            path: path.to_path_buf(),
            _copy: None,
        };
        store.migrate()?;
        Ok(store)
    }

    fn fail(&self, e: impl std::fmt::Display) -> StoreError {
        StoreError {
            path: self.path.clone(),
            why: e.to_string(),
        }
    }

    /// The store's schema version.
    pub fn schema(&self) -> Result<u32, StoreError> {
        self.conn
            .query_row("PRAGMA user_version", [], |r| r.get(0))
            .map_err(|e| self.fail(not_a_store(e)))
    }

    /// Brings the store to [`SCHEMA`], in one transaction.
    fn migrate(&mut self) -> Result<(), StoreError> {
        self.migrate_with(&MIGRATIONS)
    }

    /// Brings the store to the schema of `migrations`, in one transaction
    /// that holds the write lock from its start: of two ppmc making one
    /// new store at once, the second finds it made.
    fn migrate_with(&mut self, migrations: &[&str]) -> Result<(), StoreError> {
        let schema = migrations.len() as u32;
        if self.schema()? == schema {
            return Ok(());
        }
        let path = self.path.clone();
        let tx = self
            .conn
            .transaction_with_behavior(TransactionBehavior::Immediate)
            .map_err(|e| fail_at(&path, not_a_store(e)))?;
        let at: u32 = tx
            .query_row("PRAGMA user_version", [], |r| r.get(0))
            .map_err(|e| fail_at(&path, not_a_store(e)))?;
        if at > schema {
            return Err(fail_at(&path, newer(at, schema)));
        }
        if at == schema {
            return Ok(());
        }
        if at == 0 {
            // Version 0 is a new, empty file, or some other SQLite file.
            let tables: i64 = tx
                .query_row("SELECT count(*) FROM sqlite_master", [], |r| r.get(0))
                .map_err(|e| fail_at(&path, not_a_store(e)))?;
            if tables > 0 {
                return Err(fail_at(
                    &path,
                    "an SQLite file that is not a ppmc results store (it has tables, and no schema version)",
                ));
            }
        }
        for (n, step) in migrations.iter().enumerate().skip(at as usize) {
            tx.execute_batch(step)
                .map_err(|e| fail_at(&path, format!("migrating to schema {}: {e}", n + 1)))?;
        }
        tx.pragma_update(None, "user_version", schema)
            .map_err(|e| fail_at(&path, e))?;
        tx.commit().map_err(|e| fail_at(&path, e))
    }

    /// Adds a run record, in one transaction: the run, its boards, every
    /// result and measurement. Returns the run's id in the store.
    pub fn add(&mut self, record: &RunRecord) -> Result<i64, StoreError> {
        let path = self.path.clone();
        let text = stored_text(record).map_err(|e| fail_at(&path, e))?;
        let tx = self.conn.transaction().map_err(|e| fail_at(&path, e))?;
        let id = insert(&tx, record, &text).map_err(|e| fail_at(&path, e))?;
        tx.commit().map_err(|e| fail_at(&path, e))?;
        Ok(id)
    }

    /// How many runs the store holds.
    pub fn runs(&self) -> Result<u64, StoreError> {
        self.conn
            .query_row("SELECT count(*) FROM runs", [], |r| r.get(0))
            .map_err(|e| self.fail(e))
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    pub(crate) fn conn(&self) -> &Connection {
        &self.conn
    }
}

/// The refusal of a store a newer ppmc made.
fn newer(at: u32, schema: u32) -> String {
    format!(
        "a results store of schema {at}, made by a newer ppmc; this one reads schemas up to {schema}: update ppmc"
    )
}

fn fail_at(path: &Path, e: impl std::fmt::Display) -> StoreError {
    StoreError {
        path: path.to_path_buf(),
        why: e.to_string(),
    }
}

/// SQLite's word for a file that is not a database, in ours.
fn not_a_store(e: rusqlite::Error) -> String {
    match e.sqlite_error_code() {
        Some(rusqlite::ErrorCode::NotADatabase) => {
            "not a results store (not an SQLite file)".to_string()
        }
        _ => e.to_string(),
    }
}

/// The record as the store keeps it: without its figures, which only the
/// run's own report draws, and which would make a lab's store grow by
/// the pulse runs of every move.
fn stored_text(record: &RunRecord) -> Result<String, serde_json::Error> {
    let mut kept = record.clone();
    for s in &mut kept.scenarios {
        s.figures = None;
    }
    serde_json::to_string(&kept)
}

fn insert(tx: &Transaction, r: &RunRecord, text: &str) -> rusqlite::Result<i64> {
    let s = &r.summary;
    let source = if r.run.source.is_some() {
        "capture"
    } else {
        "boards"
    };
    tx.execute(
        "INSERT INTO runs (started, harness_version, git_revision, host, source, wall_s,
             passed, marginal, flaky, failed, errors, not_run, record)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13)",
        params![
            r.run.started,
            r.run.harness_version,
            r.run.git_revision,
            r.run.host,
            source,
            r.run.wall_s,
            s.passed,
            s.marginal,
            s.flaky,
            s.failed,
            s.errors,
            s.not_run,
            text,
        ],
    )?;
    let run = tx.last_insert_rowid();
    let mut board_ids = Vec::with_capacity(r.run.boards.len());
    for b in &r.run.boards {
        tx.execute(
            "INSERT INTO boards (run_id, name, target, board_serial, board_rev,
                 bridge_firmware, bridge_serial, reached)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)",
            params![
                run,
                b.name,
                b.target,
                b.board_serial,
                b.board_rev,
                b.bridge_firmware,
                b.bridge_serial,
                b.error.is_none(),
            ],
        )?;
        board_ids.push((b.name.as_str(), tx.last_insert_rowid()));
    }
    let mut result = tx.prepare(
        "INSERT INTO results (run_id, board_id, scenario, section, pass, verdict, blame,
             attempts, elapsed_ns, detail)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)",
    )?;
    let mut measure = tx.prepare(
        "INSERT INTO measurements (result_id, name, value_ns, lo_ns, hi_ns, marginal_lo_ns,
             marginal_hi_ns, grade)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)",
    )?;
    for sc in &r.scenarios {
        let board = sc
            .board
            .as_deref()
            .and_then(|n| board_ids.iter().find(|(name, _)| *name == n))
            .map(|(_, id)| *id);
        let detail = sc
            .failure
            .as_ref()
            .map(|f| format!("{}: expected {}, got {}", f.expectation, f.expected, f.got))
            .or_else(|| sc.error.as_ref().map(|e| e.message.clone()))
            .or_else(|| sc.detail.clone());
        result.execute(params![
            run,
            board,
            sc.name,
            sc.section,
            sc.pass,
            sc.verdict.name(),
            sc.blame.flatten().map(|b| b.name()),
            sc.attempts.len() as i64 + 1,
            sc.elapsed_ns as i64,
            detail,
        ])?;
        let rid = tx.last_insert_rowid();
        for m in &sc.measurements {
            measure.execute(params![
                rid,
                m.name,
                m.value.as_nanos() as i64,
                m.lo.as_nanos() as i64,
                m.hi_ns().map(|v| v as i64),
                m.marginal_lo.as_nanos() as i64,
                m.marginal_hi_ns().map(|v| v as i64),
                m.grade.name(),
            ])?;
        }
    }
    Ok(run)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An older store is read through a migrated copy: the copy is at the
    /// newer schema (a column a later ppmc added is there), the file
    /// itself is not touched. Schema 2 here is a stand-in for the next.
    #[test]
    fn an_older_store_is_read_through_a_migrated_copy() {
        let dir = tempfile::tempdir().expect("scratch");
        let path = dir.path().join("old.db");
        drop(Store::open(&path).expect("made at schema 1"));
        let before = std::fs::read(&path).expect("read");
        let next = [MIGRATIONS[0], "ALTER TABLE runs ADD COLUMN note TEXT;"];
        let s = Store::open_existing_with(&path, &next).expect("read at schema 2");
        assert_eq!(s.schema().expect("schema"), 2);
        let n: i64 = s
            .conn()
            .query_row("SELECT count(note) FROM runs", [], |r| r.get(0))
            .expect("the new column");
        assert_eq!(n, 0);
        drop(s);
        assert_eq!(std::fs::read(&path).expect("read"), before, "untouched");
        // The other way round, a store of schema 2 is refused by schema 1.
        let newer_path = dir.path().join("new.db");
        let mut s = Store::open(&newer_path).expect("made");
        s.migrate_with(&next).expect("to 2");
        drop(s);
        let e = Store::open_existing(&newer_path).expect_err("refused");
        assert!(
            e.to_string().contains("schema 2, made by a newer ppmc"),
            "{e}"
        );
    }
}

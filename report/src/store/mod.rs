//! The results store: every run record kept in one database, keyed by
//! board serial, revision, bridge, ppmc version, commit and time, for
//! `ppmc history` and `ppmc report --store` (`docs/results-store.md`).
//! One station's store is an SQLite file (`--store results.db`); a lab's
//! is a PostgreSQL database that every station writes to
//! (`--store postgres://user@host/db`).
//!
//! `mod.rs` opens a store (made new, or an older one brought up to this
//! schema) and adds run records to it, each once; `schema.rs` is the
//! schema and what the two databases spell differently; `db.rs` one
//! connection to either; `location.rs` where a store is; `stats.rs` asks
//! it what a lab wants to know: yield per revision, each scenario's pass
//! rate, each measurement's spread and Cpk, revision against revision,
//! the trend.
//!
//! [`SCHEMA`] is this ppmc's; an older store is migrated in place, in one
//! transaction, by [`MIGRATIONS`]; a newer one is refused, never written.

mod db;
mod location;
mod schema;
mod stats;
mod unsent;

pub use db::Dialect;
pub use location::{redact, Location, Server, TlsMode};
pub use schema::{MIGRATIONS, SCHEMA};
pub use stats::{
    mean_sd, BoardRecord, Distribution, History, RevisionYield, ScenarioRate, TrendPoint,
};
pub use unsent::keep_unsent;

use db::{Conn, DbError, Pg, Value};
use ppmc_record::RunRecord;
use rusqlite::{Connection, OpenFlags};
use std::path::Path;
use std::time::Duration;

/// A store that could not be opened, read or written: where it is (the
/// file, or the server's URL without its password), and why.
#[derive(Debug, thiserror::Error)]
#[error("{at}: {why}")]
pub struct StoreError {
    pub at: String,
    pub why: String,
    pub fault: Fault,
}

/// Whose the trouble is, for the exit status.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// The store is damaged or none of ppmc's, or the path or URL given
    /// cannot be a store: the user's input (exit 2, wherever it is found).
    Store,
    /// The server could not be reached, or was lost: the lab's network or
    /// server, not the store.
    Link,
    /// Anything else the database said.
    Other,
}

/// An open results store.
#[derive(Debug)]
pub struct Store {
    conn: Conn,
    location: Location,
    /// The migrated copy an older SQLite store is read through, removed on
    /// drop.
    _copy: Option<tempfile::NamedTempFile>,
}

/// The oldest schema every read (`history`, `report --store`) works on as
/// it is: an older PostgreSQL store is read so, never migrated by a read.
/// Raise it when a read comes to need a later schema's column.
pub const READS_FROM: u32 = 1;

/// What [`Store::add`] did with a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Added {
    /// Kept, as the run of this id in the store.
    New(i64),
    /// Already there (sent before): kept once.
    Already,
}

impl Store {
    /// Opens the store `given` names (a file, or a `postgres://` URL),
    /// made new when nothing is there, an older one migrated to
    /// [`SCHEMA`]. A symlink, a folder, a file that is not SQLite, a
    /// database of another program or a store of a newer ppmc is refused
    /// by name.
    pub fn open(given: &Path) -> Result<Store, StoreError> {
        Store::open_with(given, &MIGRATIONS)
    }

    /// Opens an existing store to read it, changing nothing in it: an
    /// older SQLite store is read through a migrated temporary copy, an
    /// older PostgreSQL store as it is (from [`READS_FROM`] on), so that an
    /// archived store, read-only or shared, reads as it is.
    pub fn open_existing(given: &Path) -> Result<Store, StoreError> {
        Store::open_existing_with(given, &MIGRATIONS)
    }

    fn locate(given: &Path) -> Result<Location, StoreError> {
        Location::of(given).map_err(|why| StoreError {
            at: redact(&given.to_string_lossy()),
            why,
            fault: Fault::Store,
        })
    }

    /// [`Store::open_existing`] with `migrations` as this ppmc's (its
    /// schema their count): a test brings a store to a schema to come.
    fn open_existing_with(given: &Path, migrations: &[&str]) -> Result<Store, StoreError> {
        let location = Store::locate(given)?;
        let path = match &location {
            Location::File(path) => path.clone(),
            Location::Server(server) => {
                // Read as it is: every query a read asks works on every
                // schema from READS_FROM on, so a read needs no migration,
                // no right to change the tables, and no lock on them.
                let conn = Conn::Postgres(Box::new(Pg::new(connect(server)?)));
                let mut store = Store::with(conn, location.clone());
                let at = store.schema()?;
                store.check_version(at, migrations.len() as u32, false)?;
                if at < READS_FROM {
                    return Err(store.fail(DbError::corrupt(format!(
                        "a results store of schema {at}, which this ppmc reads from schema {READS_FROM} on"
                    ))));
                }
                return Ok(store);
            }
        };
        let err = |why: String| StoreError {
            at: path.display().to_string(),
            why,
            fault: Fault::Store,
        };
        // Not there at all; a dangling link is named as a link below.
        if std::fs::symlink_metadata(&path).is_err() {
            return Err(err(
                "no results store here (ppmc run --store FILE makes one)".into(),
            ));
        }
        ppmc_files::check_replaceable(&path).map_err(|e| err(e.to_string()))?;
        let flags = OpenFlags::SQLITE_OPEN_READ_ONLY
            | OpenFlags::SQLITE_OPEN_NOFOLLOW
            | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let mut store = Store::with(sqlite(&path, flags)?, location.clone());
        let (at, schema) = (store.schema()?, migrations.len() as u32);
        store.check_version(at, schema, false)?;
        if at == schema {
            return Ok(store);
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
            .execute(
                "VACUUM INTO $1",
                &[Value::Text(target.to_string_lossy().into_owned())],
            )
            .map_err(|e| copying(&e.why))?;
        let flags = OpenFlags::SQLITE_OPEN_READ_WRITE | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let mut s = Store::with(sqlite(&target, flags)?, location);
        s._copy = Some(copy);
        s.migrate_with(migrations)?;
        Ok(s)
    }

    fn open_with(given: &Path, migrations: &[&str]) -> Result<Store, StoreError> {
        let location = Store::locate(given)?;
        let conn = match &location {
            Location::File(path) => {
                let err = |why: String| StoreError {
                    at: path.display().to_string(),
                    why,
                    fault: Fault::Store,
                };
                ppmc_files::check_replaceable(path).map_err(|e| err(e.to_string()))?;
                // A store in a folder not there yet: the folder is made,
                // as a report's would be.
                if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
                    std::fs::create_dir_all(parent)
                        .map_err(|e| err(format!("making its folder {}: {e}", parent.display())))?;
                }
                let flags = OpenFlags::SQLITE_OPEN_READ_WRITE
                    | OpenFlags::SQLITE_OPEN_NOFOLLOW
                    | OpenFlags::SQLITE_OPEN_NO_MUTEX
                    | OpenFlags::SQLITE_OPEN_CREATE;
                sqlite(path, flags)?
            }
            Location::Server(server) => Conn::Postgres(Box::new(Pg::new(connect(server)?))),
        };
        let mut store = Store::with(conn, location);
        store.migrate_with(migrations)?;
        Ok(store)
    }

    fn with(conn: Conn, location: Location) -> Store {
        Store {
            conn,
            location,
            _copy: None,
        }
    }

    fn fail(&self, e: impl Into<DbError>) -> StoreError {
        let e = e.into();
        StoreError {
            at: self.location.shown(),
            why: e.why,
            fault: e.fault,
        }
    }

    /// Which database the store is in.
    pub fn dialect(&self) -> Dialect {
        self.conn.dialect()
    }

    /// The store's schema version.
    pub fn schema(&mut self) -> Result<u32, StoreError> {
        schema::version(&mut self.conn).map_err(|e| self.fail(e))
    }

    /// Refuses a store ppmc cannot read at `schema`: a newer one, or (when
    /// not `empty_ok`) a database with no version.
    fn check_version(&mut self, at: u32, schema: u32, empty_ok: bool) -> Result<(), StoreError> {
        if at > schema {
            return Err(self.fail(DbError::corrupt(newer(at, schema))));
        }
        if at == 0 && !empty_ok {
            return Err(self.fail(DbError::corrupt(match self.dialect() {
                Dialect::Sqlite => "not a ppmc results store: it has no schema version (an empty file, or another program's SQLite file)",
                Dialect::Postgres => "not a ppmc results store: the database has no ppmc schema (ppmc run --store URL makes one in an empty database)",
            })));
        }
        Ok(())
    }

    /// Brings the store to the schema of `migrations`, in one transaction
    /// that holds off every other ppmc's migration from its start: of two
    /// ppmc making one new store at once, the second finds it made.
    fn migrate_with(&mut self, migrations: &[&str]) -> Result<(), StoreError> {
        if self.schema()? == migrations.len() as u32 {
            return Ok(());
        }
        schema::begin_migration(&mut self.conn).map_err(|e| self.fail(e))?;
        let done = self
            .apply(migrations)
            .and_then(|()| self.conn.batch("COMMIT").map_err(|e| self.fail(e)));
        if done.is_err() {
            let _ = self.conn.batch("ROLLBACK");
        }
        done
    }

    /// The steps from the store's schema to that of `migrations`, in the
    /// transaction begun.
    fn apply(&mut self, migrations: &[&str]) -> Result<(), StoreError> {
        let schema = migrations.len() as u32;
        let at = self.schema()?;
        self.check_version(at, schema, true)?;
        if at == schema {
            return Ok(());
        }
        if at == 0 && schema::tables(&mut self.conn).map_err(|e| self.fail(e))? > 0 {
            return Err(self.fail(DbError::corrupt(match self.dialect() {
                Dialect::Sqlite => "an SQLite file that is not a ppmc results store (it has tables, and no schema version)",
                Dialect::Postgres => "a database that is not a ppmc results store (it has tables, and no ppmc schema): give ppmc a database of its own",
            })));
        }
        let dialect = self.dialect();
        for (n, step) in migrations.iter().enumerate().skip(at as usize) {
            self.conn
                .batch(&schema::render(step, dialect))
                .map_err(|e| self.fail(format!("migrating to schema {}: {}", n + 1, e.why)))?;
        }
        schema::set_version(&mut self.conn, schema).map_err(|e| self.fail(e))
    }

    /// Adds a run record, in one transaction: the run, its boards, every
    /// result and measurement. A record already there (the same run's id;
    /// for a record with none, the same text) is kept once.
    pub fn add(&mut self, record: &RunRecord) -> Result<Added, StoreError> {
        let text = stored_text(record).map_err(|e| self.fail(e.to_string()))?;
        let key = record.run.id.clone().unwrap_or_else(|| {
            format!(
                "text:{}",
                uuid::Uuid::new_v5(&uuid::Uuid::NAMESPACE_OID, text.as_bytes())
            )
        });
        match self.add_once(record, &text, &key) {
            // A server that dropped the connection during a long run (an
            // idle timeout, a restart) is connected to again, once; the
            // transaction that failed left nothing.
            Err(e) if e.fault == Fault::Link => {
                if let (Conn::Postgres(pg), Location::Server(server)) =
                    (&mut self.conn, &self.location)
                {
                    **pg = Pg::new(connect(server)?);
                    return self.add_once(record, &text, &key);
                }
                Err(e)
            }
            done => done,
        }
    }

    fn add_once(&mut self, record: &RunRecord, text: &str, key: &str) -> Result<Added, StoreError> {
        self.conn.batch("BEGIN").map_err(|e| self.fail(e))?;
        let done = insert(&mut self.conn, record, text, key).and_then(|added| {
            self.conn.batch("COMMIT")?;
            Ok(added)
        });
        if done.is_err() {
            let _ = self.conn.batch("ROLLBACK");
        }
        done.map_err(|e| self.fail(e))
    }

    /// How many runs the store holds.
    pub fn runs(&mut self) -> Result<u64, StoreError> {
        let n = self.conn.row("SELECT count(*) FROM runs", &[]);
        n.and_then(|r| r.uint(0)).map_err(|e| self.fail(e))
    }

    /// Where the store is, as messages name it (never a password).
    pub fn shown(&self) -> String {
        self.location.shown()
    }

    pub(crate) fn conn(&mut self) -> &mut Conn {
        &mut self.conn
    }
}

fn sqlite(path: &Path, flags: OpenFlags) -> Result<Conn, StoreError> {
    let fail = |e: rusqlite::Error| {
        let e = DbError::from(e);
        StoreError {
            at: path.display().to_string(),
            why: e.why,
            // A file SQLite cannot open is the user's path.
            fault: Fault::Store,
        }
    };
    let conn = Connection::open_with_flags(path, flags).map_err(fail)?;
    // Two CI jobs writing one store wait for each other, briefly.
    conn.busy_timeout(Duration::from_secs(30)).map_err(fail)?;
    Ok(Conn::Sqlite(conn))
}

fn connect(server: &Server) -> Result<postgres::Client, StoreError> {
    server.connect().map_err(|e| StoreError {
        at: server.shown.clone(),
        why: format!("cannot reach the store's server: {}", e.why),
        fault: match e.fault {
            Fault::Store => Fault::Store,
            _ => Fault::Link,
        },
    })
}

/// The refusal of a store a newer ppmc made.
fn newer(at: u32, schema: u32) -> String {
    format!(
        "a results store of schema {at}, made by a newer ppmc; this one reads schemas up to {schema}: update ppmc"
    )
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

fn int(v: impl TryInto<i64>) -> Value {
    // Counts and nanoseconds: far below i64's end in any run.
    Value::Int(v.try_into().unwrap_or(i64::MAX))
}

fn insert(c: &mut Conn, r: &RunRecord, text: &str, key: &str) -> Result<Added, DbError> {
    let s = &r.summary;
    let source = if r.run.source.is_some() {
        "capture"
    } else {
        "boards"
    };
    let run = c.query(
        "INSERT INTO runs (started, harness_version, git_revision, host, source, wall_s,
             passed, marginal, flaky, failed, errors, not_run, record, run_key)
         VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14)
         ON CONFLICT (run_key) DO NOTHING RETURNING id",
        &[
            r.run.started.as_str().into(),
            r.run.harness_version.as_str().into(),
            r.run.git_revision.as_str().into(),
            r.run.host.as_str().into(),
            source.into(),
            r.run.wall_s.into(),
            int(s.passed),
            int(s.marginal),
            int(s.flaky),
            int(s.failed),
            int(s.errors),
            int(s.not_run),
            text.into(),
            key.into(),
        ],
    )?;
    let Some(run) = run.first() else {
        return Ok(Added::Already);
    };
    let run = run.int(0)?;
    let mut board_ids = Vec::with_capacity(r.run.boards.len());
    for b in &r.run.boards {
        let id = c
            .row(
                "INSERT INTO boards (run_id, name, target, board_serial, board_rev,
                     bridge_firmware, bridge_serial, reached)
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8) RETURNING id",
                &[
                    run.into(),
                    b.name.as_str().into(),
                    b.target.as_str().into(),
                    b.board_serial.clone().into(),
                    b.board_rev.clone().into(),
                    b.bridge_firmware.clone().into(),
                    b.bridge_serial.clone().into(),
                    int(b.error.is_none()),
                ],
            )?
            .int(0)?;
        board_ids.push((b.name.as_str(), id));
    }
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
        let rid = c
            .row(
                "INSERT INTO results (run_id, board_id, scenario, section, pass, verdict, blame,
                     attempts, elapsed_ns, detail)
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10) RETURNING id",
                &[
                    run.into(),
                    board.into(),
                    sc.name.as_str().into(),
                    sc.section.as_str().into(),
                    sc.pass.map(int).unwrap_or(Value::Null),
                    sc.verdict.name().into(),
                    sc.blame.flatten().map(|b| b.name()).into(),
                    int(sc.attempts.len() + 1),
                    int(sc.elapsed_ns),
                    detail.into(),
                ],
            )?
            .int(0)?;
        for m in &sc.measurements {
            c.execute(
                "INSERT INTO measurements (result_id, name, value_ns, lo_ns, hi_ns, marginal_lo_ns,
                     marginal_hi_ns, grade)
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8)",
                &[
                    rid.into(),
                    m.name.as_str().into(),
                    int(m.value.as_nanos()),
                    int(m.lo.as_nanos()),
                    m.hi_ns().map(int).unwrap_or(Value::Null),
                    int(m.marginal_lo.as_nanos()),
                    m.marginal_hi_ns().map(int).unwrap_or(Value::Null),
                    m.grade.name().into(),
                ],
            )?;
        }
    }
    Ok(Added::New(run))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An older store is read through a migrated copy: the copy is at the
    /// newer schema (a column a later ppmc added is there), the file
    /// itself is not touched. The step after the last is a stand-in for
    /// the next.
    #[test]
    fn an_older_store_is_read_through_a_migrated_copy() {
        let dir = tempfile::tempdir().expect("scratch");
        let path = dir.path().join("old.db");
        drop(Store::open(&path).expect("made at this schema"));
        let before = std::fs::read(&path).expect("read");
        let next = [
            MIGRATIONS[0],
            MIGRATIONS[1],
            "ALTER TABLE runs ADD COLUMN note TEXT;",
        ];
        let mut s = Store::open_existing_with(&path, &next).expect("read at the next schema");
        assert_eq!(s.schema().expect("schema"), SCHEMA + 1);
        let n = s
            .conn()
            .row("SELECT count(note) FROM runs", &[])
            .and_then(|r| r.int(0))
            .expect("the new column");
        assert_eq!(n, 0);
        drop(s);
        assert_eq!(std::fs::read(&path).expect("read"), before, "untouched");
        // The other way round, a store of the next schema is refused by
        // this one.
        let newer_path = dir.path().join("new.db");
        let mut s = Store::open(&newer_path).expect("made");
        s.migrate_with(&next).expect("to the next");
        drop(s);
        let e = Store::open_existing(&newer_path).expect_err("refused");
        assert!(
            e.to_string()
                .contains(&format!("schema {}, made by a newer ppmc", SCHEMA + 1)),
            "{e}"
        );
        assert_eq!(
            e.fault,
            Fault::Store,
            "a store this ppmc cannot read is bad input"
        );
    }
}

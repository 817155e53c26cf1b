//! The results store (issue 31, `docs/results-store.md`): a store an
//! older ppmc wrote is still read, unchanged; a store of a newer ppmc, a
//! file that is no store and a planted symlink are refused by name.

use ppmc_report::store::{Store, SCHEMA};
use std::path::{Path, PathBuf};

/// A store made from the frozen SQL of schema 1, in a scratch folder.
fn store_v1(dir: &Path) -> PathBuf {
    let path = dir.join("results.db");
    let sql = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/store-v1.sql"
    ))
    .expect("fixture");
    let c = rusqlite::Connection::open(&path).expect("open");
    c.execute_batch(&sql).expect("the fixture loads");
    drop(c);
    path
}

#[test]
fn a_store_of_schema_1_is_read_as_it_is() {
    let dir = tempfile::tempdir().expect("scratch");
    let path = store_v1(dir.path());
    let before = std::fs::read(&path).expect("read");
    // Read-only, as an archived store would be: reading changes nothing.
    let mut perms = std::fs::metadata(&path).expect("meta").permissions();
    perms.set_readonly(true);
    std::fs::set_permissions(&path, perms).expect("chmod");
    let mut store = Store::open_existing(&path).expect("an older store reads");
    assert_eq!(store.schema().expect("schema"), SCHEMA);
    let h = store.history().expect("history");
    assert_eq!(h.runs, 2);
    assert_eq!(h.boards, 2);
    let yields: Vec<(&str, u64, u64)> = h
        .revisions
        .iter()
        .map(|r| (r.rev.as_str(), r.passed, r.tests))
        .collect();
    assert_eq!(yields, [("A", 1, 1), ("B", 0, 1)]);
    let worst = &h.scenarios[0];
    assert_eq!(worst.scenario, "s3_3_4_accel_trapezoid_200_steps");
    assert_eq!((worst.passed, worst.failed, worst.boards), (1, 1, 2));
    let by_rev: Vec<(&str, u64)> = h
        .measurements
        .iter()
        .map(|d| (d.rev.as_str(), d.values[0]))
        .collect();
    assert_eq!(by_rev, [("A", 200_000), ("B", 1_200_000)]);
    drop(store);
    assert_eq!(
        std::fs::read(&path).expect("read"),
        before,
        "the store is unchanged"
    );
}

#[test]
fn a_new_store_takes_a_record_and_gives_it_back_in_its_history() {
    let dir = tempfile::tempdir().expect("scratch");
    let path = dir.path().join("new.db");
    let mut store = Store::open(&path).expect("made");
    assert_eq!(store.runs().expect("runs"), 0);
    let text = r#"{"format":"ppmc-run-record/4","run":{"harness_version":"0.1.0","git_revision":"x",
        "boards":[{"name":"emu","target":"emu","target_details":{},"board_rev":"C","board_serial":"C-7",
        "bridge_firmware":null,"bridge_serial":null,"link":null,"error":null}],"spread":"one",
        "started":"2026-11-26T10:00:00Z","wall_s":0.1,"host":"h","options":{"golden":null,
        "marginal_pct":0.25,"interval_tol_pct":1.0,"time_floor_ns":100}},
        "summary":{"passed":0,"marginal":0,"flaky":1,"failed":0,"error":0,"not_run":0},
        "scenarios":[{"name":"s","board":"emu","section":"3-1","verdict":"flaky","detail":null,
        "failure":null,"error":null,"elapsed_ns":5,"measurements":[],"figures":{"moves":[]},
        "attempts":[{"verdict":"error","detail":"link","error":{"kind":"infrastructure","message":"link"},
        "elapsed_ns":1,"wall_s":0.0}]}]}"#;
    let record = ppmc_record::RunRecord::parse(text, "t").expect("parses");
    store.add(&record).expect("kept");
    let h = store.history().expect("history");
    assert_eq!(
        (h.runs, h.revisions[0].rev.as_str(), h.revisions[0].flaky),
        (1, "C", 1)
    );
    assert_eq!(h.scenarios[0].flaky, 1);
    let kept: String = store_conn_record(&path);
    assert!(
        !kept.contains("figures"),
        "the store keeps no figures: {kept}"
    );
}

fn store_conn_record(path: &Path) -> String {
    let c = rusqlite::Connection::open(path).expect("open");
    c.query_row("SELECT record FROM runs", [], |r| r.get(0))
        .expect("a run")
}

#[test]
fn what_is_not_a_store_of_ours_is_refused_by_name() {
    let dir = tempfile::tempdir().expect("scratch");
    let newer = dir.path().join("newer.db");
    let c = rusqlite::Connection::open(&newer).expect("open");
    c.execute_batch("CREATE TABLE runs (id INTEGER); PRAGMA user_version = 99;")
        .expect("made");
    drop(c);
    let other = dir.path().join("other.db");
    let c = rusqlite::Connection::open(&other).expect("open");
    c.execute_batch("CREATE TABLE songs (title TEXT);")
        .expect("made");
    drop(c);
    let text = dir.path().join("notes.db");
    std::fs::write(
        &text,
        "these are notes, not a database, and long enough to have a header",
    )
    .expect("written");
    let link = dir.path().join("link.db");
    std::os::unix::fs::symlink(&other, &link).expect("symlink");
    for (path, says) in [
        (&newer, "newer ppmc"),
        (&other, "not a ppmc results store"),
        (&text, "not a results store"),
        (&link, "symbolic link"),
    ] {
        for opened in [
            Store::open(path).map(|_| ()),
            Store::open_existing(path).map(|_| ()),
        ] {
            let e = opened.expect_err("refused").to_string();
            assert!(
                e.contains(path.to_str().expect("utf-8")) && e.contains(says),
                "{e}"
            );
        }
    }
    assert!(Store::open_existing(&dir.path().join("none.db"))
        .expect_err("refused")
        .to_string()
        .contains("no results store here"));
}

/// The record the tests keep: one board of revision C, one flaky result.
fn a_record() -> ppmc_record::RunRecord {
    let text = r#"{"format":"ppmc-run-record/4","run":{"id":"6f1c2a4e-0b8d-4f3e-9a51-2d7c8e9f0a1b",
        "harness_version":"0.1.0","git_revision":"x",
        "boards":[{"name":"emu","target":"emu","target_details":{},"board_rev":"C","board_serial":"C-7",
        "bridge_firmware":null,"bridge_serial":null,"link":null,"error":null}],"spread":"one",
        "started":"2026-11-26T10:00:00Z","wall_s":0.1,"host":"h","options":{"golden":null,
        "marginal_pct":0.25,"interval_tol_pct":1.0,"time_floor_ns":100}},
        "summary":{"passed":0,"marginal":0,"flaky":1,"failed":0,"error":0,"not_run":0},
        "scenarios":[{"name":"s","board":"emu","section":"3-1","verdict":"flaky","detail":null,
        "failure":null,"error":null,"elapsed_ns":5000000000,"measurements":[
        {"name":"first pulse","value_ns":200000,"lo_ns":199000,"hi_ns":201000,"u_ns":0,
         "marginal_lo_ns":199500,"marginal_hi_ns":200500,"grade":"PASS","at_ns":1000}],"figures":{"moves":[]},
        "attempts":[{"verdict":"error","detail":"link","error":{"kind":"infrastructure","message":"link"},
        "elapsed_ns":1,"wall_s":0.0}]}]}"#;
    ppmc_record::RunRecord::parse(text, "t").expect("parses")
}

/// Each backend's store for one test: a new SQLite file, and a new
/// database on PostgreSQL where there is one (CI's; see
/// `ppmc_test_support::postgres`).
fn both(dir: &Path) -> Vec<(PathBuf, Option<ppmc_test_support::postgres::Db>)> {
    let mut out = vec![(dir.join("results.db"), None)];
    if let Some(db) = ppmc_test_support::postgres::Db::new() {
        out.push((PathBuf::from(&db.url), Some(db)));
    }
    out
}

/// A run is kept once, however often its record is sent (`ppmc store
/// push` after a store was out of reach): its id is its key. A record of
/// an older ppmc (no id) is known by its text.
#[test]
fn each_backend_keeps_a_run_once() {
    use ppmc_report::store::Added;
    let dir = tempfile::tempdir().expect("scratch");
    for (at, _db) in both(dir.path()) {
        let mut store = Store::open(&at).expect("made");
        let record = a_record();
        assert!(
            matches!(store.add(&record).expect("kept"), Added::New(_)),
            "{at:?}"
        );
        assert_eq!(
            store.add(&record).expect("sent again"),
            Added::Already,
            "{at:?}"
        );
        let mut older = record.clone();
        older.run.id = None;
        assert!(matches!(store.add(&older).expect("kept"), Added::New(_)));
        assert_eq!(store.add(&older).expect("again"), Added::Already, "{at:?}");
        assert_eq!(store.runs().expect("runs"), 2, "{at:?}");
        let h = store.history().expect("history");
        assert_eq!(
            (h.runs, h.revisions[0].rev.as_str(), h.revisions[0].flaky),
            (2, "C", 2)
        );
        assert_eq!(h.measurements[0].values, [200_000, 200_000], "{at:?}");
    }
}

/// The frozen store of schema 1 reads the same on both backends: on
/// PostgreSQL, its rows are put in a database made at schema 1 by the
/// first step as PostgreSQL spells it, and a role that may only read
/// reads it as it is, leaving it at schema 1.
#[test]
fn the_schema_1_store_reads_alike_on_both_backends() {
    let dir = tempfile::tempdir().expect("scratch");
    let Some(db) = ppmc_test_support::postgres::Db::new() else {
        return;
    };
    let file = store_v1(dir.path());
    let from_file = Store::open_existing(&file)
        .expect("reads")
        .history()
        .expect("history");
    let mut pg = postgres::Client::connect(&db.url, postgres::NoTls).expect("connect");
    let step = ppmc_report::store::MIGRATIONS[0]
        .replace(
            "INTEGER PRIMARY KEY",
            "BIGINT GENERATED BY DEFAULT AS IDENTITY PRIMARY KEY",
        )
        .replace("INTEGER", "BIGINT")
        .replace("REAL", "DOUBLE PRECISION");
    pg.batch_execute(&step).expect("schema 1");
    pg.batch_execute(
        "CREATE TABLE ppmc_schema (version BIGINT NOT NULL); INSERT INTO ppmc_schema VALUES (1);",
    )
    .expect("version");
    let lite = rusqlite::Connection::open(&file).expect("open");
    for table in ["runs", "boards", "results", "measurements"] {
        let mut st = lite
            .prepare(&format!("SELECT * FROM {table}"))
            .expect("select");
        let n = st.column_count();
        let rows: Vec<String> = st
            .query_map([], |r| {
                let mut vals = Vec::new();
                for i in 0..n {
                    use rusqlite::types::ValueRef as V;
                    vals.push(match r.get_ref(i)? {
                        V::Null => "NULL".to_string(),
                        V::Integer(v) => v.to_string(),
                        V::Real(v) => format!("{v:?}"),
                        V::Text(t) | V::Blob(t) => {
                            format!("'{}'", String::from_utf8_lossy(t).replace('\'', "''"))
                        }
                    });
                }
                Ok(format!("({})", vals.join(", ")))
            })
            .expect("rows")
            .collect::<Result<_, _>>()
            .expect("rows");
        pg.batch_execute(&format!("INSERT INTO {table} VALUES {}", rows.join(", ")))
            .expect("copied");
    }
    // A role that may only read: a read needs no more.
    pg.batch_execute(
        "CREATE ROLE reader LOGIN; GRANT SELECT ON ALL TABLES IN SCHEMA public TO reader;",
    )
    .expect("a reader");
    let as_reader = db.url.replacen("ppmc@", "reader@", 1);
    let mut store = Store::open_existing(Path::new(&as_reader)).expect("an older store reads");
    assert_eq!(store.schema().expect("schema"), 1, "read as it is");
    assert_eq!(store.history().expect("history"), from_file);
    drop(store);
    let version: i64 = pg
        .query_one("SELECT version FROM ppmc_schema", &[])
        .expect("version")
        .get(0);
    assert_eq!(version, 1, "reading changed nothing");
}

/// What is no store of ours on a server is refused by name, and whose the
/// trouble is: the store's (exit 2) or the link's; the password is never
/// shown.
#[test]
fn postgres_refuses_what_is_no_store_of_ours() {
    use ppmc_report::store::Fault;
    let Some(db) = ppmc_test_support::postgres::Db::new() else {
        return;
    };
    let mut pg = postgres::Client::connect(&db.url, postgres::NoTls).expect("connect");
    pg.batch_execute("CREATE TABLE songs (title TEXT)")
        .expect("made");
    let e = Store::open(Path::new(&db.url)).expect_err("another program's");
    assert_eq!(e.fault, Fault::Store);
    assert!(e.to_string().contains("not a ppmc results store"), "{e}");
    pg.batch_execute("DROP TABLE songs; CREATE TABLE ppmc_schema (version BIGINT); INSERT INTO ppmc_schema VALUES (99);")
        .expect("made");
    for opened in [
        Store::open(Path::new(&db.url)),
        Store::open_existing(Path::new(&db.url)),
    ] {
        let e = opened.expect_err("newer");
        assert!(
            e.to_string().contains("schema 99, made by a newer ppmc"),
            "{e}"
        );
        assert_eq!(e.fault, Fault::Store);
    }
    // No server there: the link's, named without the password.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("port")
        .port();
    let url = format!("postgres://lab:s3cret@127.0.0.1:{port}/results");
    let e = Store::open(Path::new(&url)).expect_err("nothing listens");
    assert_eq!(e.fault, Fault::Link);
    let shown = e.to_string();
    assert!(
        shown.starts_with(&format!("postgres://lab@127.0.0.1:{port}/results: "))
            && !shown.contains("s3cret"),
        "{shown}"
    );
}

/// TLS as the URL asks, checked against a real server's certificate:
/// `verify-full` with the authority that signed it connects encrypted;
/// with another authority it is refused; `disable` connects in the clear.
#[test]
fn postgres_over_tls_as_the_url_asks() {
    let Some(bin) = ppmc_test_support::postgres::bin_dir() else {
        if std::env::var_os("CI").is_some() {
            panic!("no PostgreSQL under CI");
        }
        return;
    };
    let cluster = ppmc_test_support::postgres::Cluster::start(&bin, true);
    let ca = cluster.ca.clone().expect("an authority");
    let base = format!("{}/postgres", cluster.url());
    let full = format!("{base}?sslmode=verify-full&sslrootcert={}", ca.display());
    let mut store = Store::open(Path::new(&full)).expect("verify-full with its authority");
    store.add(&a_record()).expect("kept over TLS");
    drop(store);
    // Another authority: refused, by the certificate's check.
    let other = ppmc_test_support::postgres::Cluster::start(&bin, true);
    let wrong = format!(
        "{base}?sslmode=verify-full&sslrootcert={}",
        other.ca.as_ref().expect("its authority").display()
    );
    let e = Store::open(Path::new(&wrong)).expect_err("another authority's server");
    assert!(e.to_string().to_lowercase().contains("certificate"), "{e}");
    // In the clear when asked, and TLS seen by the server when not.
    let mut seen = postgres::Client::connect(&base, postgres::NoTls).expect("plain");
    let store = Store::open(Path::new(&format!(
        "{base}?sslmode=require&application_name=tls_probe"
    )))
    .expect("require");
    let ssl: bool = seen
        .query_one(
            "SELECT bool_or(s.ssl) FROM pg_stat_ssl s JOIN pg_stat_activity a ON a.pid = s.pid WHERE a.application_name = 'tls_probe'",
            &[],
        )
        .expect("asked")
        .get(0);
    assert!(ssl, "sslmode=require went in the clear");
    drop(store);
}

/// Eight stations opening one new store at once, each adding its run:
/// one makes the schema, the others wait for it and find it made, and
/// every run is kept (on PostgreSQL a station once read the schema from a
/// view of the catalog older than the migration it had waited for, and
/// refused the store as another program's).
#[test]
fn eight_stations_make_one_new_store_at_once() {
    let dir = tempfile::tempdir().expect("scratch");
    for (at, _db) in both(dir.path()) {
        let stations: Vec<_> = (0..8)
            .map(|i| {
                let at = at.clone();
                std::thread::spawn(move || {
                    let mut record = a_record();
                    record.run.id = Some(format!("00000000-0000-4000-8000-{i:012}"));
                    let mut store = Store::open(&at).map_err(|e| e.to_string())?;
                    store.add(&record).map_err(|e| e.to_string())
                })
            })
            .collect();
        for s in stations {
            let added = s.join().expect("no panic");
            assert!(
                matches!(added, Ok(ppmc_report::store::Added::New(_))),
                "{at:?}: {added:?}"
            );
        }
        let mut store = Store::open_existing(&at).expect("reads");
        assert_eq!(store.runs().expect("runs"), 8, "{at:?}");
    }
}

/// A server that drops the station's connection during a long run (an
/// idle timeout, a restart): the run's record is still kept, the store
/// connected to again once (the client library's closed flag alone never
/// saw it: the first request after is what fails).
#[test]
fn a_dropped_connection_is_opened_again_to_keep_the_run() {
    let Some(db) = ppmc_test_support::postgres::Db::new() else {
        return;
    };
    let mut store = Store::open(Path::new(&db.url)).expect("made");
    let mut admin = postgres::Client::connect(&db.url, postgres::NoTls).expect("connect");
    let name = db.url.rsplit('/').next().expect("a database").to_string();
    let n: i64 = admin
        .query_one(
            "SELECT count(pg_terminate_backend(pid)) FROM pg_stat_activity
             WHERE datname = $1 AND pid <> pg_backend_pid()",
            &[&name],
        )
        .expect("terminated")
        .get(0);
    assert_eq!(n, 1, "the store's connection");
    assert!(matches!(
        store.add(&a_record()).expect("kept all the same"),
        ppmc_report::store::Added::New(_)
    ));
    assert_eq!(store.runs().expect("runs"), 1);
}

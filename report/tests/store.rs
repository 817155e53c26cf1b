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
    let store = Store::open_existing(&path).expect("an older store reads");
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

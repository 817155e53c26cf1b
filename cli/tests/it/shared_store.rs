//! A lab's store as stations use it (issue 44, docs/results-store.md):
//! on PostgreSQL as on an SQLite file, a run's record that the store does
//! not take is kept on disk and sent later by `ppmc store push`, once;
//! every command that reads a store reads the server's; a store damaged
//! where only reading finds it is the user's input (exit 2), as at open.

use crate::common;

use common::{scratch, text};
use std::path::Path;
use std::process::{Command, Output};

/// `ppmc` in `dir`, with `env` set.
fn ppmc_in(dir: &Path, env: &[(&str, &str)], args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .current_dir(dir)
        .env_remove("PPMC_STORE")
        .envs(env.iter().copied())
        .args(args)
        .output()
        .expect("ppmc runs")
}

/// SQL run on the store behind ppmc's back, as a lab's DBA might.
fn sql(store: &str, statements: &str) {
    if store.starts_with("postgres://") {
        let mut c = postgres::Client::connect(store, postgres::NoTls).expect("connect");
        c.batch_execute(statements).expect("SQL");
    } else {
        let c = rusqlite::Connection::open(store).expect("open");
        c.execute_batch(statements).expect("SQL");
    }
}

/// The store refuses the second run's record (a trigger a lab's server
/// might have, raising an error): the board's verdict stands, the run
/// says what was not kept (exit 1, as for any report not written) and
/// keeps the record in the working folder; `ppmc store push` sends it
/// once the store takes records again, and a second push adds nothing.
#[test]
fn a_record_the_store_did_not_take_is_kept_and_pushed_once() {
    let dir = scratch("shared-store");
    let db = ppmc_test_support::postgres::Db::new();
    let file = dir.path().join("results.db");
    let mut stores = vec![file.to_str().expect("utf-8").to_string()];
    stores.extend(db.as_ref().map(|d| d.url.clone()));
    for store in &stores {
        let work = tempfile::tempdir_in(dir.path()).expect("a station's folder");
        let run = |extra: &[&str]| {
            let mut args = vec!["run", "--filter", "s3_3_5_constant_speed_100_steps"];
            args.extend_from_slice(extra);
            ppmc_in(work.path(), &[], &args)
        };
        let out = run(&["--store", store]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        let refuse = if store.starts_with("postgres://") {
            "CREATE FUNCTION refuse() RETURNS trigger AS $$ BEGIN RAISE EXCEPTION 'disk on fire'; END $$ LANGUAGE plpgsql;
             CREATE TRIGGER refuse BEFORE INSERT ON runs FOR EACH ROW EXECUTE FUNCTION refuse();"
        } else {
            "CREATE TRIGGER refuse BEFORE INSERT ON runs BEGIN SELECT RAISE(ABORT, 'disk on fire'); END;"
        };
        sql(store, refuse);
        // The station's record, as the run names it.
        let out = run(&["--store", store]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(
            text(&out.stdout).contains("suite: 1 passed, 0 failed, 0 errors, 0 not run"),
            "the board's verdict stands: {}",
            text(&out.stdout)
        );
        assert!(
            err.contains("disk on fire") && err.contains("was not kept in the store"),
            "{err}"
        );
        let kept: Vec<_> = std::fs::read_dir(work.path())
            .expect("listed")
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with("ppmc-unsent-") && n.ends_with(".json"))
            .collect();
        assert_eq!(kept.len(), 1, "{kept:?}");
        assert!(
            err.contains(&format!("ppmc store push {}", kept[0])),
            "{err}"
        );
        let drop = if store.starts_with("postgres://") {
            "DROP TRIGGER refuse ON runs;"
        } else {
            "DROP TRIGGER refuse;"
        };
        sql(store, drop);
        // Through PPMC_STORE, as a station's environment would give it.
        for (pass, says) in [(1, ": kept, run "), (2, ": in the store already")] {
            let out = ppmc_in(
                work.path(),
                &[("PPMC_STORE", store)],
                &["store", "push", &kept[0]],
            );
            let said = text(&out.stdout);
            assert_eq!(
                out.status.code(),
                Some(0),
                "push {pass}: {}",
                text(&out.stderr)
            );
            assert!(said.contains(says), "push {pass}: {said}");
        }
        let out = ppmc_in(work.path(), &[], &["history", "--store", store]);
        let said = text(&out.stdout);
        assert!(said.contains(": 2 runs, 1 boards"), "{said}");
    }
}

/// Every command that reads a store reads the server's: `history`, and
/// `report --store`, whose page names the store without its password.
#[test]
fn history_and_the_report_read_a_store_on_postgres() {
    let Some(db) = ppmc_test_support::postgres::Db::new() else {
        return;
    };
    let dir = scratch("pg-report");
    for board in [
        "emu,rev=A,board-serial=A-1",
        "emu,rev=B,board-serial=B-1,chip-fault=int-late",
    ] {
        let out = ppmc_in(
            dir.path(),
            &[],
            &[
                "run", "--filter", "s3_4_1", "--target", board, "--store", &db.url,
            ],
        );
        assert!(
            matches!(out.status.code(), Some(0 | 1)),
            "{}",
            text(&out.stderr)
        );
    }
    // The same URL with a password the server does not ask for.
    let with_password = db.url.replacen("ppmc@", "ppmc:s3cret@", 1);
    let out = ppmc_in(dir.path(), &[], &["history", "--store", &with_password]);
    let said = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(said.contains("  A ") && said.contains("  B "), "{said}");
    assert!(!said.contains("s3cret"), "{said}");
    let page = dir.path().join("history.html");
    let out = ppmc_in(
        dir.path(),
        &[],
        &[
            "report",
            "--store",
            &with_password,
            "-o",
            page.to_str().expect("utf-8"),
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let html = std::fs::read_to_string(&page).expect("written");
    assert!(html.contains(&db.url) && !html.contains("s3cret"));
}

/// Issue 44: `history` and `report --store` gave exit 2 for a damaged
/// store found at open and 1 for the same damage found while reading. A
/// store whose pages past the first are overwritten opens (its header is
/// whole) and fails as it is read: exit 2 for both, naming the store.
#[test]
fn a_store_damaged_where_reading_finds_it_is_exit_2() {
    let dir = scratch("damaged-store");
    let db = dir.path().join("results.db");
    let db_s = db.to_str().expect("utf-8");
    for _ in 0..3 {
        let out = ppmc_in(dir.path(), &[], &["run", "--store", db_s]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    }
    let mut bytes = std::fs::read(&db).expect("read");
    assert!(bytes.len() > 16 * 4096, "a store of several pages");
    for b in &mut bytes[8192..] {
        *b = 0x5a;
    }
    std::fs::write(&db, &bytes).expect("damaged");
    let page = dir.path().join("page.html");
    for args in [
        vec!["history", "--store", db_s],
        vec![
            "report",
            "--store",
            db_s,
            "-o",
            page.to_str().expect("utf-8"),
        ],
    ] {
        let out = ppmc_in(dir.path(), &[], &args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(db_s), "{err}");
    }
}

/// Issue 44: a verdict a store's row holds that is none of ppmc's was
/// counted in no rate without a word, and a run could keep a label that
/// garbles every listing. Now: a label with a control character, an
/// empty one or `(none)` is refused where it is given (flag, target
/// option, record), and a store with a verdict of another program's is
/// refused by `history` by name (exit 2), on both backends.
#[test]
fn an_unknown_verdict_or_label_is_refused_by_name() {
    let dir = scratch("labels");
    for args in [
        vec!["run", "--filter", "e0_undefined", "--board-rev", "B\n2"],
        vec!["run", "--filter", "e0_undefined", "--board-serial", ""],
        vec![
            "run",
            "--filter",
            "e0_undefined",
            "--target",
            "emu,rev=(none)",
        ],
        vec![
            "run",
            "--filter",
            "e0_undefined",
            "--target",
            "emu,board-serial=\u{1b}[31mSN",
        ],
    ] {
        let out = ppmc_in(dir.path(), &[], &args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("label"), "{args:?}: {err}");
    }
    // A record of a board whose revision holds a terminal's escape.
    let json = dir.path().join("run.json");
    let out = ppmc_in(
        dir.path(),
        &[],
        &[
            "run",
            "--filter",
            "e0_undefined",
            "--json",
            json.to_str().expect("utf-8"),
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let mut record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("written")).expect("JSON");
    record["run"]["boards"][0]["board_rev"] = "B\u{1b}[2J".into();
    let planted = dir.path().join("planted.json");
    std::fs::write(&planted, record.to_string()).expect("written");
    let db = ppmc_test_support::postgres::Db::new();
    let file = dir.path().join("results.db");
    let mut stores = vec![file.to_str().expect("utf-8").to_string()];
    stores.extend(db.as_ref().map(|d| d.url.clone()));
    for store in &stores {
        let out = ppmc_in(
            dir.path(),
            &[],
            &[
                "store",
                "push",
                "--store",
                store,
                planted.to_str().expect("utf-8"),
            ],
        );
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains("run.boards[0].board_rev `B\\u{1b}[2J`"),
            "{err}"
        );
        // A verdict another program wrote into the store.
        let out = ppmc_in(
            dir.path(),
            &[],
            &[
                "store",
                "push",
                "--store",
                store,
                json.to_str().expect("utf-8"),
            ],
        );
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        sql(store, "UPDATE results SET verdict = 'exploded';");
        let out = ppmc_in(dir.path(), &[], &["history", "--store", store]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains("verdict `exploded`, not one of ppmc's (passed, marginal, flaky, failed, error, not_run)"),
            "{err}"
        );
    }
}

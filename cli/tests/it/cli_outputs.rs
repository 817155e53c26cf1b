//! Nothing destroyed: what ppmc writes never replaces what it was not asked
//! to replace (its own input, another report, another recorder's golden
//! file), and an output that cannot be written is found before the run,
//! not after it.

use crate::common;

use common::{ppmc, scratch, text};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../golden")
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// `ppmc` with `args`, run in `dir`.
fn ppmc_in(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("ppmc runs")
}

/// Each golden file a `ppmc record` output names on a line starting with
/// `word`.
fn named(stdout: &str, word: &str) -> Vec<PathBuf> {
    stdout
        .lines()
        .filter_map(|l| l.strip_prefix(word))
        .map(|rest| PathBuf::from(rest.trim_start().split(": ").next().unwrap_or_default()))
        .collect()
}

/// Two recorders into one folder at once, at different straps (so every
/// trace differs): each file is created by exactly one, holds that one's
/// trace, and the other says it refused it; nothing is replaced.
#[test]
fn two_recorders_into_one_folder_create_each_file_once_and_never_replace_one() {
    let dir = scratch("record2");
    let out = dir.path().join("golden");
    let start = |target: &str| {
        Command::new(env!("CARGO_BIN_EXE_ppmc"))
            .args(["record", "--skip-tag", "long", "--out", s(&out)])
            .args(["--target", target])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("ppmc record starts")
    };
    let (a, b) = (start("emu"), start("emu,clock-mhz=12"));
    let (a, b) = (
        a.wait_with_output().expect("a ends"),
        b.wait_with_output().expect("b ends"),
    );
    let (sa, sb) = (text(&a.stdout), text(&b.stdout));
    let both = format!("--- 16 MHz:\n{sa}\n--- 12 MHz:\n{sb}");
    assert!(
        named(&sa, "replaced").is_empty() && named(&sb, "replaced").is_empty(),
        "{both}"
    );
    assert!(
        sa.contains(" 0 replaced") && sb.contains(" 0 replaced"),
        "{both}"
    );
    let files: Vec<PathBuf> = fs::read_dir(&out)
        .expect("folder written")
        .map(|e| e.expect("entry").path())
        .collect();
    assert!(files.len() > 50, "{both}");
    assert!(
        files
            .iter()
            .all(|f| f.extension().is_some_and(|e| e == "snap")),
        "{files:?}"
    );
    let (created_a, created_b) = (named(&sa, "created"), named(&sb, "created"));
    let (refused_a, refused_b) = (named(&sa, "refused"), named(&sb, "refused"));
    for f in &files {
        let by_a = created_a.contains(f);
        let by_b = created_b.contains(f);
        assert!(
            by_a != by_b,
            "{}: created by both or neither\n{both}",
            f.display()
        );
        // The file is its creator's trace, and the other was told.
        let body = fs::read_to_string(f).expect("read");
        let at_12 = body.contains("detail sysclk_hz 12000000");
        assert_eq!(
            at_12,
            by_b,
            "{}: not its creator's trace\n{both}",
            f.display()
        );
        let told = if by_a { &refused_b } else { &refused_a };
        assert!(
            told.contains(f),
            "{}: no refusal from the other\n{both}",
            f.display()
        );
    }
    for (o, stdout) in [(&a, &sa), (&b, &sb)] {
        if stdout.contains("refused ") {
            assert_eq!(o.status.code(), Some(1), "{stdout}");
            assert!(
                stdout.contains("exists and differs from this run; pass --bless"),
                "{stdout}"
            );
        }
    }
}

/// `export` never writes over the trace it reads, however the path is
/// spelled, and without -o it writes into `out/`.
#[test]
fn export_refuses_to_write_over_its_input() {
    let dir = scratch("export-self");
    let d = dir.path();
    let trace = d.join("t.snap");
    fs::copy(
        golden_dir().join("s3_3_5_constant_speed_100_steps.snap"),
        &trace,
    )
    .expect("copy");
    let before = fs::read(&trace).expect("read");
    let hard = d.join("hard.snap");
    fs::hard_link(&trace, &hard).expect("hard link");
    let dotted = d.join(".").join("t.snap");
    for o in [&trace, &dotted, &hard] {
        let out = ppmc(&["export", s(&trace), "-o", s(o)]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "-o {}: {err}", o.display());
        assert!(err.contains("-o names the input trace"), "{err}");
        assert_eq!(fs::read(&trace).expect("read"), before, "input kept");
    }
    // Relative against absolute, run from the trace's folder.
    let out = ppmc_in(d, &["export", "t.snap", "-o", s(&trace)]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    // Without -o (issue 42): into `out/` of the current folder, named by
    // the trace's scenario; never beside the input, which may be a
    // tracked golden file, and so never over a trace named `.vcd`.
    let named_vcd = d.join("w.vcd");
    fs::copy(&trace, &named_vcd).expect("copy");
    for input in ["t.snap", "w.vcd"] {
        let out = ppmc_in(d, &["export", input]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        assert_eq!(
            text(&out.stdout),
            "wrote out/s3_3_5_constant_speed_100_steps.vcd\n"
        );
        fs::remove_file(d.join("out/s3_3_5_constant_speed_100_steps.vcd")).expect("written");
    }
    assert_eq!(fs::read(&named_vcd).expect("read"), before, "input kept");
    assert!(!d.join("t.vcd").exists());
    // `out` that is a file is named, not written through.
    fs::remove_dir(d.join("out")).expect("an empty out/");
    fs::write(d.join("out"), "a file").expect("write");
    let out = ppmc_in(d, &["export", "t.snap"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("out"), "{err}");
}

/// `--junit X --json X` would keep one report of two: refused before the
/// run, for any spelling of the one file.
#[test]
fn the_same_file_for_two_reports_is_refused_before_the_run() {
    let dir = scratch("two-reports");
    let d = dir.path();
    let run = |junit: &str, json: &str| {
        ppmc_in(
            d,
            &[
                "run",
                "--filter",
                "e0_undefined",
                "--junit",
                junit,
                "--json",
                json,
            ],
        )
    };
    let x = d.join("x");
    for (junit, json) in [("x", "x"), ("x", "./x"), (s(&x), "x"), ("sub/../x", "x")] {
        fs::create_dir_all(d.join("sub")).expect("sub");
        let out = run(junit, json);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{junit} {json}: {err}");
        assert!(err.contains("are the same file"), "{err}");
        assert!(out.stdout.is_empty(), "nothing ran: {}", text(&out.stdout));
        assert!(!x.exists(), "nothing written");
    }
    // A hard link to a report from an earlier run is the same file too.
    fs::write(&x, "earlier").expect("x");
    fs::hard_link(&x, d.join("y")).expect("hard link");
    let out = run("x", "y");
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert_eq!(fs::read_to_string(&x).expect("kept"), "earlier");
    // Two files: both written.
    let out = run("r.xml", "r.json");
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(d.join("r.xml").is_file() && d.join("r.json").is_file());
}

/// Issue 44: a report path that names a file holding something else (a
/// results store, a golden trace, another kind of report, a file of the
/// user's) is refused before the run, the file kept byte for byte; a
/// report of the same kind is replaced, as asked.
#[test]
fn a_report_over_a_file_of_another_kind_is_refused_before_the_run() {
    let dir = scratch("report-kinds");
    let d = dir.path();
    let run = |args: &[&str]| {
        let mut all = vec!["run", "--filter", "e0_undefined"];
        all.extend_from_slice(args);
        ppmc_in(d, &all)
    };
    // One run writes a store and one report of each kind.
    let out = run(&[
        "--store", "k.db", "--json", "r.json", "--html", "r.html", "--junit", "r.xml",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    fs::copy(
        golden_dir().join("e0_undefined_command_code.snap"),
        d.join("g.snap"),
    )
    .expect("a golden trace");
    fs::write(d.join("notes.txt"), "a file of the user's\n").expect("notes");
    let refused = [
        ("--json", "k.db", "a results store (SQLite)"),
        ("--html", "g.snap", "a golden trace"),
        ("--html", "r.json", "a JSON run record"),
        ("--junit", "r.html", "an HTML report of ppmc's"),
        ("--json", "r.xml", "a JUnit report"),
        ("--junit", "notes.txt", "not a report of ppmc's"),
    ];
    for (flag, file, what) in refused {
        let before = fs::read(d.join(file)).expect("there");
        let out = run(&[flag, file]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flag} {file}: {err}");
        assert!(
            err.contains(&format!("{flag} {file}: the file is {what}")),
            "{flag} {file}: {err}"
        );
        assert!(out.stdout.is_empty(), "nothing ran: {}", text(&out.stdout));
        assert_eq!(
            fs::read(d.join(file)).expect("kept"),
            before,
            "{file} changed"
        );
    }
    // The same kind, and an empty file, are replaced.
    fs::write(d.join("empty.json"), "").expect("empty");
    for (flag, file) in [
        ("--json", "r.json"),
        ("--html", "r.html"),
        ("--junit", "r.xml"),
        ("--json", "empty.json"),
    ] {
        let out = run(&[flag, file]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{flag} {file}: {}",
            text(&out.stderr)
        );
    }
    assert!(fs::read_to_string(d.join("empty.json"))
        .expect("written")
        .contains("ppmc-run-record/"));
}

/// Every output is tried before any scenario runs: a folder that is a
/// regular file, a report that is a directory.
#[test]
fn an_output_that_cannot_be_written_is_found_before_any_scenario_runs() {
    let dir = scratch("outputs");
    let d = dir.path();
    let file = d.join("plain");
    fs::write(&file, "x").expect("file");
    let trace = golden_dir().join("e0_undefined_command_code.snap");
    let under = |name: &str| file.join(name).display().to_string();
    let cases: Vec<Vec<String>> = vec![
        vec!["run".into(), "--junit".into(), under("r.xml")],
        vec!["run".into(), "--json".into(), under("sub/r.json")],
        vec!["run".into(), "--json".into(), d.display().to_string()],
        vec!["run".into(), "--artifacts".into(), under("arts")],
        vec![
            "run".into(),
            "--artifacts".into(),
            file.display().to_string(),
        ],
        vec!["record".into(), "--out".into(), under("golden")],
        vec![
            "export".into(),
            s(&trace).into(),
            "-o".into(),
            under("w.vcd"),
        ],
    ];
    for args in cases {
        let mut args: Vec<&str> = args.iter().map(String::as_str).collect();
        if args[0] != "export" {
            args.extend(["--filter", "e0_undefined"]);
        }
        let out = ppmc(&args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("plain is a regular file, not a folder") || err.contains("is a directory"),
            "{args:?}: {err}"
        );
        assert!(
            out.stdout.is_empty(),
            "{args:?}: ran: {}",
            text(&out.stdout)
        );
    }
    assert_eq!(fs::read_to_string(&file).expect("kept"), "x");
}

/// A read-only report folder is found before the run. Root writes into a
/// read-only folder all the same (as in CI's container), so under root the
/// test says so and checks nothing.
#[cfg(unix)]
#[test]
fn a_read_only_report_folder_is_found_before_any_scenario_runs() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch("readonly");
    let ro = dir.path().join("ro");
    fs::create_dir(&ro).expect("dir");
    fs::set_permissions(&ro, fs::Permissions::from_mode(0o555)).expect("chmod");
    if fs::write(ro.join("probe"), "").is_ok() {
        eprintln!("note: running as root, a read-only folder is writable; not checked");
        return;
    }
    for args in [
        vec!["run", "--junit", "ro/r.xml"],
        vec!["run", "--artifacts", "ro/arts"],
        vec!["record", "--out", "ro"],
    ] {
        let mut args = args.clone();
        args.extend(["--filter", "e0_undefined"]);
        let out = ppmc_in(dir.path(), &args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("ro"), "{args:?}: {err}");
        assert!(err.contains("Permission denied"), "{args:?}: {err}");
        assert!(
            out.stdout.is_empty(),
            "{args:?}: ran: {}",
            text(&out.stdout)
        );
    }
    fs::set_permissions(&ro, fs::Permissions::from_mode(0o755)).expect("chmod back");
}

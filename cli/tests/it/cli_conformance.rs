//! `ppmc run`, `record`, `compare` and `export` as a user runs them.

use crate::common;

use common::{ppmc, scratch, text};

use ppmc::compare::scale_times;
use ppmc::trace::Trace;
use std::fs;
use std::path::{Path, PathBuf};

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../golden")
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn run_passes_on_the_emulator_and_writes_valid_junit_and_json() {
    let d_dir = scratch("run");
    let d = d_dir.path();
    let (junit, json) = (d.join("report.xml"), d.join("run.json"));
    let out = ppmc(&[
        "run",
        "--junit",
        s(&junit),
        "--json",
        s(&json),
        "--board-rev",
        "B2",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
    let stdout = text(&out.stdout);
    let n = ppmc_scenarios::all().len();
    assert!(
        stdout.contains(&format!("suite: {n} passed, 0 failed")),
        "{stdout}"
    );
    let xml = fs::read_to_string(&junit).expect("junit written");
    let report = quick_junit::Report::deserialize_from_str(&xml).expect("valid JUnit XML");
    assert_eq!(report.tests, n);
    assert_eq!(report.failures, 0);
    let suite = &report.test_suites[0];
    assert!(suite
        .properties
        .iter()
        .any(|p| p.name.as_str() == "board_rev" && p.value.as_str() == "B2"));
    let record: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(&json).expect("json written"))
            .expect("valid JSON");
    assert_eq!(record["summary"]["passed"], n);
    assert_eq!(record["run"]["boards"][0]["board_rev"], "B2");
    assert_eq!(record["run"]["spread"], "one");
    assert_eq!(record["scenarios"][0]["board"], "emu");
    let with_measures = record["scenarios"]
        .as_array()
        .expect("scenarios")
        .iter()
        .find(|s| s["name"] == "s3_3_5_constant_speed_100_steps")
        .expect("scenario in record");
    assert_eq!(
        with_measures["measurements"][0]["name"],
        "constant_first_pout"
    );
    assert_eq!(with_measures["measurements"][0]["value_ns"], 194_000);
    assert_eq!(with_measures["measurements"][0]["grade"], "PASS");
}

#[test]
fn run_compares_with_golden_as_it_runs() {
    let out = ppmc(&["run", "--golden", s(&golden_dir()), "--tag", "stop"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
}

/// Writes a copy of the golden set with every time scaled by `num / den`.
fn scaled_copy(tag: &str, num: u64, den: u64) -> tempfile::TempDir {
    let d_dir = scratch(tag);
    let d = d_dir.path();
    for e in fs::read_dir(golden_dir()).expect("golden dir") {
        let p = e.expect("entry").path();
        if p.extension().is_some_and(|x| x == "snap") {
            let t = Trace::parse(&fs::read_to_string(&p).expect("read")).expect("golden parses");
            let scaled = scale_times(&t, num, den);
            fs::write(d.join(p.file_name().expect("name")), scaled.render()).expect("write");
        }
    }
    d_dir
}

#[test]
fn compare_traces_writes_junit_and_json_as_run_does_and_names_a_missing_trace() {
    // Issue 29: `compare --traces` had no reports, other verdict words
    // than `run`, and a trace missing from the compared set was reported
    // as a missing golden file.
    let three_dir = scaled_copy("three-reports", 103, 100);
    let three = three_dir.path();
    fs::remove_file(three.join("e0_undefined_command_code.snap")).ok();
    let out_dir = scratch("compare-reports");
    let (junit, json) = (out_dir.path().join("c.xml"), out_dir.path().join("c.json"));
    let out = ppmc(&[
        "compare",
        s(&golden_dir()),
        "--traces",
        s(three),
        "--filter",
        "e0_undefined_command_code",
        "--junit",
        s(&junit),
        "--json",
        s(&json),
    ]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}{}", text(&out.stderr));
    assert!(
        stdout.contains("ERROR    e0_undefined_command_code"),
        "{stdout}"
    );
    assert!(
        stdout.contains(&format!("no trace of this scenario in {}", three.display())),
        "{stdout}"
    );
    let out = ppmc(&[
        "compare",
        s(&golden_dir()),
        "--traces",
        s(three),
        "--filter",
        "s3_3_5_constant_speed_100_steps",
        "--junit",
        s(&junit),
        "--json",
        s(&json),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    let xml = fs::read_to_string(&junit).expect("JUnit written");
    assert!(
        xml.contains(r#"<testcase name="s3_3_5_constant_speed_100_steps""#)
            && xml.contains(r#"<failure type="device""#),
        "{xml}"
    );
    let record: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(&json).expect("JSON written")).expect("JSON");
    common::check_record(&common::run_record_schema(), &record);
    assert_eq!(record["summary"]["failed"], 1, "{record}");
}

#[test]
fn compare_passes_half_a_percent_and_fails_three_percent() {
    let half_dir = scaled_copy("half", 1005, 1000);
    let half = half_dir.path();
    let out = ppmc(&["compare", s(&golden_dir()), "--traces", s(half)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
    assert!(text(&out.stdout).contains(" 0 failed"));

    let three_dir = scaled_copy("three", 103, 100);
    let three = three_dir.path();
    let out = ppmc(&["compare", s(&golden_dir()), "--traces", s(three)]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("FAIL     s3_3_5_constant_speed_100_steps (section 3-3-5)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("golden trace: first divergence in "),
        "{stdout}"
    );
    assert!(stdout.contains("(allowed "), "{stdout}");
    // Loosen the tolerances and 3 % passes.
    let out = ppmc(&[
        "compare",
        s(&golden_dir()),
        "--traces",
        s(three),
        "--latency-tol",
        "4",
        "--interval-tol",
        "4",
        "--filter",
        "e0_",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
}

#[test]
fn export_writes_a_vcd_that_parses_back() {
    let d_dir = scratch("vcd");
    let d = d_dir.path();
    let vcd_path = d.join("out.vcd");
    let golden = golden_dir().join("s3_3_5_constant_speed_100_steps.snap");
    let out = ppmc(&["export", s(&golden), "-o", s(&vcd_path)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let bytes = fs::read(&vcd_path).expect("vcd written");
    let mut parser = vcd::Parser::new(&bytes[..]);
    let header = parser.parse_header().expect("header");
    let pout = header.find_var(&["ppmc", "pout"]).expect("pout wire").code;
    let rises = parser
        .filter_map(Result::ok)
        .filter(|c| matches!(c, vcd::Command::ChangeScalar(i, vcd::Value::V1) if *i == pout))
        .count();
    assert_eq!(rises, 100);
}

#[test]
fn record_never_overwrites_without_bless() {
    let d_dir = scratch("record");
    let d = d_dir.path();
    let args = |extra: &[&str]| {
        let mut v = vec!["record", "--out", s(d), "--filter", "e0_undefined"];
        v.extend_from_slice(extra);
        ppmc(&v)
    };
    let out = args(&[]);
    assert_eq!(out.status.code(), Some(0));
    assert!(text(&out.stdout).contains("1 created"));
    let file = d.join("e0_undefined_command_code.snap");
    let recorded = fs::read_to_string(&file).expect("recorded");
    assert_eq!(
        recorded,
        fs::read_to_string(golden_dir().join("e0_undefined_command_code.snap")).expect("golden")
    );
    assert!(text(&args(&[]).stdout).contains("1 unchanged"));
    let edited = recorded.replace("section 3-1-1", "section 9-9");
    fs::write(&file, &edited).expect("edit");
    let out = args(&[]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stdout).contains("pass --bless"),
        "{}",
        text(&out.stdout)
    );
    assert_eq!(
        fs::read_to_string(&file).expect("kept"),
        edited,
        "untouched without --bless"
    );
    let out = args(&["--bless"]);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(fs::read_to_string(&file).expect("replaced"), recorded);
}

#[test]
fn a_corrupt_golden_file_is_a_harness_error_of_its_scenario_alone_with_path_and_line() {
    let g_dir = scratch("corrupt");
    let g = g_dir.path();
    for name in ["e0_undefined_command_code", "e3_data_without_a_command"] {
        fs::copy(
            golden_dir().join(format!("{name}.snap")),
            g.join(format!("{name}.snap")),
        )
        .expect("copy");
    }
    let bad = g.join("e3_data_without_a_command.snap");
    let text_ = fs::read_to_string(&bad).expect("read");
    fs::write(&bad, text_.replacen(" wd ", " wq ", 1)).expect("corrupt");
    let arts_dir = scratch("artifacts");
    let arts = arts_dir.path();
    let out = ppmc(&[
        "run",
        "--golden",
        s(g),
        "--filter",
        "e",
        "--tag",
        "error",
        "--shard",
        "1/1",
        "--artifacts",
        s(arts),
        "--json",
        s(&arts.join("record.json")),
    ]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    // The JSON record names the files kept, as JUnit's attachments do.
    let record: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(arts.join("record.json")).expect("record"))
            .expect("JSON");
    let kept = |name: &str| {
        record["scenarios"]
            .as_array()
            .expect("scenarios")
            .iter()
            .find(|r| r["name"] == name)
            .map(|r| r["artifacts"].clone())
    };
    let e3 = kept("e3_data_without_a_command").expect("e3 in the record");
    let e3: Vec<&str> = e3
        .as_array()
        .expect("artifacts")
        .iter()
        .filter_map(|v| v.as_str())
        .collect();
    assert!(
        e3.iter()
            .any(|p| p.ends_with("e3_data_without_a_command.trace"))
            && e3
                .iter()
                .any(|p| p.ends_with("e3_data_without_a_command.vcd")),
        "{e3:?}"
    );
    assert_eq!(
        kept("e0_undefined_command_code"),
        Some(serde_json::Value::Null)
    );
    assert!(
        stdout.contains("PASS     e0_undefined_command_code"),
        "{stdout}"
    );
    // The golden file is at fault, not the device: an error, not a failure.
    assert!(
        stdout.contains("ERROR    e3_data_without_a_command"),
        "{stdout}"
    );
    assert!(!stdout.contains("FAIL "), "{stdout}");
    assert!(
        stdout.contains("e3_data_without_a_command.snap:"),
        "{stdout}"
    );
    assert!(stdout.contains("unknown event `wq`"), "{stdout}");
    // Scenarios with no golden file are errors too, naming the missing file.
    assert!(
        stdout.contains("no golden trace for this scenario"),
        "{stdout}"
    );
    assert!(arts.join("e3_data_without_a_command.trace").exists());
    assert!(arts.join("e3_data_without_a_command.vcd").exists());
    assert!(!arts.join("e0_undefined_command_code.trace").exists());
}

#[test]
fn bad_usage_exits_2() {
    for args in [
        &["run", "--shard", "5/4"][..],
        &["run", "--filter", "no_such_scenario"],
        &["run", "--golden", "/no/such/dir"],
        &["compare", "/no/such/dir", "--traces", "."],
        &["export", "/no/such/file"],
        // Options are checked before a port is touched.
        &[
            "run",
            "--target",
            "serial:/dev/ppmc-none",
            "--link-timeout",
            "0s",
        ],
        &[
            "run",
            "--target",
            "serial:/dev/ppmc-none",
            "--clock-mhz",
            "0.5",
        ],
        &["run", "--clock-mhz", "41"],
        // A malformed network address is the user's typing, not the
        // network's failure.
        &["run", "--target", "tcp://[::1"],
        &["run", "--target", "tcp://[::1:4321"],
        &["run", "--target", "rfc2217://[::1,baud=115200"],
        &["run", "--target", "tcp://bench 1:4321"],
    ] {
        let out = ppmc(args);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{args:?}: {}",
            text(&out.stderr)
        );
        assert!(!text(&out.stderr).is_empty());
    }
    let out = ppmc(&["run", "--clock-mhz", "0.5"]);
    assert!(
        text(&out.stderr).contains("--clock-mhz 0.5: the system clock must be 1 to 40 MHz"),
        "{}",
        text(&out.stderr)
    );
    let out = ppmc(&["run", "--target", "tcp://[::1"]);
    assert!(
        text(&out.stderr).contains(
            "bad target `tcp://[::1`: write tcp://<host>:<port> (an IPv6 address in brackets: [::1])"
        ),
        "{}",
        text(&out.stderr)
    );
}

/// A golden or compared file that cannot be used is an error of its own in
/// `compare`'s count (the file is at fault, not the board), apart from the
/// traces that diverge, and still makes the exit status non-zero.
#[test]
fn compare_counts_an_unusable_file_as_an_error_not_a_failure() {
    let g_dir = scratch("compare-bad");
    let g = g_dir.path();
    for name in ["e0_undefined_command_code", "e0_motor_type_code_00"] {
        fs::copy(
            golden_dir().join(format!("{name}.snap")),
            g.join(format!("{name}.snap")),
        )
        .expect("copy");
    }
    // Unreadable as a trace: not UTF-8.
    fs::write(g.join("e0_motor_type_code_00.snap"), [0xFF, 0xFE, 0x00]).expect("spoil");
    let traces = golden_dir();
    let args = |extra: &[&str]| {
        let mut v = vec!["compare", s(g), "--traces", s(&traces)];
        v.extend_from_slice(extra);
        ppmc(&v)
    };
    let out = args(&["--filter", "e0_undefined"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
    assert!(
        text(&out.stdout).contains("compare: 1 passed, 0 failed, 0 errors"),
        "{}",
        text(&out.stdout)
    );
    let out = args(&["--filter", "e0_motor_type_code_00"]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("ERROR    e0_motor_type_code_00"),
        "{stdout}"
    );
    assert!(stdout.contains("not UTF-8 text"), "{stdout}");
    assert!(
        stdout.contains("compare: 0 passed, 0 failed, 1 errors"),
        "{stdout}"
    );
}

#[test]
fn list_and_shards_cover_the_suite() {
    let n = ppmc_scenarios::all().len();
    let out = ppmc(&["list"]);
    assert!(text(&out.stdout).contains(&format!("{n} scenarios")));
    let count = |shard: &str| {
        let out = ppmc(&["list", "--shard", shard]);
        let t = text(&out.stdout);
        t.lines()
            .last()
            .and_then(|l| l.split_whitespace().next())
            .and_then(|k| k.parse::<usize>().ok())
            .expect("count line")
    };
    assert_eq!(count("1/3") + count("2/3") + count("3/3"), n);
}

/// Reports and golden files never follow a planted symlink, never replace a
/// device, a FIFO or a directory, and never leave a temporary file behind.
#[cfg(unix)]
#[test]
fn outputs_never_follow_a_symlink_or_replace_what_is_not_a_regular_file() {
    let d_dir = scratch("planted");
    let d = d_dir.path();
    let outside = d.join("outside.txt");
    fs::write(&outside, "keep me").expect("outside file");
    let report = d.join("report.json");
    std::os::unix::fs::symlink(&outside, &report).expect("symlink");
    let out = ppmc(&["run", "--filter", "e0_undefined", "--json", s(&report)]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stdout));
    let err = text(&out.stderr);
    assert!(err.contains("report.json: is a symbolic link"), "{err}");
    assert!(out.stdout.is_empty(), "refused before anything ran");
    assert_eq!(fs::read_to_string(&outside).expect("kept"), "keep me");

    let out = ppmc(&["run", "--filter", "e0_undefined", "--junit", "/dev/null"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("/dev/null: is a device"));

    // A golden file planted as a symlink is refused too, and counted.
    let golden = d.join("golden");
    fs::create_dir(&golden).expect("golden dir");
    std::os::unix::fs::symlink(&outside, golden.join("e0_undefined_command_code.snap"))
        .expect("symlink");
    let out = ppmc(&["record", "--filter", "e0_undefined", "--out", s(&golden)]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("is a symbolic link"), "{stdout}");
    assert!(stdout.contains("1 not written"), "{stdout}");
    assert_eq!(fs::read_to_string(&outside).expect("kept"), "keep me");
    let leftovers: Vec<_> = fs::read_dir(&golden)
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .filter(|n| n.to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// A golden path that is a FIFO or a device is refused, not read forever.
#[cfg(unix)]
#[test]
fn a_golden_file_that_is_a_fifo_or_a_device_is_an_error_not_a_hang() {
    let d_dir = scratch("fifo");
    let d = d_dir.path();
    let fifo = d.join("e0_undefined_command_code.snap");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo");
    assert!(made.success());
    std::os::unix::fs::symlink("/dev/zero", d.join("e0_motor_type_code_00.snap")).expect("symlink");
    let out = ppmc(&["run", "--golden", s(d), "--filter", "e0_"]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("e0_undefined_command_code.snap: is a FIFO"),
        "{stdout}"
    );
    assert!(
        stdout.contains("e0_motor_type_code_00.snap: is a device"),
        "{stdout}"
    );
    assert!(
        stdout.contains("ERROR    e0_undefined_command_code"),
        "{stdout}"
    );
}

/// Issue 42's rough edges of the command line, as a newcomer met them:
/// each message says what is wrong and what to write instead.
#[test]
fn a_newcomers_slips_are_answered_with_what_to_write() {
    let said = |args: &[&str], code: i32| {
        let out = ppmc(args);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {stderr}");
        stderr
    };
    // Two letters swapped: clap's own measure finds nothing near.
    let e = said(&["rnu"], 2);
    assert!(e.contains("a similar subcommand exists: 'run'"), "{e}");
    // An option misspelt is not an unknown target.
    let e = said(&["run", "--target", "emu,foo=bar"], 2);
    assert!(e.contains("unknown option `foo=bar`"), "{e}");
    // A bare device path is shown its form.
    let e = said(&["run", "--target", "/dev/ttyACM0"], 2);
    assert!(e.contains("`serial:/dev/ttyACM0`"), "{e}");
    // --scenario of judge names a trace; the judging needs none.
    let e = said(&["judge", "x.vcd", "--scenario", "s"], 2);
    assert!(e.contains("give --trace DIR too"), "{e}");
    // A duration in minutes, as the help writes it, is read.
    let e = said(&["fuzz", "run", "--duration", "3m", "--ops", "1"], 0);
    assert!(!e.contains("--duration"), "{e}");
    // The main help says what `report --store` draws.
    let help = text(&ppmc(&["--help"]).stdout);
    let report = help
        .lines()
        .find(|l| l.trim_start().starts_with("report"))
        .expect("report in the help");
    assert!(report.contains("--store"), "{report}");
}

/// `--skip NAME` leaves one scenario out by its whole name (issue 42); a
/// name that is no scenario's is the user's typo.
#[test]
fn skip_leaves_out_a_scenario_by_name() {
    let all = ppmc(&["run", "--filter", "s3_3_5"]);
    let skipped = ppmc(&[
        "run",
        "--filter",
        "s3_3_5",
        "--skip",
        "s3_3_5_constant_speed_100_steps",
    ]);
    let (all, skipped) = (text(&all.stdout), text(&skipped.stdout));
    assert!(all.contains("s3_3_5_constant_speed_100_steps"), "{all}");
    assert!(
        !skipped.contains("s3_3_5_constant_speed_100_steps"),
        "{skipped}"
    );
    assert_eq!(
        skipped.lines().count() + 1,
        all.lines().count(),
        "{all}\n{skipped}"
    );
    let out = ppmc(&["run", "--skip", "s3_3_5_constant"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("--skip s3_3_5_constant: no scenario of that name"),
        "{}",
        text(&out.stderr)
    );
}

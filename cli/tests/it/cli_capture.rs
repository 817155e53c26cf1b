//! `ppmc decode` and `ppmc judge` on captures (issue 30,
//! `docs/capture.md`): a scenario's capture from `ppmc export --scenario
//! --bus`, judged on the clean model (passes) and with a board fault
//! (fails, the board's); hand-written captures whose host writes while
//! IBF is 1, or moves before initializing (the host firmware's findings,
//! exit 3); one without a bus channel (the capture's, exit 4). The
//! decoded accesses replay with `ppmc console`. The same verdicts in the
//! JUnit report and the JSON run record (`--junit`, `--json`), each its
//! own kind.

use crate::common;
use common::{check_record, ppmc, run_record_schema, scratch, text};
use serde_json::Value;
use std::path::Path;

fn export(dir: &Path, name: &str, scenario: &str, faults: &[&str]) -> String {
    let path = dir.join(name).to_str().expect("utf-8").to_string();
    let mut args = vec!["export", "--scenario", scenario, "--bus", "-o", &path];
    for f in faults {
        args.extend(["--chip-fault", f]);
    }
    let out = ppmc(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    path
}

/// Sections 3-3 and 3-4: a clean board's capture passes, every pulse
/// compared; one that loses the last pulse of a move fails, blamed on the
/// board, with the pulse and the access before it.
#[test]
fn a_clean_capture_passes_and_a_faulty_boards_fails() {
    let dir = scratch("judge");
    let clean = export(
        dir.path(),
        "clean.vcd",
        "s3_3_5_constant_speed_100_steps",
        &[],
    );
    let out = ppmc(&["judge", &clean]);
    let said = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{said}{}", text(&out.stderr));
    assert!(said.contains("100 POUT pulses compared"), "{said}");
    assert!(said.contains("PASS the board"), "{said}");
    let bad = export(
        dir.path(),
        "bad.vcd",
        "s3_3_5_constant_speed_100_steps",
        &["drop-last-pulse"],
    );
    let out = ppmc(&["judge", &bad]);
    let said = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{said}");
    assert!(said.contains("FAIL the board: POUT pulse 100"), "{said}");
}

/// `ppmc decode` prints the accesses in the console's language, and
/// `ppmc console` replays them (3-1: the same registers, the same bytes).
#[test]
fn decoded_accesses_replay_in_the_console() {
    let dir = scratch("decode");
    let cap = export(
        dir.path(),
        "cap.vcd",
        "s3_4_1_finish_read_releases_int",
        &[],
    );
    let out = ppmc(&["decode", &cap]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let script = text(&out.stdout);
    assert!(script.contains("wc! 0x02"), "{script}");
    let file = dir.path().join("session.ppmc");
    std::fs::write(&file, &script).expect("script");
    let out = ppmc(&["console", file.to_str().expect("utf-8")]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // Every status the capture read, the replay reads too.
    let captured: Vec<&str> = script
        .lines()
        .filter_map(|l| l.strip_prefix("rs  # "))
        .map(|l| &l[..4])
        .collect();
    let replayed: Vec<String> = text(&out.stdout)
        .lines()
        .filter_map(|l| l.strip_prefix("rs "))
        .map(|l| l[..4].to_string())
        .collect();
    assert_eq!(captured, replayed, "{script}");
}

/// A VCD of the bus by hand: `cycles` are (ns, write, a0, byte), each a
/// 100 ns strobe ending at its time; `wires` the bus wires it declares.
fn hand_vcd(cycles: &[(u64, bool, bool, u8)], wires: &[&str]) -> String {
    let mut v = String::from("$timescale 1 ns $end\n$scope module bus $end\n");
    let code = |i: usize| char::from(b'!' + i as u8);
    for (i, w) in wires.iter().enumerate() {
        v.push_str(&format!("$var wire 1 {} {w} $end\n", code(i)));
    }
    v.push_str("$upscope $end\n$enddefinitions $end\n#0\n$dumpvars\n");
    let idle = |w: &str| matches!(w, "cs" | "rd" | "wr");
    for (i, w) in wires.iter().enumerate() {
        v.push_str(&format!("{}{}\n", u8::from(idle(w)), code(i)));
    }
    v.push_str("$end\n");
    let set = |v: &mut String, t: u64, w: &str, level: bool| {
        if let Some(i) = wires.iter().position(|x| *x == w) {
            v.push_str(&format!("#{t}\n{}{}\n", u8::from(level), code(i)));
        }
    };
    for &(t, write, a0, byte) in cycles {
        let strobe = if write { "wr" } else { "rd" };
        set(&mut v, t - 150, "cs", false);
        set(&mut v, t - 150, "a0", a0);
        set(&mut v, t - 100, strobe, false);
        for b in 0..8 {
            set(&mut v, t - 100, &format!("d{b}"), byte >> b & 1 == 1);
        }
        set(&mut v, t, strobe, true);
        set(&mut v, t + 20, "cs", true);
    }
    v.push_str(&format!("#{}\n", cycles.last().map_or(0, |c| c.0) + 1000));
    v
}

const BUS: [&str; 12] = [
    "cs", "rd", "wr", "a0", "d0", "d1", "d2", "d3", "d4", "d5", "d6", "d7",
];

/// Section 3-1-1: a host that writes the data byte 300 ns after the
/// command, while IBF is still 1, is the host firmware's fault (exit 3),
/// not the board's; a capture without WR* cannot be judged (exit 4).
#[test]
fn host_findings_and_capture_problems_are_their_own_kinds() {
    let dir = scratch("judge-kinds");
    let hasty = dir.path().join("hasty.vcd");
    std::fs::write(
        &hasty,
        hand_vcd(&[(1000, true, true, 0x02), (1300, true, false, 0x64)], &BUS),
    )
    .expect("vcd");
    let out = ppmc(&["judge", hasty.to_str().expect("utf-8")]);
    let said = text(&out.stdout);
    assert_eq!(out.status.code(), Some(3), "{said}{}", text(&out.stderr));
    assert!(said.contains("host firmware (section 3-1-1)"), "{said}");
    assert!(said.contains("written while IBF was 1"), "{said}");
    assert!(said.contains("PASS the board"), "{said}");
    // Section 3-2: a single step before any initialization, which the
    // chip answers with error 2 (status 0xA0), is the host's too (exit 3).
    let uninit = dir.path().join("uninit.vcd");
    std::fs::write(
        &uninit,
        hand_vcd(
            &[(1000, true, true, 0x42), (21_000, false, true, 0xA0)],
            &BUS,
        ),
    )
    .expect("vcd");
    let out = ppmc(&["judge", uninit.to_str().expect("utf-8")]);
    let said = text(&out.stdout);
    assert_eq!(out.status.code(), Some(3), "{said}{}", text(&out.stderr));
    assert!(said.contains("host firmware (section 3-2)"), "{said}");
    assert!(said.contains("before the initialization command"), "{said}");
    assert!(said.contains("PASS the board"), "{said}");
    let no_wr: Vec<&str> = BUS.iter().copied().filter(|w| *w != "wr").collect();
    let partial = dir.path().join("no-wr.vcd");
    std::fs::write(&partial, hand_vcd(&[(1000, false, true, 0x00)], &no_wr)).expect("vcd");
    let out = ppmc(&["judge", partial.to_str().expect("utf-8")]);
    let said = text(&out.stdout);
    assert_eq!(out.status.code(), Some(4), "{said}");
    assert!(said.contains("no channel for WR"), "{said}");
    // A file that is no capture is the user's input (exit 2), named.
    let junk = dir.path().join("junk.txt");
    std::fs::write(&junk, "hello").expect("junk");
    let out = ppmc(&["judge", junk.to_str().expect("utf-8")]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("junk.txt"),
        "{}",
        text(&out.stderr)
    );
}

/// Issue 30, item 6: a scenario's capture converted by sigrok-cli itself
/// into sigrok sessions (`.sr`) at 100 MHz and 24 MHz is judged as
/// passing, every pulse compared; at 4 MHz the 100 ns strobes last a
/// single sample, and the capture (exit 4), not the board, is blamed.
#[cfg_attr(
    ppmc_missing_sigrok_cli,
    ignore = "sigrok-cli is not installed (apt install sigrok-cli)"
)]
#[test]
fn sigrok_sessions_at_three_sample_rates_are_judged() {
    if !common::sigrok_cli("judging .sr captures") {
        return;
    }
    let dir = scratch("judge-sr");
    let vcd = export(
        dir.path(),
        "cap.vcd",
        "s3_3_5_constant_speed_100_steps",
        &[],
    );
    // The VCD's 1 ns timescale divided: 100 MHz, 23.8 MHz, 4 MHz.
    for (downsample, code, says) in [
        (10, 0, "100 POUT pulses compared"),
        (42, 0, "100 POUT pulses compared"),
        (250, 4, "needs at least 8 MHz"),
    ] {
        let sr = dir.path().join(format!("cap-{downsample}.sr"));
        let out = std::process::Command::new("sigrok-cli")
            .args([
                "-I",
                &format!("vcd:downsample={downsample}"),
                "-i",
                &vcd,
                "-o",
            ])
            .arg(&sr)
            .output()
            .expect("sigrok-cli runs");
        assert!(out.status.success(), "{}", text(&out.stderr));
        let out = ppmc(&["judge", sr.to_str().expect("utf-8")]);
        let said = text(&out.stdout);
        assert_eq!(out.status.code(), Some(code), "{downsample}: {said}");
        assert!(said.contains(says), "{downsample}: {said}");
        assert!(said.contains("sigrok session"), "{said}");
        // Every access of the VCD is in the session, the last one too
        // (issue 40: sigrok-cli drops the changes at a file's last
        // timestamp, and the export ends 1 us after its last event).
        if code == 0 {
            let accesses = |capture: &str| {
                let out = ppmc(&["decode", capture]);
                let said = text(&out.stdout);
                said.lines().last().unwrap_or_default().to_string()
            };
            assert_eq!(
                accesses(sr.to_str().expect("utf-8")),
                accesses(&vcd),
                "{downsample}"
            );
        }
    }
}

/// `scripts/judge-figures`, which makes the figures of
/// `docs/performance.md` ("Judging a capture"), on a 10 MB capture (the
/// debug build): sigrok-cli converts a scenario's capture cut to 0.01 GB
/// and to a tenth of it, and each row is judged, passes and has its
/// figures.
#[cfg_attr(
    ppmc_missing_sigrok_cli,
    ignore = "sigrok-cli is not installed (apt install sigrok-cli)"
)]
#[test]
fn the_judge_figures_script_measures_both_lengths() {
    if !common::sigrok_cli("the judge's figures") {
        return;
    }
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/../scripts/judge-figures");
    let out = std::process::Command::new(script)
        .args(["--gigabytes", "0.01", "--runs", "1"])
        .args(["--ppmc", env!("CARGO_BIN_EXE_ppmc")])
        .output()
        .expect("the script runs");
    let said = text(&out.stdout);
    assert!(out.status.success(), "{said}{}", text(&out.stderr));
    assert!(
        said.starts_with("| samples (100 MHz, 5 bytes each) |"),
        "{said}"
    );
    for row in ["| 200000 | 0.001 GB |", "| 2000000 | 0.010 GB |"] {
        let line = said
            .lines()
            .find(|l| l.starts_with(row))
            .unwrap_or_else(|| panic!("no row `{row}`:\n{said}"));
        assert!(
            line.ends_with(" MiB |") && line.contains(" M/s |"),
            "{line}"
        );
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        assert!(
            cells.get(4).is_some_and(|c| c.parse::<u64>().is_ok()),
            "no count of pulses compared: {line}"
        );
    }
}

/// Issue 30, item 8: a FIFO where a capture should be, and a 10 GB sparse
/// file (all zeros) under each format's name, are each refused at once
/// with the file named (exit 2), in bounded time and memory: nothing
/// blocks on the FIFO, nothing reads the 10 GB.
#[test]
fn fifos_and_huge_empty_files_are_refused_by_name() {
    let dir = scratch("bad-captures");
    let fifo = |name: &str| {
        let p = dir.path().join(name);
        let made = std::process::Command::new("mkfifo")
            .arg(&p)
            .status()
            .expect("mkfifo runs");
        assert!(made.success());
        p
    };
    let sparse = |name: &str| {
        let p = dir.path().join(name);
        let f = std::fs::File::create(&p).expect("create");
        f.set_len(10 << 30).expect("a sparse 10 GB file");
        p
    };
    let saleae = dir.path().join("saleae");
    std::fs::create_dir(&saleae).expect("folder");
    let cases = [
        (fifo("fifo.sr"), "not a regular file"),
        (fifo("fifo.vcd"), "is a FIFO"),
        (fifo("fifo.csv"), "is a FIFO"),
        (sparse("big.sr"), ""),
        (sparse("big.vcd"), "a token longer than"),
        (sparse("big.csv"), "a line longer than"),
        (sparse("digital_0.bin"), "not a Saleae binary export"),
        (
            {
                let p = saleae.join("digital_0.bin");
                let made = std::process::Command::new("mkfifo")
                    .arg(&p)
                    .status()
                    .expect("mkfifo runs");
                assert!(made.success());
                saleae.clone()
            },
            "is a FIFO",
        ),
    ];
    for (path, says) in cases {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_ppmc"))
            .arg("judge")
            .arg(&path)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("ppmc runs");
        let status = common::wait_bounded(&mut child, std::time::Duration::from_secs(30));
        let mut err = String::new();
        std::io::Read::read_to_string(&mut child.stderr.take().expect("stderr"), &mut err)
            .expect("stderr reads");
        let name = path
            .file_name()
            .expect("name")
            .to_string_lossy()
            .into_owned();
        assert_eq!(status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(&name), "{name}: {err}");
        assert!(err.contains(says), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
    }
}

/// `ppmc judge CAPTURE --junit J --json R --html H`: the JUnit report and
/// the JSON run record (checked against `docs/run-record.schema.json`),
/// and the judgement's exit status; the HTML page, a judge's, names every
/// result of the record and what a failure expected.
fn judged(dir: &Path, capture: &str) -> (Option<i32>, quick_junit::Report, String, Value) {
    let junit = dir.join("judge.xml");
    let json = dir.join("judge.json");
    let html = dir.join("judge.html");
    for f in [&junit, &json, &html] {
        let _ = std::fs::remove_file(f);
    }
    let out = ppmc(&[
        "judge",
        capture,
        "--junit",
        junit.to_str().expect("utf-8"),
        "--json",
        json.to_str().expect("utf-8"),
        "--html",
        html.to_str().expect("utf-8"),
    ]);
    let page = std::fs::read_to_string(&html).expect("the HTML report is written");
    let xml = std::fs::read_to_string(&junit).expect("the JUnit report is written");
    let report = quick_junit::Report::deserialize_from_str(&xml).expect("the JUnit report parses");
    let record: Value = serde_json::from_str(&std::fs::read_to_string(&json).expect("written"))
        .expect("the record is JSON");
    check_record(&run_record_schema(), &record);
    assert_eq!(record["run"]["source"]["kind"], "capture", "{record:#}");
    assert_eq!(record["run"]["source"]["path"], capture);
    // What CI asserts of a run's reports holds of a judge's too: the
    // summary counts one verdict per test case.
    let cases: usize = report.test_suites.iter().map(|s| s.test_cases.len()).sum();
    let s = &record["summary"];
    let counted: u64 = ["passed", "marginal", "failed", "error", "not_run"]
        .iter()
        .map(|k| s[k].as_u64().expect("a count"))
        .sum();
    assert_eq!(counted as usize, cases, "{record:#}");
    assert!(
        page.contains("<title>ppmc judge report"),
        "the page's title"
    );
    for r in record["scenarios"].as_array().expect("results") {
        let name = r["name"].as_str().expect("a name");
        assert!(page.contains(name), "the page names {name}");
        if let Some(expected) = r["failure"]["expectation"].as_str() {
            assert!(
                page.contains(expected),
                "the page says what {name} expected: {expected}"
            );
        }
    }
    (out.status.code(), report, xml, record)
}

/// A test case's failure or error: its element, type, message and text;
/// `None` when it passed.
fn outcome(c: &quick_junit::TestCase) -> Option<(&'static str, String, String, String)> {
    match &c.status {
        quick_junit::TestCaseStatus::Success { .. } => None,
        quick_junit::TestCaseStatus::NonSuccess {
            kind,
            message,
            ty,
            description,
            ..
        } => Some((
            match kind {
                quick_junit::NonSuccessKind::Failure => "failure",
                quick_junit::NonSuccessKind::Error => "error",
            },
            ty.as_ref().map(|t| t.to_string()).unwrap_or_default(),
            message.as_ref().map(|t| t.to_string()).unwrap_or_default(),
            description
                .as_ref()
                .map(|t| t.to_string())
                .unwrap_or_default(),
        )),
        quick_junit::TestCaseStatus::Skipped { .. } => {
            Some(("skipped", "".into(), "".into(), "".into()))
        }
    }
}

/// Sections 3-3 and 3-4, in the reports (issue 30): a clean board's
/// capture is two passing test cases, the board and the host firmware,
/// blamed on no one; the capture is the record's source. A board that
/// loses the last pulse of a move is a failure of type `device`, its
/// message the divergence, its text what was not judged and what was
/// compared, the record blaming the board; the host firmware still passes.
#[test]
fn judge_reports_blame_the_board_for_its_divergence() {
    let dir = scratch("judge-reports");
    let clean = export(
        dir.path(),
        "clean.vcd",
        "s3_3_5_constant_speed_100_steps",
        &[],
    );
    let (code, report, xml, record) = judged(dir.path(), &clean);
    assert_eq!(code, Some(0), "{xml}");
    let suite = &report.test_suites[0];
    let names: Vec<&str> = suite.test_cases.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        ["judge.clean.vcd", "judge.clean.vcd.host-firmware"],
        "{xml}"
    );
    assert!(
        suite.test_cases.iter().all(|c| outcome(c).is_none()),
        "{xml}"
    );
    assert_eq!(record["summary"]["passed"], 2);
    assert_eq!(record["scenarios"][0]["blame"], Value::Null);
    assert_eq!(
        record["scenarios"][1]["host_findings"],
        serde_json::json!([])
    );
    assert_eq!(record["run"]["source"]["pulses"], 100);
    assert_eq!(record["run"]["source"]["format"], "VCD (ppmc)");

    let bad = export(
        dir.path(),
        "bad.vcd",
        "s3_3_5_constant_speed_100_steps",
        &["drop-last-pulse"],
    );
    let (code, report, xml, record) = judged(dir.path(), &bad);
    assert_eq!(code, Some(1), "{xml}");
    let cases = &report.test_suites[0].test_cases;
    let (tag, ty, message, text) = outcome(&cases[0]).expect("the board fails");
    assert_eq!((tag, ty.as_str()), ("failure", "device"), "{xml}");
    assert!(message.starts_with("POUT pulse 100 at "), "{message}");
    assert!(!text.contains("not judged: "), "every pin compared: {text}");
    assert!(text.contains("99 POUT pulses compared"), "{text}");
    assert_eq!(outcome(&cases[1]), None, "the host is not blamed: {xml}");
    assert_eq!(report.failures, 1);
    assert_eq!(report.errors, 0);
    let board = &record["scenarios"][0];
    assert_eq!(board["verdict"], "failed");
    assert_eq!(board["blame"], "board");
    assert_eq!(board["failure"]["expectation"], "POUT pulse 100");
    assert_eq!(record["scenarios"][1]["verdict"], "passed");
    assert_eq!(record["scenarios"][1]["blame"], Value::Null);
}

/// Section 3-1-1, in the reports: a host that writes the data byte while
/// IBF is still 1 is a failure of type `host` on the host firmware's
/// test case, each finding with its section, while the board's passes;
/// the record blames the host and lists its findings.
#[test]
fn judge_reports_blame_the_host_firmware_for_its_findings() {
    let dir = scratch("judge-reports-host");
    let hasty = dir.path().join("hasty.vcd");
    std::fs::write(
        &hasty,
        hand_vcd(&[(1000, true, true, 0x02), (1300, true, false, 0x64)], &BUS),
    )
    .expect("vcd");
    let (code, report, xml, record) = judged(dir.path(), hasty.to_str().expect("utf-8"));
    assert_eq!(code, Some(3), "{xml}");
    let cases = &report.test_suites[0].test_cases;
    assert_eq!(cases[0].name.as_str(), "judge.hasty.vcd");
    assert_eq!(outcome(&cases[0]), None, "the board passes: {xml}");
    assert_eq!(cases[1].name.as_str(), "judge.hasty.vcd.host-firmware");
    let (tag, ty, message, text) = outcome(&cases[1]).expect("the host fails");
    assert_eq!((tag, ty.as_str()), ("failure", "host"), "{xml}");
    assert!(
        message.contains("broke chapter 3's rules 1 times"),
        "{message}"
    );
    assert!(text.contains("host firmware (section 3-1-1)"), "{text}");
    assert!(text.contains("written while IBF was 1"), "{text}");
    assert_eq!(cases[1].classname.as_deref(), Some("section 3-1-1"));
    assert_eq!(record["scenarios"][0]["verdict"], "passed");
    let host = &record["scenarios"][1];
    assert_eq!(host["verdict"], "failed");
    assert_eq!(host["blame"], "host");
    assert_eq!(host["host_findings"][0]["section"], "3-1-1");
    assert_eq!(host["host_findings"][0]["at_ns"], 1300);
}

/// A capture without WR* (no bus to decode: Table 3-1's strobes) is an
/// error of type `capture`, neither the board's nor the host's: one test
/// case, no failure; the record's error kind and blame are the capture.
#[test]
fn judge_reports_blame_the_capture_for_a_missing_channel() {
    let dir = scratch("judge-reports-capture");
    let no_wr: Vec<&str> = BUS.iter().copied().filter(|w| *w != "wr").collect();
    let partial = dir.path().join("no-wr.vcd");
    std::fs::write(&partial, hand_vcd(&[(1000, false, true, 0x00)], &no_wr)).expect("vcd");
    let (code, report, xml, record) = judged(dir.path(), partial.to_str().expect("utf-8"));
    assert_eq!(code, Some(4), "{xml}");
    assert_eq!((report.failures, report.errors), (0, 1), "{xml}");
    let cases = &report.test_suites[0].test_cases;
    assert_eq!(cases.len(), 1, "nothing else was judged: {xml}");
    let (tag, ty, message, _) = outcome(&cases[0]).expect("an error");
    assert_eq!((tag, ty.as_str()), ("error", "capture"), "{xml}");
    assert!(message.contains("no channel for WR"), "{message}");
    let s = &record["scenarios"][0];
    assert_eq!(s["verdict"], "error");
    assert_eq!(s["blame"], "capture");
    assert_eq!(s["error"]["kind"], "capture");
    assert_eq!(record["summary"]["error"], 1);
}

/// The reports keep `ppmc run`'s write rules: the two reports in one file
/// is bad usage (exit 2) and nothing is judged; `--json -` puts the record
/// on standard output and the verdict lines on standard error.
#[test]
fn judge_reports_keep_the_write_rules() {
    let dir = scratch("judge-reports-rules");
    let cap = export(
        dir.path(),
        "cap.vcd",
        "s3_4_1_finish_read_releases_int",
        &[],
    );
    let same = dir.path().join("r.out");
    let s = same.to_str().expect("utf-8");
    let out = ppmc(&["judge", &cap, "--junit", s, "--json", s]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("are the same file"),
        "{}",
        text(&out.stderr)
    );
    assert!(text(&out.stdout).is_empty(), "{}", text(&out.stdout));
    assert!(!same.exists());
    let out = ppmc(&["judge", &cap, "--json", "-"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let record: Value = serde_json::from_slice(&out.stdout).expect("the record alone");
    check_record(&run_record_schema(), &record);
    assert!(
        text(&out.stderr).contains("PASS the board"),
        "{}",
        text(&out.stderr)
    );
}

/// Issue 30, item 5: `ppmc judge --trace` writes a capture as a trace, and
/// `ppmc compare` judges it against the golden trace as it judges a board
/// behind the bridge: a clean board's capture compares equal (3-3-4's
/// moves, pulses and outputs; the writes and data reads), a board that
/// loses a move's last pulse (3-3-1) diverges at the number of pulses. A
/// trace already there is never replaced.
#[test]
fn a_captures_trace_compares_with_the_golden_trace() {
    let dir = scratch("judge-trace");
    let scenario = "s3_3_4_accel_1000_steps_cw";
    let golden = concat!(env!("CARGO_MANIFEST_DIR"), "/../golden");
    for (faults, folder, verdict) in [
        (&[][..], "clean", "PASS"),
        (&["drop-last-pulse"][..], "faulty", "FAIL"),
    ] {
        let cap = export(dir.path(), &format!("{folder}.vcd"), scenario, faults);
        let traces = dir.path().join(folder);
        let traces = traces.to_str().expect("utf-8");
        let out = ppmc(&["judge", &cap, "--trace", traces, "--scenario", scenario]);
        let said = text(&out.stdout);
        assert!(
            said.contains(&format!("trace: {traces}/{scenario}.snap")),
            "{said}"
        );
        let out = ppmc(&["compare", golden, "--traces", traces, "--filter", scenario]);
        let said = text(&out.stdout);
        assert!(said.starts_with(&format!("{verdict} ")), "{said}");
        if verdict == "FAIL" {
            assert!(said.contains("number of pulses: expected 1000"), "{said}");
            // The clean capture's trace is not put over the faulty one.
            let clean = dir.path().join("clean.vcd");
            let out = ppmc(&[
                "judge",
                clean.to_str().expect("utf-8"),
                "--trace",
                traces,
                "--scenario",
                scenario,
            ]);
            assert_ne!(out.status.code(), Some(0));
            assert!(text(&out.stderr).contains("exists, with another trace"));
        }
    }
}

/// Issue 30, item 8: a capture with nothing on the bus (the probes off
/// it, or the recording started after the host's accesses) is the
/// capture's problem (exit 4), never a pass.
#[test]
fn a_capture_with_nothing_on_the_bus_is_the_captures_problem() {
    let dir = scratch("quiet-bus");
    let quiet = dir.path().join("quiet.vcd");
    std::fs::write(&quiet, hand_vcd(&[], &BUS)).expect("vcd");
    let out = ppmc(&["judge", quiet.to_str().expect("utf-8")]);
    let said = text(&out.stdout);
    assert_eq!(out.status.code(), Some(4), "{said}{}", text(&out.stderr));
    assert!(said.contains("no register access on the bus"), "{said}");
}

/// `ppmc judge` on `capture` with `args` exits with `code` and says each
/// of `says`; what it said.
fn judge_says(capture: &str, args: &[&str], code: i32, says: &[&str]) -> String {
    let mut all = vec!["judge", capture];
    all.extend_from_slice(args);
    let out = ppmc(&all);
    let said = format!("{}{}", text(&out.stdout), text(&out.stderr));
    assert_eq!(out.status.code(), Some(code), "{args:?}: {said}");
    for s in says {
        assert!(said.contains(s), "{args:?}: `{s}` not in\n{said}");
    }
    said
}

/// The VCD `src` with each line passed through `f` (`None` drops it).
fn rewrite(src: &str, dst: &Path, f: impl Fn(&str) -> Option<String>) -> String {
    let text = std::fs::read_to_string(src).expect("our VCD");
    let out: Vec<String> = text.lines().filter_map(f).collect();
    std::fs::write(dst, out.join("\n") + "\n").expect("write");
    dst.to_str().expect("utf-8").to_string()
}

/// Issue 40: a capture that stops early (in the middle of a line, of a
/// move: 3-3-4's 1,000 pulses cut after some 500) is the capture's
/// problem, exit 4, never a pass; with --partial, a pass that says what
/// was not judged.
#[test]
fn a_capture_cut_short_is_the_captures_problem() {
    let dir = scratch("judge-cut");
    let whole = export(dir.path(), "whole.vcd", "s3_3_4_accel_1000_steps_cw", &[]);
    let text = std::fs::read_to_string(&whole).expect("VCD");
    let half = dir.path().join("half.vcd");
    // Half the file, cut three bytes into a timestamp's line (`#12` of
    // `#1234567`).
    let cut = text.len() / 2;
    let cut = text[..cut].rfind("\n#").expect("timestamps") + 4;
    std::fs::write(&half, &text[..cut]).expect("write");
    let half = half.to_str().expect("utf-8");
    judge_says(
        half,
        &[],
        4,
        &[
            "ERROR the capture",
            "the file ends in the middle of line",
            "the recording ends during move 1, the board still moving",
            "pulses unjudged",
        ],
    );
    judge_says(
        half,
        &["--partial"],
        0,
        &[
            "not judged: the recording ends during move 1",
            "PASS the board",
        ],
    );
    // Cut at a line's end, mid-move: the move alone says it.
    let at_line = &text[..text[..text.len() / 2].rfind('\n').expect("lines") + 1];
    let line_cut = dir.path().join("line.vcd");
    std::fs::write(&line_cut, at_line).expect("write");
    let said = judge_says(
        line_cut.to_str().expect("utf-8"),
        &[],
        4,
        &["the board still moving"],
    );
    assert!(!said.contains("middle of line"), "{said}");
}

/// A map names each signal once and each channel once: bad usage (exit
/// 2), naming both pairs. A VCD of a million nested scopes is refused at
/// the nesting limit, in bounded memory (exit 2, the file's line named).
#[test]
fn a_doubled_map_and_a_million_scopes_are_refused() {
    let dir = scratch("judge-refused");
    let vcd = export(dir.path(), "c.vcd", "s3_3_5_constant_speed_100_steps", &[]);
    judge_says(
        &vcd,
        &["--map", "CS=cs,CS=rd"],
        2,
        &["CS is given twice (`CS=cs` before)"],
    );
    judge_says(
        &vcd,
        &["--map", "CS=cs,RD=cs"],
        2,
        &["channel `cs` is given for CS already"],
    );
    let deep = dir.path().join("deep.vcd");
    let mut f = std::io::BufWriter::new(std::fs::File::create(&deep).expect("create"));
    use std::io::Write;
    writeln!(f, "$timescale 1 ns $end").expect("write");
    for _ in 0..1_000_000 {
        writeln!(f, "$scope module m $end").expect("write");
    }
    writeln!(f, "$var wire 1 ! cs $end\n$enddefinitions $end\n#0 1!").expect("write");
    drop(f);
    judge_says(
        deep.to_str().expect("utf-8"),
        &[],
        2,
        &["line 258: $scope nested deeper than 256 levels"],
    );
}

/// A wrong map is the capture's problem, naming the signal, never the
/// board's: POUT with no channel while the chip pulses; D0 and D1
/// exchanged; CS and RD exchanged; WR* inverted (strobes that overlap);
/// channels named as sigrok names them (`D0`..`D37`), never taken for the
/// data lines.
#[test]
fn a_wrong_map_is_the_captures_problem_naming_the_signal() {
    let dir = scratch("judge-wrong-map");
    let vcd = export(dir.path(), "a.vcd", "s3_3_4_accel_1000_steps_cw", &[]);
    let no_pout = rewrite(&vcd, &dir.path().join("nopout.vcd"), |l| {
        Some(l.replace(" pout $end", " probe7 $end"))
    });
    let said = judge_says(&no_pout, &[], 4, &["no channel for POUT"]);
    assert!(!said.contains("FAIL the board"), "{said}");
    judge_says(
        &vcd,
        &["--map", "D0=d1,D1=d0"],
        4,
        &["but D0 and D1 look exchanged"],
    );
    judge_says(
        &vcd,
        &["--map", "CS=rd,RD=cs"],
        4,
        &["but CS and RD look exchanged"],
    );
    // WR* read inverted: it idles low, so every read has both strobes low.
    judge_says(
        &vcd,
        &["--map", "WR=~wr"],
        4,
        &["RD* and WR* were low together with CS*"],
    );
    let n = std::cell::Cell::new(0);
    let default_names = rewrite(&vcd, &dir.path().join("names.vcd"), |l| {
        let w: Vec<&str> = l.split(' ').collect();
        if w.len() == 6 && w[0] == "$var" {
            let k = n.get();
            n.set(k + 1);
            return Some(format!("{} {} {} {} D{k} {}", w[0], w[1], w[2], w[3], w[5]));
        }
        Some(l.to_string())
    });
    judge_says(
        &default_names,
        &[],
        4,
        &["named as the analyzer names them (D0..D37)"],
    );
}

/// POUT and DIR inverted by the board's output stage: `~` in the map
/// judges them (3-3-4's pulses and direction); without it, a POUT that
/// idles high is the capture's problem naming the map, and a DIR
/// opposite at every pulse a hint naming the map that passes.
#[test]
fn inverted_pout_and_dir_are_judged_with_a_tilde_and_hinted_without() {
    let dir = scratch("judge-inverted");
    let vcd = export(dir.path(), "a.vcd", "s3_3_4_accel_1000_steps_cw", &[]);
    let text = std::fs::read_to_string(&vcd).expect("VCD");
    let code_of = |name: &str| {
        text.lines()
            .find(|l| l.ends_with(&format!(" {name} $end")) && l.starts_with("$var"))
            .and_then(|l| l.split(' ').nth(3))
            .expect("declared")
            .to_string()
    };
    let (pout, dirc) = (code_of("pout"), code_of("dir"));
    let inverted = rewrite(&vcd, &dir.path().join("inv.vcd"), |l| {
        for c in [&pout, &dirc] {
            match l.strip_suffix(c.as_str()) {
                Some("0") => return Some(format!("1{c}")),
                Some("1") => return Some(format!("0{c}")),
                _ => {}
            }
        }
        Some(l.to_string())
    });
    judge_says(
        &inverted,
        &["--map", "POUT=~pout,DIR=~dir"],
        0,
        &["1000 POUT pulses compared"],
    );
    // Without the map: POUT idles high, the capture's problem, naming the
    // map that reads it.
    judge_says(
        &inverted,
        &[],
        4,
        &[
            "POUT is high where the model starts (the chip idles it low): it looks inverted",
            "--map POUT=~pout",
        ],
    );
    // POUT read inverted, DIR not: the board diverges at DIR, with the
    // hint that names the map that passes.
    judge_says(
        &inverted,
        &["--map", "POUT=~pout"],
        1,
        &["hint: DIR looks inverted: judged with `--map POUT=~pout,DIR=~dir` the board passes"],
    );
}

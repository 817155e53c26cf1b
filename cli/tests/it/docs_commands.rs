//! Docs that cannot rot: every command shown in `README.md`, `docs/*.md`,
//! `fuzz/README.md` and `scenarios/README.md` is run here, as written, in a
//! scratch directory per file (commands of one file run in order, so a
//! `record --out rev-b/` feeds the `compare` after it), and every shown
//! output (`$ command` then its lines, in a `text` block) must match. A
//! flag that changes, a file a command names that a clean checkout lacks,
//! or an output that drifts fails CI.
//!
//! What is not run here says why, in [`ELSEWHERE`]: it runs in `.ci/run`
//! (checked below to be there) or in another test. Board ports in the docs
//! (`serial:/dev/ttyACM0`, `serial:/dev/pts/3`) are served by a bridge
//! simulator the test starts; a `ppmc bridge-sim` line is started, must
//! say where it serves, and is stopped. Measurement commands run with the
//! smallest workload their flags allow ([`SHRINK`]).

use crate::common;
use common::{scratch, text, wait_bounded};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// The files whose commands run.
const FILES: [&str; 15] = [
    "README.md",
    "docs/reports.md",
    "docs/results-store.md",
    "docs/capture.md",
    "docs/board-farm.md",
    "firmware/README.md",
    "docs/bridge-hardware.md",
    "docs/conformance.md",
    "docs/console.md",
    "docs/detection.md",
    "docs/performance.md",
    "docs/writing-scenarios.md",
    "docs/bridge-protocol.md",
    "fuzz/README.md",
    "scenarios/README.md",
];

/// Commands run elsewhere, by prefix, and where. Those "in .ci/run" must
/// appear in `.ci/run` as written (the part after the prefix's match).
const ELSEWHERE: [(&str, &str); 42] = [
    (
        "PPMC=target/release/ppmc scripts/campaign-figures",
        "by hand (405 runs of a minute of board time each against bridge-sim: a guided and a blind campaign and the --seed stream, five seeds each, for each of 27 chips; its figures in docs/performance.md); at a second of board time and one seed in cli/tests/it/cli_fuzz.rs",
    ),
    (
        "scripts/bridge-sim-power",
        "in cli/tests/it/cli_power.rs (a bridge-sim made to hang, power-cycled through --power-cmd and --power-hub)",
    ),
    ("export LG_ENV=", "in cli/tests/it/labgrid/place.sh"),
    (
        "scripts/store-load",
        "by hand (10,000 runs of the suite; its figures in docs/performance.md); .ci/run runs it with 100 runs a station on both databases",
    ),
    (
        "scripts/fuzz-memory",
        "by hand (30 minutes of a fuzz against bridge-sim; its figures in docs/performance.md)",
    ),
    (
        "scripts/pg-throwaway",
        "started by .ci/run for the store's tests; by hand, a server to try the store on",
    ),
    (
        "scripts/rebuild-figures",
        "in .ci/run (after the tests, on the built workspace)",
    ),
    (
        "scripts/loaded-check",
        "by hand (an hour of a loaded machine; its figures in docs/performance.md); the script itself in loaded_check_says_how_each_run_ended below",
    ),
    (
        "docs/examples/chop-period.sh",
        "in cli/tests/it/console_cli.rs (on the emulator and through ppmc bridge-sim, the debug build)",
    ),
    (
        "scripts/store-figures",
        "in cli/tests/it/results_store.rs (a store of 3 runs, the debug build)",
    ),
    (
        "sigrok-cli -I vcd:downsample=42",
        "in cli/tests/it/cli_capture.rs (the same conversion at three rates, each capture judged)",
    ),
    (
        "SIGROKDECODE_DIR=contrib/sigrok sigrok-cli",
        "in cli/tests/it/vcd_sigrok.rs (the PulseView decoder on a capture of a scenario)",
    ),
    (
        "timeout -s INT 5 ppmc run",
        "in cli/tests/it/cli_signals.rs (timeout -s INT during the long move on a real-time bridge, ten times)",
    ),
    (
        "scripts/report-images",
        "in .ci/run (the browser step; it needs node and Chromium)",
    ),
    (
        "scripts/fuzz-figures",
        "in .ci/run (the fuzz step runs every row, 1 s each; it needs nightly and cargo-fuzz)",
    ),
    (
        "scripts/network-figures",
        "in cli/tests/it/cli_network.rs (every row once, the debug build)",
    ),
    (
        "scripts/judge-figures",
        "in cli/tests/it/cli_capture.rs (a 0.01 GB capture and a tenth of it, the debug build)",
    ),
    (
        "labgrid-client",
        "in cli/tests/it/labgrid/place.sh (against a local coordinator)",
    ),
    (
        "unshare -rn bash",
        "in cli/tests/it/cli_labgrid.rs, which runs cli/tests/it/labgrid/place.sh so (unshare -n, as root)",
    ),
    ("ip link set lo up", "in cli/tests/it/labgrid/place.sh"),
    ("ip addr add", "in cli/tests/it/labgrid/place.sh"),
    ("labgrid-coordinator", "in cli/tests/it/labgrid/place.sh"),
    (
        "labgrid-exporter -c 127.0.0.1",
        "in cli/tests/it/labgrid/place.sh",
    ),
    (
        "labgrid-exporter",
        "started by cli/tests/it/labgrid/place.sh, with --hostname 127.0.0.1 in a network namespace",
    ),
    (
        "PPMC_BOARD=",
        "needs a board; .ci/run runs the same test group against the QEMU board",
    ),
    ("cargo test", "in .ci/run (the test step)"),
    (
        "firmware/build qemu",
        "in harness/tests/it/firmware_qemu.rs (firmware/run-qemu builds the image so)",
    ),
    (
        "firmware/build board",
        "a part of `firmware/build`, which runs in .ci/run (the firmware step)",
    ),
    ("firmware/build", "in .ci/run (the firmware step)"),
    (
        "firmware/run-twin",
        "in harness/tests/it/firmware_twin.rs (started, scenarios run through it, stopped)",
    ),
    (
        "firmware/run-qemu",
        "in harness/tests/it/firmware_qemu.rs (started, the whole suite run through it, stopped)",
    ),
    (
        "cargo run --release --locked --manifest-path firmware/Cargo.toml -p ppmc-twin --bin capture-margin",
        "in .ci/run (the firmware step: the twin's capture margin)",
    ),
    (
        "firmware/pioemu/run",
        "in .ci/run (the pioemu step, with the CI venv's Python)",
    ),
    (
        "cargo run -p board-suite",
        "in .ci/run (a board team's own suite: the binary the tests' build made, with these arguments)",
    ),
    (
        "cargo install cargo-fuzz",
        "in .ci/run (the fuzz step installs it)",
    ),
    (
        "cargo +nightly fuzz run",
        "in .ci/run (the fuzz step runs every target so, 20 s each)",
    ),
    (
        "mkdir -p ../target/fuzz-corpus",
        "in .ci/run (the fuzz step's scratch corpus)",
    ),
    ("cd ", "shell navigation around the fuzz commands"),
    (
        "cp fuzz/artifacts",
        "a template: there is no finding to copy on a clean checkout",
    ),
    (
        "sigrok-cli -d fx2lafw",
        "needs a logic analyzer on a board; cli/tests/it/suite_captures.rs judges sigrok-cli's sessions of every scenario",
    ),
    (
        "sigrok-cli",
        "in cli/tests/it/vcd_sigrok.rs (the same decoder and options)",
    ),
    (
        "/usr/bin/time -v",
        "a measurement; the command after it runs here",
    ),
];

/// `ppmc` commands whose targets are a lab's, run elsewhere against a
/// local stand-in: `(text in the command, where)`. Those "in
/// cli/tests/it/labgrid/place.sh" must appear in that script as written
/// (with `"$ppmc"` for `ppmc`).
const PPMC_ELSEWHERE: [(&str, &str); 7] = [
    (
        "fuzz replay fuzz-findings/",
        "in cli/tests/it/cli_fuzz.rs (a finding of a campaign against a faulty bridge-sim, replayed there and on the emulator, shrunk, made a scenario)",
    ),
    (
        "serial:/tmp/rig/pty",
        "in cli/tests/it/cli_power.rs (the same bridge, made to hang and power-cycled)",
    ),
    (
        "judge out/capture.sr",
        "in cli/tests/it/cli_capture.rs (sigrok-cli converts a capture to .sr at 100, 24 and 4 MHz, each judged)",
    ),
    (
        "selftest --target serial:",
        "in cli/tests/it/cli_selftest.rs (against the board twin: a bridge-sim has no generator)",
    ),
    (
        "127.0.0.1:4000",
        "in cli/tests/it/cli_chaos.rs (the chaos proxy in front of a bridge-sim, a suite run through it)",
    ),
    (
        "bench1.lab:4321",
        "in cli/tests/it/cli_network.rs (the suite through ser2net on 127.0.0.1, both modes)",
    ),
    ("--target labgrid:", "in cli/tests/it/labgrid/place.sh"),
];

/// The script that runs the labgrid commands of the docs.
const LABGRID_SCRIPT: &str = "cli/tests/it/labgrid/place.sh";

/// Measurement commands and how they are shrunk here: `(text to find,
/// replacement)`, applied to the command before it runs.
const SHRINK: [(&str, &str); 7] = [
    ("bench --repeat 21", "bench --repeat 1"),
    // The 10-minute soak and fuzz run of docs/performance.md.
    ("run --repeat 100000000", "run --repeat 2 --filter s3_3_5"),
    ("--duration 600s", "--duration 1s"),
    (
        "bench --noisy-link --seeds 3",
        "bench --noisy-link --seeds 1 --fault corrupt:0.1",
    ),
    (
        "--ops 1000000000 --duration 5s",
        "--ops 1000000000 --duration 1s",
    ),
    // The 816 MB VCD is streamed to standard output and thrown away.
    ("-o big.vcd", "-o -"),
    ("--duration 300s", "--duration 5s"),
];

/// A documented command.
#[derive(Debug)]
struct Doc {
    file: &'static str,
    line: usize,
    command: String,
    /// Shown output (`text` blocks), to match exactly.
    output: Option<String>,
}

impl std::fmt::Display for Doc {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}: `{}`", self.file, self.line, self.command)
    }
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `line` without a trailing `# comment` (outside quotes).
fn strip_comment(line: &str) -> &str {
    let mut quoted = false;
    let b = line.as_bytes();
    for (i, c) in line.char_indices() {
        match c {
            '\'' => quoted = !quoted,
            '#' if !quoted && (i == 0 || b[i - 1] == b' ') => return line[..i].trim_end(),
            _ => {}
        }
    }
    line.trim_end()
}

/// Every command of `file`: the lines of `sh` blocks, and the `$ ` lines
/// of `text` blocks with the output shown under them.
fn commands(file: &'static str) -> Vec<Doc> {
    let body = std::fs::read_to_string(root().join(file)).expect("doc file");
    let mut out = Vec::new();
    let mut block: Option<&str> = None;
    for (i, line) in body.lines().enumerate() {
        // Fences indented in a list item count too.
        if let Some(lang) = line.trim_start().strip_prefix("```") {
            block = match block {
                Some(_) => None,
                None => Some(lang.trim()),
            };
            continue;
        }
        match block {
            Some("sh") => {
                let c = strip_comment(line.trim());
                if !c.is_empty() {
                    out.push(Doc {
                        file,
                        line: i + 1,
                        command: c.to_string(),
                        output: None,
                    });
                }
            }
            Some("text") => {
                if let Some(c) = line.strip_prefix("$ ") {
                    out.push(Doc {
                        file,
                        line: i + 1,
                        command: c.to_string(),
                        output: Some(String::new()),
                    });
                } else if let Some(Doc {
                    output: Some(o), ..
                }) = out.last_mut()
                {
                    o.push_str(line);
                    o.push('\n');
                }
            }
            _ => {}
        }
    }
    out
}

/// Shell words, with single quotes; `< file` is standard input.
fn words(cmd: &str) -> (Vec<String>, Option<String>) {
    let mut words = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut any = false;
    for c in cmd.chars() {
        match c {
            '\'' => {
                quoted = !quoted;
                any = true;
            }
            ' ' if !quoted => {
                if any {
                    words.push(std::mem::take(&mut cur));
                    any = false;
                }
            }
            c => {
                cur.push(c);
                any = true;
            }
        }
    }
    if any {
        words.push(cur);
    }
    let mut stdin = None;
    if let Some(i) = words.iter().position(|w| w == "<") {
        stdin = words.get(i + 1).cloned();
        words.truncate(i);
    }
    (words, stdin)
}

/// The `ppmc` arguments of a command that runs the tool, if it does.
fn ppmc_args(cmd: &str) -> Option<String> {
    let cmd = cmd.strip_prefix("/usr/bin/time -v ").unwrap_or(cmd);
    // A run stopped after its time as CI would (the shrunk run ends first).
    let cmd = cmd.strip_prefix("timeout -s INT 600 ").unwrap_or(cmd);
    [
        "ppmc ",
        "cargo run --bin ppmc -- ",
        "cargo run --release --bin ppmc -- ",
        "cargo run -q --bin ppmc -- ",
    ]
    .iter()
    .find_map(|p| cmd.strip_prefix(p))
    .map(str::to_string)
    .or_else(|| (cmd == "ppmc").then(String::new))
}

/// A bridge simulator the documented board ports stand for.
struct Bridge {
    child: std::process::Child,
    link: PathBuf,
    _out: BufReader<std::process::ChildStdout>,
}

impl Bridge {
    fn start(dir: &Path, name: &str, args: &[String]) -> Result<Bridge, String> {
        let link = dir.join(name);
        let mut child = Command::new(env!("CARGO_BIN_EXE_ppmc"))
            .arg("bridge-sim")
            .args(args)
            .arg("--link")
            .arg(&link)
            .current_dir(dir)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| e.to_string())?;
        let mut out = BufReader::new(child.stdout.take().expect("piped"));
        let mut first = String::new();
        out.read_line(&mut first).map_err(|e| e.to_string())?;
        if !first.starts_with("bridge-sim: serving on /dev/") {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("bridge-sim printed `{}`", first.trim()));
        }
        Ok(Bridge {
            child,
            link,
            _out: out,
        })
    }
}

impl Drop for Bridge {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_file(&self.link);
    }
}

/// A scratch directory that looks like a checkout to the commands: the
/// golden traces, examples, fuzz corpus and regression inputs, a script,
/// and a findings folder.
fn workspace(tag: &str) -> tempfile::TempDir {
    let dir = scratch(tag);
    let d = dir.path();
    let r = root();
    std::os::unix::fs::symlink(r.join("golden"), d.join("golden")).expect("link");
    std::fs::create_dir_all(d.join("docs")).expect("docs");
    std::os::unix::fs::symlink(r.join("docs/examples"), d.join("docs/examples")).expect("link");
    std::fs::create_dir_all(d.join("fuzz/artifacts/bus_bytes")).expect("fuzz");
    std::os::unix::fs::symlink(r.join("fuzz/corpus"), d.join("fuzz/corpus")).expect("link");
    std::os::unix::fs::symlink(r.join("fuzz/regressions"), d.join("fuzz/regressions"))
        .expect("link");
    for f in std::fs::read_dir(r.join("fuzz/regressions/bus_bytes")).expect("regressions") {
        let f = f.expect("entry").path();
        let name = f.file_name().expect("name");
        std::fs::copy(&f, d.join("fuzz/artifacts/bus_bytes").join(name)).expect("copy");
    }
    for s in ["script.ppmc", "my-script.ppmc"] {
        std::fs::copy(r.join("docs/examples/accel-1000-steps.ppmc"), d.join(s)).expect("copy");
    }
    dir
}

/// The lab's PostgreSQL store of docs/board-farm.md, which a throwaway
/// server's database stands for (`ppmc_test_support::postgres`).
const LAB_STORE: &str = "postgres://ppmc@db.lab:5432/results";

/// What a file's commands share: the bridges its board ports stand for,
/// and the lab's store (`None` until a command names it; `Some(None)`
/// where this machine has no PostgreSQL, outside CI).
#[derive(Default)]
struct Lab {
    boards: [Option<Bridge>; 2],
    store: Option<Option<ppmc_test_support::postgres::Db>>,
}

/// Runs one documented `ppmc` command in `dir`; `Err` says what is wrong.
fn run(doc: &Doc, args: &str, dir: &Path, lab: &mut Lab) -> Result<(), String> {
    let boards = &mut lab.boards;
    let mut args = args.to_string();
    for (from, to) in SHRINK {
        args = args.replace(from, to);
    }
    let (mut argv, stdin) = words(&args);
    // `> file`: standard output into a file of the scratch directory.
    let into = argv.iter().position(|w| w == ">").map(|i| {
        let file = argv.get(i + 1).cloned().unwrap_or_default();
        argv.truncate(i);
        file
    });
    if argv.iter().any(|a| a.contains(LAB_STORE)) {
        let db = lab
            .store
            .get_or_insert_with(ppmc_test_support::postgres::Db::new);
        let Some(db) = db else {
            eprintln!("{doc}: skipped: no PostgreSQL here");
            return Ok(());
        };
        for a in &mut argv {
            *a = a.replace(LAB_STORE, &db.url);
        }
    }
    if argv.first().map(String::as_str) == Some("bridge-sim") {
        // Started, must say where it serves, stopped.
        Bridge::start(dir, "doc-bridge", &argv[1..])?;
        return Ok(());
    }
    // The documented board ports (with a board's options after them): a
    // clean bridge simulator for each.
    for a in &mut argv {
        // ttyACM0 and pts/3 are the one board of the single-board docs.
        for (slot, port) in [
            (0, "serial:/dev/ttyACM0"),
            (0, "serial:/dev/pts/3"),
            (1, "serial:/dev/ttyACM1"),
        ] {
            let Some(options) = a.strip_prefix(port) else {
                continue;
            };
            if !(options.is_empty() || options.starts_with(',')) {
                continue;
            }
            if boards[slot].is_none() {
                boards[slot] = Some(Bridge::start(dir, &format!("board{slot}"), &[])?);
            }
            let link = &boards[slot].as_ref().expect("started").link;
            *a = format!("serial:{}{options}", link.display());
            break;
        }
    }
    let mut child = Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args(&argv)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .stdin(match &stdin {
            Some(f) => Stdio::from(std::fs::File::open(dir.join(f)).map_err(|e| e.to_string())?),
            None => Stdio::null(),
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| e.to_string())?;
    // Read both pipes while waiting, so a long output cannot block it.
    let mut so = child.stdout.take().expect("piped");
    let mut se = child.stderr.take().expect("piped");
    let out_t = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = std::io::Read::read_to_end(&mut so, &mut v);
        v
    });
    let err_t = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = std::io::Read::read_to_end(&mut se, &mut v);
        v
    });
    let status = wait_bounded(&mut child, Duration::from_secs(240));
    let stdout = text(&out_t.join().unwrap_or_default());
    if let Some(file) = &into {
        std::fs::write(dir.join(file), &stdout).map_err(|e| format!("> {file}: {e}"))?;
    }
    let stderr = text(&err_t.join().unwrap_or_default());
    if let Some(want) = &doc.output {
        if stdout != *want {
            return Err(format!("shows\n{want}but prints\n{stdout}{stderr}"));
        }
    }
    // 0, or 1 where a command's point is a verdict: a fuzz run that finds
    // a departure, a run on a bad board. Never bad usage (2), never a panic.
    match status.code() {
        Some(0) => Ok(()),
        Some(1) if EXIT_1.iter().any(|p| doc.command.contains(p)) => Ok(()),
        c => Err(format!(
            "exit status {c:?}\n{}{}",
            tail(&stdout),
            tail(&stderr)
        )),
    }
}

/// Commands whose documented purpose ends in a verdict (exit status 1).
const EXIT_1: [&str; 4] = [
    "fuzz triage fuzz/artifacts/bus_bytes/",
    "judge out/faulty.vcd",
    // docs/reports.md: a board of the catalogue's faults, on purpose.
    "chip-fault=decel-stop-slow,rev=B --html out/faulty.html",
    "chip-fault=accel-first-pout-slow",
];

fn tail(s: &str) -> String {
    let lines: Vec<&str> = s.lines().collect();
    lines[lines.len().saturating_sub(8)..].join("\n") + "\n"
}

/// Runs the commands of one documented file in a scratch checkout of its
/// own: how many ran, and what is wrong with any.
fn check_file(file: &'static str, ci: &str, labgrid: &str) -> (usize, Vec<String>) {
    let mut bad = Vec::new();
    let mut ran = 0;
    let dir = workspace("docs");
    let mut lab = Lab::default();
    for doc in commands(file) {
        if doc.command.contains('<') && !doc.command.contains(" < ") {
            // A template (`crash-<hash>`): the loop it shows runs in
            // cli/tests/it/cli_fuzz.rs with a real finding.
            continue;
        }
        if let Some(args) = ppmc_args(&doc.command) {
            if let Some((_, where_)) = PPMC_ELSEWHERE.iter().find(|(t, _)| args.contains(t)) {
                let shown = doc.command.replacen("ppmc ", "\"$ppmc\" ", 1);
                if where_.contains(LABGRID_SCRIPT) && !labgrid.contains(&shown) {
                    bad.push(format!("{doc}: said to run {where_}, but it does not"));
                }
                continue;
            }
            ran += 1;
            if let Err(e) = run(&doc, &args, dir.path(), &mut lab) {
                bad.push(format!("{doc}: {e}"));
            }
            continue;
        }
        match ELSEWHERE.iter().find(|(p, _)| doc.command.starts_with(p)) {
            Some((_, where_)) if where_.starts_with(&format!("in {LABGRID_SCRIPT}")) => {
                if !labgrid.contains(&doc.command) {
                    bad.push(format!("{doc}: said to run {where_}, but it does not"));
                }
            }
            Some((_, where_)) if where_.starts_with("in .ci/run") => {
                let shown = doc.command.trim_start_matches("cd ");
                // `.ci/run` runs the board team's binary its tests' build
                // made, as `"$board_suite" ARGS`.
                let built = shown.replacen("cargo run -p board-suite -- ", "\"$board_suite\" ", 1);
                let in_ci = ci.contains(shown)
                    || ci.contains(&built)
                    || (doc.command.starts_with("cargo +nightly fuzz run")
                        && ci.contains(
                            "cargo +nightly fuzz run -s none $(./flags \"$target\") \"$target\" \"$scratch\" \"$seeds\"",
                        ))
                    || (doc.command.starts_with("mkdir -p ../target/fuzz-corpus")
                        && ci.contains("scratch=\"$PWD/target/fuzz-corpus/$target\""));
                if !in_ci {
                    bad.push(format!("{doc}: said to run {where_}, but .ci/run does not"));
                }
            }
            Some(_) => {}
            None => bad.push(format!(
                "{doc}: neither a ppmc command nor listed as run elsewhere"
            )),
        }
    }
    (ran, bad)
}

#[test]
fn every_documented_command_runs_as_shown() {
    // `.ci/run` writes `cargo run -q`, and `cargo "${lint[@]}" test` for
    // its builds that lint as they compile; the docs show commands
    // without either.
    let ci = std::fs::read_to_string(root().join(".ci/run"))
        .expect(".ci/run")
        .replace(" -q ", " ")
        .replace(" \"${lint[@]}\" ", " ");
    let labgrid = std::fs::read_to_string(root().join(LABGRID_SCRIPT)).expect("the labgrid script");
    // Each file in a scratch checkout of its own, its commands in order;
    // the files side by side (most of the time is spent waiting on the
    // commands' bridges and links, not computing).
    let next = std::sync::atomic::AtomicUsize::new(0);
    let done = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..3 {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(file) = FILES.get(i) else { return };
                let r = check_file(file, &ci, &labgrid);
                done.lock().expect("results").push((i, r));
            });
        }
    });
    let mut done = done.into_inner().expect("results");
    done.sort_by_key(|(i, _)| *i);
    let ran: usize = done.iter().map(|(_, (n, _))| n).sum();
    let bad: Vec<String> = done.into_iter().flat_map(|(_, (_, b))| b).collect();
    assert!(
        ran >= 40,
        "only {ran} commands found: is the extraction broken?"
    );
    assert!(
        bad.is_empty(),
        "{} documented commands do not hold:\n\n{}",
        bad.len(),
        bad.join("\n\n")
    );
}

/// The extraction itself: comments go, quotes hold, `$ ` blocks keep their
/// output, and a missing-file command is caught (a test that can fail).
#[test]
fn the_extraction_reads_commands_as_a_shell_would() {
    assert_eq!(strip_comment("ppmc run   # the suite"), "ppmc run");
    assert_eq!(
        strip_comment("ppmc console -e 'wc 0x81; rd # not a comment'"),
        "ppmc console -e 'wc 0x81; rd # not a comment'"
    );
    let (w, stdin) = words("ppmc console -e 'wc 0x81; rd' < script.ppmc");
    assert_eq!(w, ["ppmc", "console", "-e", "wc 0x81; rd"]);
    assert_eq!(stdin.as_deref(), Some("script.ppmc"));
    assert_eq!(
        ppmc_args("cargo run --bin ppmc -- list").as_deref(),
        Some("list")
    );
    let console = commands("docs/console.md");
    assert!(console
        .iter()
        .any(|d| d.output.as_deref().is_some_and(|o| o.contains("rd 0x83"))));
    let dir = workspace("docs-neg");
    let doc = Doc {
        file: "test",
        line: 1,
        command: "ppmc export out/nothing.trace -o wave.vcd".into(),
        output: None,
    };
    let e = run(
        &doc,
        "export out/nothing.trace -o wave.vcd",
        dir.path(),
        &mut Lab::default(),
    )
    .expect_err("a file a clean checkout lacks");
    assert!(e.contains("exit status Some(2)"), "{e}");
}

/// `scripts/loaded-check` (docs/performance.md, "On a loaded machine"),
/// with no load and a command that passes and one that fails: a row per
/// run with its exit status, and the script's own status says whether all
/// passed.
#[test]
fn loaded_check_says_how_each_run_ended() {
    let script = root().join("scripts/loaded-check");
    let run = |cmd: &str| {
        Command::new(&script)
            .args(["--runs", "2", "--load", "0", "--", cmd])
            .output()
            .expect("the script runs")
    };
    let ok = run("true");
    assert_eq!(ok.status.code(), Some(0), "{}", text(&ok.stderr));
    let rows = text(&ok.stdout);
    assert!(rows.contains("| 1 | `true` | 0 |"), "{rows}");
    assert!(rows.contains("| 2 | `true` | 0 |"), "{rows}");
    let bad = run("false");
    assert_eq!(bad.status.code(), Some(1), "{}", text(&bad.stderr));
    assert!(text(&bad.stdout).contains("| 1 | `false` | 1 |"));
    let usage = Command::new(&script).output().expect("runs");
    assert_eq!(usage.status.code(), Some(2));
}

/// The fenced blocks of `lang` in `file`, each as its lines.
fn blocks(file: &str, lang: &str) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(root().join(file)).expect("the doc");
    let mut out = Vec::new();
    let mut inside: Option<Vec<String>> = None;
    for line in text.lines() {
        match inside.as_mut() {
            None if line.trim() == format!("```{lang}") => inside = Some(Vec::new()),
            Some(_) if line.trim() == "```" => out.extend(inside.take()),
            Some(b) => b.push(line.to_string()),
            None => {}
        }
    }
    out
}

/// Issue 42: writing-scenarios.md showed no Cargo.toml for a crate of a
/// team's own; the one it shows is the example crate's, its paths moved
/// to a checkout beside it.
#[test]
fn the_external_crates_manifest_is_the_example_crates() {
    let example = std::fs::read_to_string(root().join("examples/board-suite/Cargo.toml"))
        .expect("the example's manifest");
    let expected: Vec<String> = example
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(|l| l.replace("\"../../", "\"../ppmc/"))
        .collect();
    let shown = blocks("docs/writing-scenarios.md", "toml");
    let first: Vec<String> = shown
        .first()
        .expect("a toml block")
        .iter()
        .filter(|l| !l.trim().is_empty())
        .cloned()
        .collect();
    assert_eq!(first, expected);
    // The git form names the same three crates.
    let git = shown.get(1).expect("the git form").join("\n");
    for krate in ["ppmc =", "ppmc-cli =", "ppmc-scenarios ="] {
        assert!(git.contains(krate) && git.contains("rev = "), "{git}");
    }
    assert!(!git.contains("example.invalid"), "{git}");
}

/// Issue 42: an install that ignores Cargo.lock locks every package
/// afresh; every `cargo install --path` the docs show keeps the lock.
#[test]
fn every_install_from_a_path_is_locked() {
    for file in FILES {
        let text = std::fs::read_to_string(root().join(file)).expect("the doc");
        for (n, line) in text.lines().enumerate() {
            for part in line.split("cargo install").skip(1) {
                let command = part.split('`').next().unwrap_or_default();
                if command.contains("--path") {
                    assert!(
                        command.contains("--locked"),
                        "{file}:{}: cargo install{command}: without --locked",
                        n + 1
                    );
                }
            }
        }
    }
}

/// Issue 42: docs/reports.md wrote `report.html` and `results.db` into
/// the repository's root while the README used `out/`. Every file a
/// report command there or in the README writes goes under `out/`.
#[test]
fn the_report_docs_write_into_out() {
    for file in ["README.md", "docs/reports.md"] {
        for block in blocks(file, "sh") {
            for line in block {
                let line = strip_comment(&line);
                if !line.trim_start().starts_with("ppmc ") {
                    continue;
                }
                let words: Vec<&str> = line.split_whitespace().collect();
                for pair in words.windows(2) {
                    if ["--html", "--json", "--junit", "--store", "-o"].contains(&pair[0]) {
                        assert!(
                            pair[1].starts_with("out/") || pair[1] == "-",
                            "{file}: {line}: {} {} is not under out/",
                            pair[0],
                            pair[1]
                        );
                    }
                }
            }
        }
    }
}

/// Issue 42: writing-scenarios.md did not say whose band `expect_latency`
/// grades against; a scenario author must learn it is Table 3-3's, at the
/// board's straps, and that they give none.
#[test]
fn the_scenario_guide_says_expect_latency_grades_against_table_3_3() {
    let text =
        std::fs::read_to_string(root().join("docs/writing-scenarios.md")).expect("the guide");
    let paragraph = text
        .split("\n\n")
        .find(|p| p.starts_with("`expect_latency(TimingId::X)`"))
        .expect("a paragraph on expect_latency");
    for said in ["Table 3-3", "straps", "MARGINAL", "You give no band"] {
        assert!(paragraph.contains(said), "{said}: {paragraph}");
    }
}

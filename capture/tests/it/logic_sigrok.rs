//! Session files (`.sr`) that sigrok-cli itself wrote, read by
//! `ppmc_logic::sigrok` and held against what sigrok-cli prints of the
//! same file: its CSV rows (one per sample, `-O csv`), and its `--show`
//! (sample rate, logic channels, sample count). The captures: the demo
//! device (8 and 12 channels, so unit sizes 1 and 2; its patterns; some
//! channels disabled; analog channels beside), and golden traces exported
//! as VCD and converted by sigrok-cli at several sample rates.
//!
//! Without sigrok-cli the tests say so and pass, except in CI (`CI` set),
//! where `.ci/run` installs it and its absence fails.

use ppmc_test_support as common;

use ppmc_logic::sigrok::SigrokReader;
use ppmc_logic::source::{LogicInfo, LogicSource};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn arg(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}

/// What sigrok-cli prints of a session file: the channel names and every
/// sample (bit `i` = column `i`), from `-O csv`.
fn csv(sr: &Path) -> (Vec<String>, Vec<u64>) {
    let text = common::run_sigrok_cli(&["-i", arg(sr), "-O", "csv:label=channel:header=false"]);
    let mut lines = text.lines();
    let names = lines
        .next()
        .expect("a header row")
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',').enumerate().fold(0u64, |acc, (i, v)| match v {
                "0" => acc,
                "1" => acc | 1 << i,
                other => panic!("{}: CSV value `{other}` in `{l}`", sr.display()),
            })
        })
        .collect();
    (names, rows)
}

/// sigrok-cli's `--show` of a session file: sample rate, enabled logic
/// channels, logic sample count. A disabled channel is listed too, named
/// by libsigrok for its index (`4`); it is left out here.
fn show(sr: &Path) -> (u64, Vec<String>, u64) {
    let text = common::run_sigrok_cli(&["-i", arg(sr), "--show"]);
    let field = |key: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(key))
            .and_then(|v| v.trim().parse::<u64>().ok())
            .unwrap_or_else(|| panic!("no `{key}` in:\n{text}"))
    };
    let logic = text
        .lines()
        .filter_map(|l| l.strip_prefix("- ")?.strip_suffix(": logic"))
        .enumerate()
        .filter(|(i, name)| *name != i.to_string())
        .map(|(_, name)| name.to_string())
        .collect();
    (field("Samplerate:"), logic, field("Logic sample count:"))
}

/// The changes of sampled levels, by definition: sample 0, then each
/// sample unlike the one before.
fn changes_of(rows: &[u64], rate: u64) -> Vec<(u64, u64)> {
    let mut out: Vec<(u64, u64)> = Vec::new();
    for (n, &r) in rows.iter().enumerate() {
        if out.last().is_none_or(|&(_, prev)| prev != r) {
            out.push((LogicInfo::sample_time_ps(n as u64, rate), r));
        }
    }
    out
}

/// Everything the reader gives of a file.
fn read(sr: &Path) -> (LogicInfo, Vec<(u64, u64)>, u64) {
    let mut r = SigrokReader::open(sr).unwrap_or_else(|e| panic!("{e}"));
    let mut out = Vec::new();
    while let Some(c) = r.next_change().unwrap_or_else(|e| panic!("{e}")) {
        out.push((c.time_ps, c.levels));
    }
    (r.info().clone(), out, r.end_ps())
}

/// How many `logic-1-N` chunks a session file has.
fn chunks(sr: &Path) -> usize {
    let file = std::fs::File::open(sr).expect("open");
    let zip = zip::ZipArchive::new(file).expect("a ZIP archive");
    zip.file_names()
        .filter(|n| n.starts_with("logic-1-"))
        .count()
}

/// Holds the reader's view of `sr` against sigrok-cli's; returns the
/// reader's changes.
fn agree(sr: &Path) -> Vec<(u64, u64)> {
    let (info, got, end) = read(sr);
    let (rate, shown, count) = show(sr);
    let (names, rows) = csv(sr);
    let what = sr.display();
    assert_eq!(info.sample_rate_hz, Some(rate), "{what}: sample rate");
    assert_eq!(
        info.channels, shown,
        "{what}: channels, as --show lists them"
    );
    assert_eq!(
        info.channels, names,
        "{what}: channels, as the CSV heads them"
    );
    assert_eq!(rows.len() as u64, count, "{what}: CSV rows against --show");
    assert!(count > 0, "{what}: no samples");
    assert_eq!(
        end,
        LogicInfo::sample_time_ps(count - 1, rate),
        "{what}: end"
    );
    let want = changes_of(&rows, rate);
    if let Some(i) = (0..got.len().max(want.len())).find(|&i| got.get(i) != want.get(i)) {
        panic!(
            "{what}: change {i} of {} is {:?}; sigrok-cli's CSV gives {:?} of {}",
            got.len(),
            got.get(i),
            want.get(i),
            want.len()
        );
    }
    got
}

fn scratch() -> tempfile::TempDir {
    tempfile::tempdir().expect("a temporary folder")
}

#[test]
fn demo_device_captures_read_as_sigrok_cli_prints_them() {
    if !common::sigrok_cli("the sigrok reader") {
        return;
    }
    let dir = scratch();
    let cases: [(&str, &[&str], usize); 4] = [
        // 8 channels, one byte a sample, the default pattern.
        (
            "demo8",
            &[
                "-d",
                "demo:analog_channels=0",
                "-c",
                "samplerate=1MHz",
                "--samples",
                "100000",
            ],
            8,
        ),
        // Every sample new.
        (
            "random8",
            &[
                "-d",
                "demo:analog_channels=0",
                "-g",
                "Logic",
                "-c",
                "pattern=random",
                "--samples",
                "30000",
            ],
            8,
        ),
        // 12 channels: two bytes a sample.
        (
            "demo12",
            &[
                "-d",
                "demo:logic_channels=12:analog_channels=0",
                "-c",
                "samplerate=2MHz",
                "--samples",
                "60000",
            ],
            12,
        ),
        // 12 channels, 4 enabled: the file lists probes 1, 4, 10 and 12.
        (
            "disabled12",
            &[
                "-d",
                "demo:logic_channels=12:analog_channels=0",
                "-C",
                "D0,D3,D9,D11",
                "--samples",
                "20000",
            ],
            4,
        ),
    ];
    for (name, args, channels) in cases {
        let sr = dir.path().join(format!("{name}.sr"));
        let mut all = args.to_vec();
        all.extend(["-o", arg(&sr)]);
        common::run_sigrok_cli(&all);
        assert!(chunks(&sr) > 1, "{name}: one chunk only");
        let got = agree(&sr);
        let info = read(&sr).0;
        assert_eq!(info.channels.len(), channels, "{name}");
        assert!(got.len() > 100, "{name}: {} changes only", got.len());
    }
    let (info, ..) = read(&dir.path().join("disabled12.sr"));
    assert_eq!(info.channels, ["D0", "D3", "D9", "D11"]);
}

#[test]
fn analog_channels_beside_are_left_out() {
    if !common::sigrok_cli("the sigrok reader") {
        return;
    }
    let dir = scratch();
    let both = dir.path().join("both.sr");
    let logic = dir.path().join("logic.sr");
    // The demo's 8 logic and 5 analog channels, then its logic alone: the
    // demo's patterns start alike, so the logic samples are the same.
    common::run_sigrok_cli(&["-d", "demo", "--samples", "20000", "-o", arg(&both)]);
    common::run_sigrok_cli(&[
        "-d",
        "demo:analog_channels=0",
        "--samples",
        "20000",
        "-o",
        arg(&logic),
    ]);
    let (rate, shown, count) = show(&both);
    let (info, got, end) = read(&both);
    assert_eq!(info.sample_rate_hz, Some(rate));
    assert_eq!(info.channels, shown, "the logic channels --show lists");
    assert_eq!(end, LogicInfo::sample_time_ps(count - 1, rate));
    assert_eq!(got, agree(&logic));
}

/// The pulses a trace records: the sum of its `pulses ... n=N` lines.
fn pulses_in(trace: &str) -> u64 {
    trace
        .lines()
        .filter(|l| l.split_whitespace().nth(1) == Some("pulses"))
        .filter_map(|l| l.split_whitespace().find_map(|w| w.strip_prefix("n=")))
        .map(|n| n.parse::<u64>().expect("a pulse count"))
        .sum()
}

/// `golden/<name>.snap` exported as ppmc's VCD (1 ns timescale).
fn vcd_of(dir: &Path, name: &str) -> (PathBuf, u64) {
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../golden");
    let trace = ppmc::golden::load(&golden, name).unwrap_or_else(|e| panic!("{e}"));
    let vcd = dir.join(format!("{name}.vcd"));
    let file = std::fs::File::create(&vcd).expect("create VCD");
    ppmc::vcd_export::export(&trace, std::io::BufWriter::new(file)).expect("export");
    let text = std::fs::read_to_string(golden.join(format!("{name}.snap"))).expect("golden");
    (vcd, pulses_in(&text))
}

#[test]
fn exported_traces_converted_at_several_rates_read_as_sigrok_cli_prints_them() {
    if !common::sigrok_cli("the sigrok reader") {
        return;
    }
    let dir = scratch();
    // sigrok's VCD input samples at 1 GHz / downsample: 1 MHz, 4.1666 MHz
    // (written `4.166666 MHz`), 10 MHz and 41.666666 MHz.
    for (name, downsample) in [
        ("s3_2_2_init_processing_with_pa_4", 1000),
        ("s3_2_2_init_processing_with_pa_4", 24),
        ("e7_second_decel_stop", 240),
        ("e7_second_decel_stop", 100),
    ] {
        let (vcd, pulses) = vcd_of(dir.path(), name);
        let sr = dir.path().join(format!("{name}-{downsample}.sr"));
        let input = format!("vcd:downsample={downsample}");
        common::run_sigrok_cli(&["-I", &input, "-i", arg(&vcd), "-o", arg(&sr)]);
        let got = agree(&sr);
        let info = read(&sr).0;
        assert_eq!(
            info.rate_hz(),
            1_000_000_000 / downsample,
            "{name} at /{downsample}"
        );
        assert!(
            info.channel("pout").is_some(),
            "{name}: {:?}",
            info.channels
        );
        // 100 ns samples or finer keep every 1 us pulse and its gap.
        if downsample <= 100 {
            let pout = info.channel("pout").expect("pout");
            let rising = got
                .windows(2)
                .filter(|w| w[0].1 >> pout & 1 == 0 && w[1].1 >> pout & 1 == 1)
                .count() as u64
                + u64::from(got[0].1 >> pout & 1 == 1);
            assert_eq!(rising, pulses, "{name} at /{downsample}: POUT rising edges");
        }
    }
}

/// How fast the reader goes, on the `.sr` files `PPMC_SR_SPEED` names
/// (a path list): MB of samples a second, best of three. A measurement,
/// not a check: `PPMC_SR_SPEED=big.sr cargo test --release -p ppmc-capture --test it
/// logic_sigrok -- --ignored --nocapture`.
#[test]
#[ignore = "a measurement: run in release with PPMC_SR_SPEED naming .sr files"]
fn read_speed() {
    let Some(files) = std::env::var_os("PPMC_SR_SPEED") else {
        eprintln!("PPMC_SR_SPEED names no .sr files: nothing measured");
        return;
    };
    for path in std::env::split_paths(&files) {
        let mut best = f64::INFINITY;
        let (mut bytes, mut changes) = (0, 0u64);
        for _ in 0..3 {
            let start = Instant::now();
            let mut r = SigrokReader::open(&path).unwrap_or_else(|e| panic!("{e}"));
            changes = 0;
            while r.next_change().unwrap_or_else(|e| panic!("{e}")).is_some() {
                changes += 1;
            }
            best = best.min(start.elapsed().as_secs_f64());
            bytes = r.samples() * r.unitsize() as u64;
        }
        println!(
            "{}: {:.0} MB of samples, {changes} changes, {best:.3} s: {:.0} MB/s",
            path.display(),
            bytes as f64 / 1e6,
            bytes as f64 / 1e6 / best
        );
    }
}

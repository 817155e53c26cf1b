//! An exported VCD, read by the tool people open it with: sigrok-cli
//! (libsigrok's VCD reader, the one PulseView uses). The POUT rising edges
//! sigrok counts must equal the trace's pulse count, and every other wire
//! must load too. Without sigrok-cli the test says so and passes, except in
//! CI (`CI` set), where `.ci/run` installs it and its absence fails.

use crate::common;
use common::{ppmc, scratch, text};
use std::path::Path;
use std::process::Command;

/// The suite's traces checked: pulses both ways, a phase pattern of each
/// motor type, and AUXO.
const TRACES: [&str; 5] = [
    "s3_3_4_accel_1000_steps_cw",
    "s3_3_3_single_step_cw_then_ccw",
    "s3_2_1_five_phase_two_three_excitation",
    "s3_2_1_four_phase_one_two_excitation",
    "s3_5_3_aux_output_drives_auxo",
];

fn sigrok() -> bool {
    common::sigrok_cli("the VCD export")
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

/// Rising edges of `wire` as sigrok's counter decoder counts them.
fn rising_edges(vcd: &Path, wire: &str) -> u64 {
    let out = Command::new("sigrok-cli")
        .arg("-I")
        // 1 ns timescale; 100 ns samples keep every 1 us pulse and its gap.
        .arg("vcd:downsample=100")
        .arg("-i")
        .arg(vcd)
        .arg("-P")
        .arg(format!("counter:data={wire}:data_edge=rising"))
        .arg("-A")
        .arg("counter=edge_count")
        .output()
        .expect("sigrok-cli runs");
    assert!(out.status.success(), "sigrok-cli: {}", text(&out.stderr));
    text(&out.stdout)
        .lines()
        .filter_map(|l| l.rsplit(':').next()?.trim().parse::<u64>().ok())
        .next_back()
        .unwrap_or(0)
}

/// The channels and sample count sigrok-cli reports for a file.
fn shown(vcd: &Path) -> String {
    let out = Command::new("sigrok-cli")
        .args(["-I", "vcd", "-i"])
        .arg(vcd)
        .arg("--show")
        .output()
        .expect("sigrok-cli runs");
    assert!(out.status.success(), "sigrok-cli: {}", text(&out.stderr));
    text(&out.stdout) + &text(&out.stderr)
}

#[cfg_attr(
    ppmc_missing_sigrok_cli,
    ignore = "sigrok-cli is not installed (apt install sigrok-cli)"
)]
#[test]
fn sigrok_counts_every_pulse_of_an_exported_trace() {
    if !sigrok() {
        return;
    }
    let dir = scratch("vcd-sigrok");
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../golden");
    for name in TRACES {
        let src = golden.join(format!("{name}.snap"));
        let vcd = dir.path().join(format!("{name}.vcd"));
        let out = ppmc(&[
            "export",
            src.to_str().expect("utf-8 path"),
            "-o",
            vcd.to_str().expect("utf-8 path"),
        ]);
        assert!(out.status.success(), "{name}: {}", text(&out.stderr));
        let show = shown(&vcd);
        for wire in ["pout", "dir", "s1", "s5", "auxo0", "auxo3"] {
            assert!(show.contains(&format!("- {wire}: logic")), "{name}: {show}");
        }
        let samples: u64 = show
            .lines()
            .find_map(|l| l.strip_prefix("Logic sample count: "))
            .and_then(|n| n.trim().parse().ok())
            .unwrap_or(0);
        assert!(samples > 0, "{name}: sigrok loads no samples:\n{show}");
        let trace = std::fs::read_to_string(&src).expect("golden");
        let want = pulses_in(&trace);
        assert_eq!(
            rising_edges(&vcd, "pout"),
            want,
            "{name}: POUT rising edges"
        );
    }
    // AUXO is four wires sigrok reads: the scenario drives some of them high.
    let auxo = dir.path().join("s3_5_3_aux_output_drives_auxo.vcd");
    let high: u64 = (0..4)
        .map(|k| rising_edges(&auxo, &format!("auxo{k}")))
        .sum();
    assert!(high > 0, "no AUXO edge reached sigrok");
}

/// Issue 30, item 7: the PulseView decoder in `contrib/sigrok/ppmc104`,
/// run by sigrok-cli itself on a capture `ppmc export --scenario --bus`
/// wrote, names every register access of the scenario (Table 3-1), in
/// order and with its byte, as the scenario's trace records them.
#[cfg_attr(
    ppmc_missing_sigrok_cli,
    ignore = "sigrok-cli is not installed (apt install sigrok-cli)"
)]
#[test]
fn the_pulseview_decoder_names_every_register_access() {
    use ppmc::trace::{BusEvent, EventKind};
    if !sigrok() {
        return;
    }
    // A move, its finish status read (data reads), INT* released.
    let name = "s3_4_1_finish_read_releases_int";
    let dir = scratch("pulseview-decoder");
    let vcd = dir.path().join("capture.vcd");
    let out = ppmc(&[
        "export",
        "--scenario",
        name,
        "--bus",
        "-o",
        vcd.to_str().expect("utf-8 path"),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // What the trace says the host did, with the same bus cycles.
    let suite = ppmc_scenarios::all();
    let s = suite.iter().find(|s| s.name == name).expect("scenario");
    let (trace, _) = ppmc_capture::fault_matrix::capture::analyzer_trace(&Default::default(), s)
        .expect("a capture");
    let want: Vec<String> = trace
        .events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::Bus(BusEvent::WriteCommand { byte, .. }) => {
                Some(format!("Write command 0x{byte:02X}"))
            }
            EventKind::Bus(BusEvent::WriteData { byte, .. }) => {
                Some(format!("Write data 0x{byte:02X}"))
            }
            EventKind::Bus(BusEvent::ReadStatus(s)) => Some(format!("Read status 0x{s:02X}")),
            EventKind::Bus(BusEvent::Await { status, .. }) => {
                Some(format!("Read status 0x{status:02X}"))
            }
            EventKind::Bus(BusEvent::ReadData { byte, .. }) => {
                Some(format!("Read data 0x{byte:02X}"))
            }
            _ => None,
        })
        .collect();
    assert!(want.len() > 10, "{want:?}");
    let channels: Vec<String> = ["cs", "rd", "wr", "a0"]
        .into_iter()
        .map(String::from)
        .chain((0..8).map(|i| format!("d{i}")))
        .map(|c| format!("{c}={c}"))
        .collect();
    let decoders = Path::new(env!("CARGO_MANIFEST_DIR")).join("../contrib/sigrok");
    let out = Command::new("sigrok-cli")
        .env("SIGROKDECODE_DIR", &decoders)
        // 1 ns timescale; 10 ns samples: each 100 ns strobe is ten.
        .args(["-I", "vcd:downsample=10", "-i"])
        .arg(&vcd)
        .args(["-P", &format!("ppmc104:{}", channels.join(":"))])
        .args(["-A", "ppmc104=accesses"])
        .output()
        .expect("sigrok-cli runs");
    assert!(out.status.success(), "{}", text(&out.stderr));
    let got: Vec<String> = text(&out.stdout)
        .lines()
        .filter_map(|l| l.strip_prefix("ppmc104-1: "))
        .map(str::to_string)
        .collect();
    assert_eq!(got, want, "sigrok-cli with contrib/sigrok/ppmc104");
}

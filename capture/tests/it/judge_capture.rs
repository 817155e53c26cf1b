//! Judging a board from a capture of its bus and pins (issue 30): the
//! suite's scenarios, run on the emulator, exported with the bus as a
//! logic analyzer would record them (`ppmc export --bus`), and judged
//! against the reference model. A clean board passes; a faulty one
//! (`ppmc::faults`) fails, blamed on the board, at its first divergence.

use ppmc::emu::ModelConfig;
use ppmc::trace::Trace;
use ppmc::vcd_export::{export_with, Export};
use ppmc_capture::fault_matrix::capture::analyzer_trace;
use ppmc_capture::judge::{judge, CaptureVerdict, JudgeOptions};
use ppmc_logic::map::ChannelMap;
use ppmc_logic::source::LogicSource;
use ppmc_logic::vcd::VcdReader;
use std::path::Path;

/// The trace of `name` on a model with `cfg`.
fn trace_of(name: &str, cfg: ModelConfig) -> Trace {
    let suite = ppmc_scenarios::all();
    let s = suite.iter().find(|s| s.name == name).expect("scenario");
    // A host on a real bus: every access takes a bus cycle.
    analyzer_trace(&cfg, s).expect("a capture").0
}

/// The capture of `trace` as a logic analyzer would record it, read by
/// the project's VCD reader.
fn capture_of(trace: &Trace) -> VcdReader<std::io::Cursor<Vec<u8>>> {
    let mut buf = Vec::new();
    export_with(
        trace,
        Export {
            window: None,
            bus: true,
        },
        &mut buf,
    )
    .expect("export");
    VcdReader::new(std::io::Cursor::new(buf), Path::new("capture.vcd")).expect("reads")
}

fn judged(trace: &Trace) -> ppmc_capture::judge::Judgement {
    let mut cap = capture_of(trace);
    let map = ChannelMap::from_names(cap.info()).expect("our names");
    judge(&mut cap, &map, &JudgeOptions::default()).expect("judged")
}

/// Sections 3-3 (moves), 3-4 (register reads), 3-2 (initialization): a
/// clean board's captures pass, every pulse compared. The host of
/// `e4_accel_pulses_11221` misuses the chip on purpose: its findings are
/// the host firmware's (3-2-2, then 3-2), not the board's.
#[test]
fn a_clean_boards_captures_pass() {
    for (name, host) in [
        ("s3_3_5_constant_speed_100_steps", &[][..]),
        ("s3_3_1_immediate_stop_of_accel_move", &[]),
        ("e4_accel_pulses_11221", &["3-2-2", "3-2"]),
    ] {
        let trace = trace_of(name, ModelConfig::default());
        let pulses: u64 = trace
            .events
            .iter()
            .filter_map(|e| match e.kind {
                ppmc::trace::EventKind::Pulses { count, .. } => Some(u64::from(count)),
                _ => None,
            })
            .sum();
        let j = judged(&trace);
        assert_eq!(j.verdict, CaptureVerdict::Passed, "{name}: {j:?}");
        assert!(j.accesses > 5, "{name}: {j:?}");
        assert_eq!(j.pulses, pulses, "{name}");
        let sections: Vec<&str> = j.host.iter().map(|h| h.section).collect();
        assert_eq!(sections, host, "{name}: {:?}", j.host);
    }
}

/// A board that loses the last pulse of a move (3-3), whose status reads
/// a stuck bit (3-1-1), whose INT* comes late or whose BUSY rises early
/// (Table 3-3), whose HOLD never turns on (3-2-1) or whose AUXO pins are
/// reversed (3-5-3) fails, blamed on the board, at its first divergence.
#[test]
fn a_faulty_boards_capture_fails_at_its_first_divergence() {
    for (fault, scenario, what) in [
        (
            "drop-last-pulse",
            "s3_3_5_constant_speed_100_steps",
            "POUT pulse",
        ),
        (
            "status-stuck-0x04",
            "s3_3_5_constant_speed_100_steps",
            "status read",
        ),
        // Table 3-3: INT* 8% late after the final POUT.
        (
            "int-late",
            "s3_3_5_constant_speed_100_steps",
            "INT asserted",
        ),
        // 3-2-1: HOLD never turns on.
        (
            "hold-stuck-off",
            "s3_3_5_constant_speed_100_steps",
            "HOLD high",
        ),
        // 3-5-3: AUXO0..3 in reverse order.
        ("auxo-reversed", "s3_5_3_aux_output_drives_auxo", "AUXO"),
        // Table 3-3: BUSY rises early, which the host's status poll sees.
        (
            "busy-rise-early",
            "s3_3_5_constant_speed_100_steps",
            "status read",
        ),
    ] {
        let mut cfg = ModelConfig::default();
        ppmc::faults::apply_all(&[fault.to_string()], &mut cfg).expect("fault");
        let trace = trace_of(scenario, cfg);
        let j = judged(&trace);
        match &j.verdict {
            CaptureVerdict::Failed(d) => assert!(d.what.starts_with(what), "{fault}: {d}"),
            other => panic!("{fault}: {other:?}"),
        }
    }
}

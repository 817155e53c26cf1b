//! Issue 40: a capture's own uncertainty is never the board's failure.
//! A host that writes each byte the instant the chip allows it (`ppmc
//! export --host exact`) recorded by an analyzer that samples at 23.8 MHz:
//! each edge is seen on the sample grid, so a write whose strobe ended as
//! IBF fell may be seen up to a sample before it. The capture cannot say
//! on which side of IBF's fall the chip took the byte (3-1-1: a byte
//! written while IBF is 1 replaces the one waiting), and the judge must
//! not pick the side that fails the board.

use ppmc::emu::ModelConfig;
use ppmc::vcd_export::{export_with, Export};
use ppmc_capture::fault_matrix::capture::analyzer_trace_with;
use ppmc_capture::judge::{judge, CaptureVerdict, JudgeOptions};
use ppmc_core::bus::HostTiming;
use ppmc_logic::map::ChannelMap;
use ppmc_logic::source::{Change, LogicInfo, LogicSource, Recorded};
use ppmc_logic::vcd::VcdReader;
use std::path::Path;

/// Scenario `name` recorded with a host timed as `host` says, as a 1 ns
/// VCD, then as an analyzer sampling every `period_ps` sees it: each
/// change at the last sample at or before it (as sigrok-cli's VCD input
/// downsamples), two changes in one sample merged.
fn sampled(name: &str, host: HostTiming, period_ps: u64) -> Recorded {
    let suite = ppmc_scenarios::all();
    let s = suite.iter().find(|s| s.name == name).expect("scenario");
    let (trace, _) = analyzer_trace_with(&ModelConfig::default(), s, host).expect("a capture");
    let mut vcd = Vec::new();
    let export = Export {
        window: None,
        bus: true,
    };
    export_with(&trace, export, &mut vcd).expect("export");
    let mut r = VcdReader::new(&vcd[..], Path::new(name)).expect("our VCD");
    let mut out: Vec<Change> = Vec::new();
    while let Some(c) = r.next_change().expect("reads") {
        let at = c.time_ps / period_ps * period_ps;
        match out.last_mut() {
            Some(last) if last.time_ps == at => *last = Change { time_ps: at, ..c },
            _ => out.push(Change { time_ps: at, ..c }),
        }
    }
    out.dedup_by(|b, a| a.levels == b.levels && a.unknown == b.unknown);
    let info = LogicInfo {
        resolution_ps: period_ps,
        sample_rate_hz: Some(1_000_000_000_000 / period_ps),
        format: "sampled".into(),
        ..r.info().clone()
    };
    Recorded::new(info, out, r.end_ps() / period_ps * period_ps)
}

fn judged(mut cap: Recorded, opts: &JudgeOptions) -> ppmc_capture::judge::Judgement {
    let map = ChannelMap::from_names(cap.info()).expect("the chip's names");
    judge(&mut cap, &map, opts).expect("judged")
}

/// 3-1-1 with Table 3-3's IBF times: the exact host's captures at 23.8
/// MHz (42 ns a sample) pass the board with no host finding; taken at
/// their captured times alone (the judge before issue 40), the same
/// captures fail the board or blame the host, which proves the sampling
/// moved writes across IBF's fall in them.
#[test]
fn s3_1_1_a_write_sampled_across_ibfs_fall_fails_neither_board_nor_host() {
    let mut across = 0;
    for name in [
        "s3_3_4_accel_1000_steps_cw",
        "s3_3_5_constant_speed_100_steps",
        "s3_4_1_finish_read_releases_int",
        "s3_2_1_four_phase_two_phase_excitation",
        // A status read that ends as IBF falls, then OBF rises within the
        // latency window: the read may show any status in that window.
        "s3_2_2_init_processing_with_pa_4",
    ] {
        let j = judged(
            sampled(name, HostTiming::Exact, 42_000),
            &JudgeOptions::default(),
        );
        assert_eq!(j.verdict, CaptureVerdict::Passed, "{name}: {j:?}");
        assert!(j.host.is_empty(), "{name}: {:?}", j.host);
        let single = JudgeOptions {
            follow_orders: false,
            ..JudgeOptions::default()
        };
        let j = judged(sampled(name, HostTiming::Exact, 42_000), &single);
        if j.verdict != CaptureVerdict::Passed || !j.host.is_empty() {
            across += 1;
        }
    }
    assert!(
        across >= 2,
        "the sampling moved writes across IBF's fall in {across} captures only"
    );
}

/// The polling host's captures never needed the second order: they pass
/// either way (the forks are only where the capture cannot order).
#[test]
fn a_polling_hosts_captures_pass_with_one_order_too() {
    let single = JudgeOptions {
        follow_orders: false,
        ..JudgeOptions::default()
    };
    let j = judged(
        sampled("s3_3_4_accel_1000_steps_cw", HostTiming::Polling, 42_000),
        &single,
    );
    assert_eq!(j.verdict, CaptureVerdict::Passed, "{j:?}");
    assert!(j.host.is_empty(), "{:?}", j.host);
}

/// Sections 3-5-1 and 3-1-1: the exact host writes the move's command as
/// IBF falls; sampled at 23.8 MHz, the chopping that the move ends passes
/// the board, every edge compared. (sigrok-cli's own conversion of the
/// same capture, where the board's move starts before the model's, is in
/// `cli/tests/it/suite_captures.rs`.)
#[test]
fn s3_5_1_chopping_ended_by_a_move_the_capture_cannot_order_passes() {
    let j = judged(
        sampled(
            "s3_5_1_default_switching_chops_the_phases",
            HostTiming::Exact,
            42_000,
        ),
        &JudgeOptions::default(),
    );
    assert!(matches!(j.verdict, CaptureVerdict::Passed), "{j:?}");
    assert!(j.changes > 1000, "the chopping compared: {}", j.changes);
}

//! The RP2350 bridge's board code on the board twin: `firmware/run-twin`
//! runs `ppmc_bridge_fw::board` (the image's board code) on a model of the
//! RP2350's PIO blocks and GPIOs wired pin by pin to the reference chip
//! model, behind the image's `BridgeEngine`, on a pseudo-terminal
//! (firmware/README.md). These tests go through it as a host goes
//! through a board.
//!
//! The whole suite (`--skip-tag long`) passes through it with the
//! emulator's verdicts: the scenarios in [`SLOW`] in a test of their own,
//! with a host patient enough for the twin's pace.

mod common;

use common::served::{only_error_3_fails, Served};
use ppmc::backend::EmuTarget;
use ppmc::runner::run_suite;
use ppmc::scenario::{DriverOptions, Verdict};
use ppmc_core::emu::ModelConfig;
use ppmc_core::protocol::Straps;

/// Scenarios the twin takes far longer over than a board, and why: each
/// runs in [`slow_scenarios_pass_through_the_twin_given_a_patient_host`].
const SLOW: [(&str, &str); 1] = [(
    "s3_3_4_longest_triangle_first_pout",
    "1.3 s of a move with the board code polling status, simulated cycle \
     by cycle: the twin answers after about a minute, later than a host \
     waits for a board (`--link-timeout 600s --link-retries 40` waits)",
)];

#[test]
fn the_suite_passes_through_the_board_code_on_the_twin_with_the_emulators_verdicts() {
    let twin = Served::start("run-twin", &[]);
    let mut t = twin.target();
    let hello = t.hello().clone();
    assert!(
        hello.firmware.starts_with("ppmc-bridge-twin "),
        "{}",
        hello.firmware
    );
    assert_eq!(hello.timer_hz, 75_000_000, "the PIO counters' timebase");
    let chosen: Vec<_> = ppmc_scenarios::all()
        .into_iter()
        .filter(|s| !s.has_tag("long") && !SLOW.iter().any(|(n, _)| *n == s.name))
        .collect();
    assert!(chosen.len() > 80, "{}", chosen.len());
    let mut emu = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    let want = run_suite(&mut emu, &chosen, 1, DriverOptions::default(), |_| {});
    let got = run_suite(&mut t, &chosen, 1, DriverOptions::default(), |_| {});
    let differ: Vec<String> = want
        .iter()
        .zip(&got)
        .filter(|(w, g)| w.verdict != g.verdict)
        .map(|(w, g)| format!("{}: emulator {:?}, twin {:?}", w.name, w.verdict, g.verdict))
        .collect();
    assert!(differ.is_empty(), "{}", differ.join("\n"));
    assert!(got.iter().all(|r| r.verdict == Verdict::Passed));
    drop(t);
    let link = twin.link.clone();
    drop(twin);
    assert!(!link.exists(), "run-twin removes its link when stopped");
}

#[test]
fn slow_scenarios_pass_through_the_twin_given_a_patient_host() {
    let twin = Served::start("run-twin", &[]);
    let mut t = twin.target_with(ppmc::backend::SerialOptions {
        reply_timeout: std::time::Duration::from_secs(600),
        retries: 40,
        ..ppmc::backend::SerialOptions::default()
    });
    let chosen: Vec<_> = ppmc_scenarios::all()
        .into_iter()
        .filter(|s| SLOW.iter().any(|(n, _)| *n == s.name))
        .collect();
    assert_eq!(
        chosen.len(),
        SLOW.len(),
        "every slow scenario is in the suite"
    );
    let mut emu = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    let want = run_suite(&mut emu, &chosen, 1, DriverOptions::default(), |_| {});
    let got = run_suite(&mut t, &chosen, 1, DriverOptions::default(), |_| {});
    for (w, g) in want.iter().zip(&got) {
        assert_eq!(w.verdict, g.verdict, "{}: {:?}", w.name, g);
        assert_eq!(g.verdict, Verdict::Passed, "{}", g.name);
    }
}

#[test]
fn a_chip_fault_behind_the_twin_is_caught() {
    let twin = Served::start(
        "run-twin",
        &["--chip-fault", "swap-error-3-4", "--clock-mhz", "12"],
    );
    let mut t = twin.target();
    assert_eq!(t.hello().straps.sysclk_hz, 12_000_000);
    only_error_3_fails(&mut t);
}

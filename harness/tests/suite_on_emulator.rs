//! The whole conformance suite passes on the reference emulator.

use ppmc::backend::EmuTarget;
use ppmc::emu::ModelConfig;
use ppmc::protocol::Straps;
use ppmc::runner::{run_suite, validate_suite};
use ppmc::scenario::DriverOptions;

#[test]
fn every_scenario_passes_on_the_emulator() {
    let all = ppmc_scenarios::all();
    validate_suite(&all).expect("valid suite");
    let mut t = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    let results = run_suite(&mut t, &all, 1, DriverOptions::default(), |_| {});
    let bad: Vec<String> = results
        .iter()
        .filter(|r| r.verdict != ppmc::scenario::Verdict::Passed)
        .map(|r| {
            format!(
                "{}: {} {}",
                r.name,
                r.verdict.label(),
                r.verdict.detail().unwrap_or_default()
            )
        })
        .collect();
    assert!(
        bad.is_empty(),
        "{} of {} not passed:\n{}",
        bad.len(),
        results.len(),
        bad.join("\n")
    );
}

#[test]
fn suite_has_the_scenario_files() {
    let all = ppmc_scenarios::all();
    let sections: std::collections::BTreeSet<&str> = all.iter().map(|s| s.section).collect();
    eprintln!("{} scenarios over {} sections", all.len(), sections.len());
    assert!(all.iter().any(|s| s.name == "e0_undefined_command_code"));
    assert!(all
        .iter()
        .any(|s| s.name == "s3_2_2_over_speed_locks_out_the_host"));
}

/// The scenarios take their rates and waits from the board's straps, so
/// the suite passes on boards strapped differently from the reference.
#[rstest::rstest]
#[case::csel_low(Straps { csel_high: false, ..Straps::default() })]
#[case::vsel_low(Straps { vsel_high: false, ..Straps::default() })]
#[case::sysclk_20mhz(Straps { sysclk_hz: 20_000_000, ..Straps::default() })]
#[case::sysclk_12_288mhz_csel_low_vsel_low(Straps { sysclk_hz: 12_288_000, csel_high: false, vsel_high: false, ext_clock_hz: None })]
#[case::external_clock_fitted(Straps { ext_clock_hz: Some(500_000), ..Straps::default() })]
fn every_scenario_passes_with_other_straps(#[case] straps: Straps) {
    let all = ppmc_scenarios::all();
    let mut t = EmuTarget::new(straps, ModelConfig::default()).expect("emulator");
    let results = run_suite(&mut t, &all, 1, DriverOptions::default(), |_| {});
    let bad: Vec<String> = results
        .iter()
        .filter(|r| !r.verdict.ok())
        .map(|r| format!("{}: {}", r.name, r.verdict.detail().unwrap_or_default()))
        .collect();
    assert!(bad.is_empty(), "{straps:?}:\n{}", bad.join("\n"));
}

/// Section 3-3-3 single steps, checked with pulse expectations that are
/// queued behind later moves: each is judged on the capture as it stood
/// where the scenario asked, not as it stands when the batch comes back.
fn steps_then_expect(d: &mut ppmc::scenario::Driver, first_cw: u64) -> ppmc::scenario::Outcome {
    use ppmc::scenario::prelude::*;
    d.init_and_wait(Init::four_phase())?;
    d.run(Move::single_step(Cw))?;
    d.expect_pulses(first_cw, Cw)?;
    // The next move's final byte is written the instant the first one ends.
    d.run(Move::single_step(Ccw))?;
    d.expect_pulses(1, Ccw)
}

#[test]
fn s3_3_3_deferred_pulse_expectations_see_the_capture_where_they_were_asked() {
    use ppmc::scenario::{run_scenario, Scenario, Verdict};
    let mut t = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    let pass = Scenario::new("pass", "3-3-3", "", &[], |d| steps_then_expect(d, 1));
    let r = run_scenario(&mut t, &pass, DriverOptions::default());
    assert_eq!(r.verdict, Verdict::Passed, "{:?}", r.verdict);
    // Asking for two: the failure names the first move's count, not the
    // second move's (which has run by the time the batch is judged).
    let fail = Scenario::new("fail", "3-3-3", "", &[], |d| steps_then_expect(d, 2));
    let r = run_scenario(&mut t, &fail, DriverOptions::default());
    let Verdict::Failed(f) = &r.verdict else {
        panic!("{:?}", r.verdict);
    };
    assert_eq!(
        (f.expectation.as_str(), f.got.as_str()),
        ("pulses cw", "1 (1 cw, 0 ccw)")
    );
}

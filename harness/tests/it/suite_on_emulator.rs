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

/// The scenarios take their rates, waits and timeouts from the board's
/// straps, so the suite passes on every board the straps allow (Section
/// 3-2-1's system clock of 1 to 40 MHz, fractional too; CSEL and VSEL
/// either way; no external clock, or one at 1 kHz or at its SysClk/16
/// maximum): the whole matrix, 160 suites.
#[test]
fn every_scenario_passes_at_every_strapping_the_cli_accepts() {
    let all = ppmc_scenarios::all();
    let clocks = [
        1_000_000, 1_843_200, 3_686_400, 7_372_800, 10_000_000, 12_288_000, 16_000_000, 24_000_000,
        33_333_333, 40_000_000,
    ];
    let mut bad = Vec::new();
    for sysclk_hz in clocks {
        for csel_high in [true, false] {
            for vsel_high in [true, false] {
                for ext_clock_hz in [None, Some(1_000), Some(sysclk_hz / 16)] {
                    // The slowest external clock once per system clock.
                    if ext_clock_hz == Some(1_000) && !(csel_high && vsel_high) {
                        continue;
                    }
                    let straps = Straps {
                        sysclk_hz,
                        csel_high,
                        vsel_high,
                        ext_clock_hz,
                    };
                    let mut t = EmuTarget::new(straps, ModelConfig::default()).expect("emulator");
                    let results = run_suite(&mut t, &all, 1, DriverOptions::default(), |_| {});
                    bad.extend(results.iter().filter(|r| !r.verdict.ok()).map(|r| {
                        format!(
                            "{straps}: {}: {}",
                            r.name,
                            r.verdict.detail().unwrap_or_default()
                        )
                    }));
                }
            }
        }
    }
    assert!(
        bad.is_empty(),
        "{} results not passed:\n{}",
        bad.len(),
        bad.join("\n")
    );
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

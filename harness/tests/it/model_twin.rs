//! The emulator checked against the plain model (`ppmc::plain_model`),
//! a second model written from the datasheet alone: every conformance
//! scenario's bus traffic and every committed bus-byte fuzz input, replayed
//! on both, must give the same reads, pins, pulses and pin changes.

use ppmc_test_support as common;

use ppmc::bus_program;
use ppmc::emu::ModelConfig;
use ppmc::plain_model::twin;
use ppmc::protocol::Straps;
use std::fs;
use std::path::Path;

fn agree_at(straps: Straps, cfg: &ModelConfig) -> usize {
    let mut failures = Vec::new();
    let mut compared = 0;
    let inputs = common::fuzz_inputs("bus_bytes")
        .into_iter()
        .chain(common::fuzz_inputs("model_twin"));
    for (path, data) in inputs {
        let ops = bus_program::decode(&data);
        match twin::check(&ops, straps, cfg) {
            Ok(a) => compared += a.pulses,
            Err(d) => failures.push(format!("{}: {d}", path.display())),
        }
    }
    assert!(
        failures.is_empty(),
        "at {straps}, {} disagree:\n{}",
        failures.len(),
        failures.join("\n")
    );
    compared
}

/// Every scenario of the suite (the bus_bytes seeds are its traffic) and
/// every regression input, whole, at the reference straps: both models
/// agree on every read, pin, pulse and pin change (all of chapter 3).
#[test]
fn the_suite_and_the_regressions_agree_on_both_models() {
    let pulses = agree_at(Straps::default(), &ModelConfig::default());
    assert!(pulses > 10_000, "pulses compared: {pulses}");
}

/// The same traffic on boards strapped otherwise (3-2-1, 3-2-2: CSEL low,
/// VSEL low's 7.5 us term, an external clock whose period is not a whole
/// number of nanoseconds, a 40 MHz system clock), and with the
/// linear-rate ramp (notes N16): the clock arithmetic and the ramp agree
/// too. (The suite's traffic is timed for 16 MHz or faster: on a slower
/// firmware its back-to-back writes overwrite each other.)
#[test]
fn the_models_agree_at_other_straps_and_curves() {
    let boards = [
        Straps {
            csel_high: false,
            vsel_high: false,
            ..Straps::default()
        },
        Straps {
            ext_clock_hz: Some(115_200),
            ..Straps::default()
        },
        Straps {
            sysclk_hz: 40_000_000,
            vsel_high: false,
            ..Straps::default()
        },
    ];
    for straps in boards {
        let pulses = agree_at(straps, &ModelConfig::default());
        assert!(pulses > 1_000, "at {straps}: pulses compared: {pulses}");
    }
    let linear_rate = ModelConfig {
        accel_curve: ppmc::emu::AccelCurve::LinearRate,
        ..ModelConfig::default()
    };
    agree_at(Straps::default(), &linear_rate);
}

/// The check can fail, and says where: an emulator whose BUSY rises 1 us
/// late (Table 3-3's busy delay), or that asserts INT* on a masked move
/// (3-3, the `int-ignores-mask` fault), disagrees with the plain model
/// on a 1,000-step move.
#[test]
fn an_emulator_off_by_one_microsecond_or_one_bit_disagrees() {
    let data = fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../fuzz/corpus/bus_bytes/s3_3_4_accel_ccw_masked_interrupt.bin"),
    )
    .expect("seed");
    let ops = bus_program::decode(&data);
    let clean = ModelConfig::default();
    assert!(twin::check_against(&ops, Straps::default(), &clean, &clean).is_ok());
    let late = ModelConfig {
        busy_rise: clean.busy_rise + ppmc::time::Duration::from_micros(1),
        ..clean.clone()
    };
    let d = twin::check_against(&ops, Straps::default(), &late, &clean).expect_err("late BUSY");
    assert!(d.detail.contains("busy = 1"), "{d}");
    let mut unmasked = clean.clone();
    ppmc::faults::apply_all(&["int-ignores-mask".to_string()], &mut unmasked).expect("fault");
    let d = twin::check_against(&ops, Straps::default(), &unmasked, &clean).expect_err("INT*");
    assert!(d.to_string().contains("int"), "{d}");
}

//! Mutation check: a changed emulator fails the scenarios that cover the
//! change, with a message naming what diverged. Every scenario must be
//! failed by at least one mutant (so no scenario is unable to fail), and
//! every mutant must be caught.

use ppmc::backend::EmuTarget;
use ppmc::compare::Tolerances;
use ppmc::emu::{ModelConfig, ModelFaults, WiringFaults};
use ppmc::protocol::{ErrorCode, Straps};
use ppmc::runner::run_suite;
use ppmc::scenario::{DriverOptions, ScenarioResult, Verdict};
use ppmc::time::Duration;
use std::collections::BTreeMap;
use std::path::Path;

type Mutate = fn(&mut ModelConfig, bool);

/// Scales a latency by +5 % (`up`) or -5 %.
fn five_percent(d: &mut Duration, up: bool) {
    *d = if up {
        d.scale(105, 100)
    } else {
        d.scale(95, 100)
    };
}

/// Every model latency, by name.
const LATENCIES: &[(&str, Mutate)] = &[
    ("byte_pickup", |c, u| five_percent(&mut c.byte_pickup, u)),
    ("obf_ready", |c, u| five_percent(&mut c.obf_ready, u)),
    ("obf_next", |c, u| five_percent(&mut c.obf_next, u)),
    ("busy_rise", |c, u| five_percent(&mut c.busy_rise, u)),
    ("init_outputs", |c, u| five_percent(&mut c.init_outputs, u)),
    ("init_time_min", |c, u| {
        five_percent(&mut c.init_time_min, u)
    }),
    ("init_time_max", |c, u| {
        five_percent(&mut c.init_time_max, u)
    }),
    ("accel_first_pout", |c, u| {
        five_percent(&mut c.accel_first_pout, u)
    }),
    ("accel_first_pout_triangle_max", |c, u| {
        five_percent(&mut c.accel_first_pout_triangle_max, u)
    }),
    ("constant_first_pout", |c, u| {
        five_percent(&mut c.constant_first_pout, u)
    }),
    ("single_step_pout", |c, u| {
        five_percent(&mut c.single_step_pout, u)
    }),
    ("single_step_done", |c, u| {
        five_percent(&mut c.single_step_done, u)
    }),
    ("decel_stop", |c, u| five_percent(&mut c.decel_stop, u)),
    ("hs_limit_accel", |c, u| {
        five_percent(&mut c.hs_limit_accel, u)
    }),
    ("hs_limit_cruise", |c, u| {
        five_percent(&mut c.hs_limit_cruise, u)
    }),
    ("remaining_calc", |c, u| {
        five_percent(&mut c.remaining_calc, u)
    }),
    ("interrupt_delay", |c, u| {
        five_percent(&mut c.interrupt_delay, u)
    }),
    ("next_command", |c, u| five_percent(&mut c.next_command, u)),
    ("hold_on", |c, u| five_percent(&mut c.hold_on, u)),
    ("aux_switch", |c, u| five_percent(&mut c.aux_switch, u)),
    ("aux_output", |c, u| five_percent(&mut c.aux_output, u)),
    ("excitation_off", |c, u| {
        five_percent(&mut c.excitation_off, u)
    }),
    ("switching_on", |c, u| five_percent(&mut c.switching_on, u)),
    ("switching_off", |c, u| {
        five_percent(&mut c.switching_off, u)
    }),
];

fn mutants() -> Vec<(String, ModelConfig)> {
    let mut v = Vec::new();
    for (name, f) in LATENCIES {
        for up in [true, false] {
            let mut c = ModelConfig::default();
            f(&mut c, up);
            if c.validate().is_ok() {
                v.push((format!("{name} {}5%", if up { "+" } else { "-" }), c));
            }
        }
    }
    v.push((
        "last pulse dropped".into(),
        ModelConfig {
            faults: ModelFaults {
                drop_last_pulse: true,
                ..ModelFaults::default()
            },
            ..ModelConfig::default()
        },
    ));
    v.push((
        "status bit 3 stuck high".into(),
        ModelConfig {
            board: WiringFaults {
                status_stuck_high: 0x08,
                ..WiringFaults::default()
            },
            ..ModelConfig::default()
        },
    ));
    for e in ErrorCode::ALL {
        let other = ErrorCode::from_number((e.number() + 1) % 8);
        v.push((
            format!("error {} reported as {}", e.number(), other.number()),
            ModelConfig {
                board: WiringFaults {
                    swap_error: Some((e, other)),
                    ..WiringFaults::default()
                },
                ..ModelConfig::default()
            },
        ));
    }
    v
}

/// Runs the suite on a mutant with the golden comparison the CLI applies.
fn run_mutant(cfg: ModelConfig) -> Vec<ScenarioResult> {
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../golden");
    let mut t = EmuTarget::new(Straps::default(), cfg).expect("valid mutant");
    let all = ppmc_scenarios::all();
    run_suite(&mut t, &all, 1, DriverOptions::default(), |r| {
        ppmc::golden::check(r, &golden, &Tolerances::default());
    })
}

fn failures(results: &[ScenarioResult]) -> BTreeMap<&'static str, String> {
    results
        .iter()
        .filter(|r| !r.verdict.ok())
        .map(|r| (r.name, r.verdict.detail().unwrap_or_default()))
        .collect()
}

#[test]
fn every_mutant_is_caught_and_every_scenario_catches_one() {
    let all: Vec<&str> = ppmc_scenarios::all().iter().map(|s| s.name).collect();
    let mut killed_by: BTreeMap<&str, Vec<String>> = BTreeMap::new();
    let mut survivors = Vec::new();
    for (name, cfg) in mutants() {
        let f = failures(&run_mutant(cfg));
        if f.is_empty() {
            survivors.push(name.clone());
        }
        for s in f.keys() {
            killed_by.entry(s).or_default().push(name.clone());
        }
    }
    let never_failing: Vec<&&str> = all
        .iter()
        .filter(|s| !killed_by.contains_key(**s))
        .collect();
    assert!(
        survivors.is_empty(),
        "mutants no scenario caught: {survivors:?}"
    );
    assert!(
        never_failing.is_empty(),
        "scenarios no mutant made fail: {never_failing:?}"
    );
}

fn failure_of(results: &[ScenarioResult], name: &str) -> String {
    let r = results
        .iter()
        .find(|r| r.name == name)
        .expect("scenario exists");
    match &r.verdict {
        Verdict::Failed(f) => f.to_string(),
        other => panic!("{name} should fail, got {other:?}"),
    }
}

/// The three kinds of change issue 3 names, each failing the scenario that
/// covers it with a message that says what diverged, expected vs got, when.
#[test]
fn latency_five_percent_off_fails_its_scenario_with_the_divergence() {
    let mut cfg = ModelConfig::default();
    five_percent(&mut cfg.constant_first_pout, true);
    let msg = failure_of(&run_mutant(cfg), "s3_3_5_constant_speed_100_steps");
    assert!(msg.contains("constant_first_pout (Table 3-3)"), "{msg}");
    assert!(
        msg.contains("expected 192.060us to 195.940us, got 203.700us"),
        "{msg}"
    );
    assert!(msg.starts_with("at "), "{msg}");
}

#[test]
fn a_dropped_pulse_fails_with_the_pulse_count() {
    let cfg = ModelConfig {
        faults: ModelFaults {
            drop_last_pulse: true,
            ..ModelFaults::default()
        },
        ..ModelConfig::default()
    };
    let results = run_mutant(cfg);
    let msg = failure_of(&results, "s3_3_5_constant_speed_100_steps");
    assert!(msg.contains("pulses cw: expected 100, got 99"), "{msg}");
    // Where the count is checked later, an earlier check already diverges:
    // the final POUT seen is a period early, so a Table 3-3 time is off.
    let msg = failure_of(&results, "s3_3_4_accel_1000_steps_cw");
    assert!(msg.contains("next_command (Table 3-3)"), "{msg}");
}

#[test]
fn a_different_error_code_fails_with_expected_and_got() {
    let cfg = ModelConfig {
        board: WiringFaults {
            swap_error: Some((ErrorCode::TooManyParameters, ErrorCode::AccelPulsesTooMany)),
            ..WiringFaults::default()
        },
        ..ModelConfig::default()
    };
    let msg = failure_of(&run_mutant(cfg), "e3_data_without_a_command");
    assert!(
        msg.contains("expected error 3 (too many parameters), got 0xC0 (error 4"),
        "{msg}"
    );
}

/// A change the scenario's own expectations do not look at is still caught
/// by the golden comparison, which names the first divergence.
#[test]
fn golden_comparison_names_the_first_divergence() {
    let mut cfg = ModelConfig::default();
    five_percent(&mut cfg.obf_next, true);
    let msg = failure_of(&run_mutant(cfg), "s3_4_4_remaining_reads_one_less");
    assert!(
        msg.contains("golden trace: first divergence in bus transaction"),
        "{msg}"
    );
    assert!(
        msg.contains("IBF/OBF seen, from the data read before it: expected 10.000us"),
        "{msg}"
    );
}

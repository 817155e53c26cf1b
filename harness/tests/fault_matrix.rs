//! Issue 5's proof that the checks catch bad boards: every fault of the
//! catalogue is caught by the conformance suite, the golden comparison or
//! a bounded differential fuzz, and the clean board by none of them.

use ppmc::backend::EmuTarget;
use ppmc::emu::ModelConfig;
use ppmc::fault_matrix::{all_as_expected, check_board, render, FuzzBudget};
use ppmc::faults::CATALOGUE;
use ppmc::invariants::ids::Invariant;
use ppmc::protocol::Straps;
use std::path::Path;

#[test]
fn every_fault_is_caught_and_the_clean_board_is_not() {
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../golden");
    let suite = ppmc_scenarios::all();
    let mut rows = Vec::new();
    let boards = std::iter::once(("clean", ModelConfig::default()))
        .chain(CATALOGUE.iter().map(|f| (f.name, f.model())));
    for (name, model) in boards {
        let mut t = EmuTarget::new(Straps::default(), model).expect("emulator");
        rows.push(check_board(name, &mut t, &suite, &golden, FuzzBudget::default()).expect("runs"));
    }
    let table = render(&rows);
    assert!(all_as_expected(&rows), "{table}");
    assert_eq!(rows.len(), CATALOGUE.len() + 1);
    assert!(!rows[0].caught(), "{table}");
    // The fuzz oracle's invariants on the board's own replies catch the
    // faults they exist for (docs/invariants.md).
    let oracle = |name: &str| {
        let row = rows.iter().find(|r| r.board == name).expect("a row");
        row.oracle.as_ref().map(|c| c.first.clone())
    };
    for (fault, invariant) in [
        ("int-ignores-mask", Invariant::IntMask),
        ("phase-step-skipped", Invariant::PhasePattern),
        ("remaining-off-by-one", Invariant::RemainingPulses),
    ] {
        let first = oracle(fault).unwrap_or_else(|| panic!("{fault}: oracle missed it\n{table}"));
        assert!(first.contains(invariant.as_str()), "{fault}: {first}");
    }
    // A Decelerating Stop 1 us late (Table 3-3's 17 us) is caught by the
    // differential fuzz: its programs place a stop 1 us before a pulse, and
    // the late one decelerates a pulse later.
    let slow = rows
        .iter()
        .find(|r| r.board == "decel-stop-slow")
        .expect("a row");
    let fuzz = slow
        .fuzz
        .as_ref()
        .unwrap_or_else(|| panic!("missed\n{table}"));
    assert!(fuzz.first.contains("pulse"), "{}", fuzz.first);
}

/// The regression scenario `to-scenario` made from the minimized finding
/// of the injected remaining-pulses bug (Section 3-4-4) fails on a chip
/// with that bug, naming the invariant, and passes on the clean one.
#[test]
fn the_committed_fuzz_regression_fails_only_with_its_bug() {
    use ppmc::runner::run_suite;
    use ppmc::scenario::{DriverOptions, Verdict};
    let suite: Vec<_> = ppmc_scenarios::all()
        .into_iter()
        .filter(|s| s.name == "fuzz_remaining_pulses_1")
        .collect();
    assert_eq!(suite.len(), 1);
    let run = |model: ModelConfig| {
        let mut t = EmuTarget::new(Straps::default(), model).expect("emulator");
        run_suite(&mut t, &suite, 1, DriverOptions::default(), |_| {})
            .remove(0)
            .verdict
    };
    assert!(run(ModelConfig::default()).ok());
    let bug = ppmc::faults::find("remaining-off-by-one")
        .expect("fault")
        .model();
    match run(bug) {
        Verdict::Failed(f) => {
            assert_eq!(f.expectation, "invariant remaining-pulses (Section 3-4-4)");
            assert!(f.got.contains("remaining pulses read 1"), "{f}");
        }
        other => panic!("expected a failure, got {other:?}"),
    }
}

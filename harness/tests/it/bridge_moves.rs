//! A bridge keeps the capture's move records itself, from the bytes it
//! writes, the status it reads and the phase pattern it sees
//! (`ppmc_core::bridge::move_tracker`, docs/bridge-protocol.md section 7). Here
//! the whole suite runs with the reference model's own records replaced by
//! the tracker's: every trace must come out the same, event for event
//! (every move's time, kind, direction, steps, winding and phase), and so
//! must every verdict. A chip fault that the golden traces catch through
//! the move records still shows.

use ppmc_test_support as common;

use ppmc::backend::{Op, Reply, Target, TargetError, TargetInfo};
use ppmc::bridge::move_tracker::Tracked;
use ppmc::bus::{Bus, EmuBus};
use ppmc::emu::ModelConfig;
use ppmc::protocol::{OutputRecord, Straps};
use ppmc::runner::run_suite;
use ppmc::scenario::DriverOptions;

/// The reference model behind a move tracker, as a target.
struct TrackedTarget(Tracked<EmuBus>);

impl TrackedTarget {
    fn new(cfg: ModelConfig) -> TrackedTarget {
        let emu = EmuBus::new(Straps::default(), cfg).expect("emulator");
        TrackedTarget(Tracked::new(emu))
    }
}

impl Target for TrackedTarget {
    fn info(&self) -> TargetInfo {
        TargetInfo {
            name: "emu".into(),
            straps: self.0.straps(),
            extra: Vec::new(),
        }
    }

    fn capture(&mut self) -> Result<OutputRecord, TargetError> {
        Ok(self.0.record().clone())
    }

    fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError> {
        Ok(ops.iter().map(|op| self.0.run(*op)).collect())
    }
}

#[test]
fn the_trackers_move_records_are_the_models_on_the_whole_suite() {
    let mut t = TrackedTarget::new(ModelConfig::default());
    let tracked = run_suite(
        &mut t,
        &ppmc_scenarios::all(),
        1,
        DriverOptions::default(),
        |_| {},
    );
    let local = common::suite_in_process();
    assert_eq!(tracked.len(), local.len());
    let mut moves = 0;
    for (a, b) in tracked.iter().zip(&local) {
        let (ta, tb) = (
            a.trace.as_ref().expect("trace"),
            b.trace.as_ref().expect("trace"),
        );
        assert_eq!(ta.events, tb.events, "{}: the same trace", a.name);
        assert_eq!(a.verdict, b.verdict, "{}", a.name);
        moves += ta
            .events
            .iter()
            .filter(|e| matches!(e.kind, ppmc::trace::EventKind::Move { .. }))
            .count();
    }
    assert!(moves >= 100, "the suite starts many moves ({moves})");
}

/// The tracker reads the phase the chip shows, so a chip that skips the
/// first step of a move shows up in the move records as it does on the
/// model's own.
#[test]
fn a_phase_fault_shows_in_the_trackers_records_too() {
    let mut cfg = ModelConfig::default();
    ppmc::faults::apply_named("phase-step-skipped", &mut cfg).expect("a catalogue fault");
    let mut tracked = TrackedTarget::new(cfg.clone());
    let mut own = ppmc::backend::EmuTarget::new(Straps::default(), cfg).expect("emulator");
    let suite = ppmc_scenarios::all();
    let a = run_suite(&mut tracked, &suite, 1, DriverOptions::default(), |_| {});
    let b = run_suite(&mut own, &suite, 1, DriverOptions::default(), |_| {});
    for (a, b) in a.iter().zip(&b) {
        assert_eq!(
            a.trace.as_ref().map(|t| &t.events),
            b.trace.as_ref().map(|t| &t.events),
            "{}",
            a.name
        );
    }
}

//! One chip, three views: the pins sampled on the bus (`pins`), the status
//! register read on the bus, and the record the trace is written from must
//! tell the same story at every instant (Table 3-3, notes N36 and N42).
//! For random action programs (the differential fuzzer's, so initializations
//! are mostly valid and moves happen), every action is followed by pin
//! samples and status reads at short, uneven delays; the pin levels
//! reconstructed from the record alone must equal every sample, and every
//! status read's BUSY bit the BUSY line the record shows at that instant.

use ppmc::backend::{EmuTarget, Op, Reply, Target};
use ppmc::console::{self, ConsoleOptions, Stmt};
use ppmc::emu::ModelConfig;
use ppmc::fuzzing::differential::program;
use ppmc::protocol::{Pin, Pins, Record, Status, Straps, Winding};
use ppmc::time::{Duration, Instant};
use proptest::prelude::*;

/// The output pins as the record says they stood at `t` (events at `t`
/// included), replayed from the record alone: pin changes, move starts
/// (winding and phase index) and every pulse (one phase step each).
/// `switching` says whether stop switching was chopping the phases.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
struct Replayed {
    busy: bool,
    int: bool,
    hold: bool,
    aux: bool,
    auxo: u8,
    dir_ccw: bool,
    phases: u8,
    switching: bool,
}

fn replay(rec: &Record, t: Instant) -> Replayed {
    // (time, order at that time, what): moves, then pulses, then pin changes.
    enum Ev {
        Move(usize),
        Pulse(ppmc::protocol::Direction),
        Pin(Pin, u8),
    }
    let mut evs: Vec<(Instant, u8, Ev)> = Vec::new();
    for (i, m) in rec.moves.iter().enumerate() {
        evs.push((m.at, 0, Ev::Move(i)));
    }
    for (at, dir) in rec.pulses() {
        evs.push((at, 1, Ev::Pulse(dir)));
    }
    for p in &rec.pins {
        evs.push((p.at, 2, Ev::Pin(p.pin, p.value)));
    }
    evs.sort_by_key(|(at, order, _)| (*at, *order));
    let mut s = Replayed::default();
    let mut winding: Option<Winding> = None;
    let mut index = 0u32;
    for (at, _, ev) in evs {
        if at > t {
            break;
        }
        match ev {
            Ev::Move(i) => {
                winding = rec.moves[i].winding;
                index = rec.moves[i].phase_index;
            }
            Ev::Pulse(dir) => {
                if let Some(w) = winding {
                    index = w.advance(index, dir, 1);
                    s.phases = w.pattern(index);
                }
            }
            Ev::Pin(pin, v) => match pin {
                Pin::Busy => s.busy = v != 0,
                Pin::Int => s.int = v != 0,
                Pin::Hold => s.hold = v != 0,
                Pin::Aux => s.aux = v != 0,
                Pin::Auxo => s.auxo = v,
                Pin::Dir => s.dir_ccw = v != 0,
                Pin::Phases => s.phases = v,
                Pin::Switching => s.switching = v != 0,
            },
        }
    }
    s
}

/// Where the sampled pins and the replayed record disagree, in words.
fn disagreement(p: &Pins, r: &Replayed) -> Option<String> {
    let dir_ccw = p.dir == ppmc::protocol::Direction::Ccw;
    let same = p.busy == r.busy
        && p.int == r.int
        && p.hold == r.hold
        && p.aux == r.aux
        && p.auxo == r.auxo
        && dir_ccw == r.dir_ccw
        // Stop switching chops the energized phases on and off; the record
        // keeps the pattern and whether chopping is on.
        && (p.phases == r.phases || (r.switching && p.phases == 0));
    (!same).then(|| format!("sampled {p:?}, the record says {r:?}"))
}

/// Runs `actions` actions of program `seed`, each followed by samples at
/// the delays in `gaps`; returns every disagreement.
fn check(seed: u64, actions: usize, gaps: &[u64]) -> Vec<String> {
    let mut t = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    let opts = ConsoleOptions::default();
    let mut ops = vec![Op::Reset];
    for a in program(seed).take(actions) {
        ops.extend(a.stmts().into_iter().map(|s| console::to_op(s, &opts)));
        for &g in gaps {
            ops.push(console::to_op(Stmt::Wait(Duration::from_nanos(g)), &opts));
            ops.push(Op::ReadPins);
            ops.push(Op::ReadStatus);
        }
    }
    let replies = t.execute(&ops).expect("the emulator runs");
    let rec = t.capture().expect("capture");
    let mut bad = Vec::new();
    for (op, r) in ops.iter().zip(&replies) {
        match (op, r) {
            (Op::ReadPins, Reply::Pins { at, pins }) => {
                if let Some(d) = disagreement(pins, &replay(&rec, *at)) {
                    bad.push(format!("pins at {at}: {d}"));
                }
            }
            (Op::ReadStatus, Reply::Status { at, status }) => {
                let line = replay(&rec, *at).busy;
                if status.0 & Status::BUSY != 0 && !line {
                    bad.push(format!(
                        "status 0x{:02X} at {at} reads BUSY, the BUSY line is low",
                        status.0
                    ));
                }
            }
            _ => {}
        }
    }
    bad
}

/// Section 3-5-4, Table 3-3 (excitation OFF 18 us), note N36: after a
/// software reset the sampled phases stay energized until the record says
/// they go off, 18 us after the write, not when the reset is taken.
#[test]
fn software_reset_shows_one_chip_in_pins_and_record() {
    let mut t = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    let opts = ConsoleOptions::default();
    let script = "wc 0x02; wd 100; wd 20; wd 100; wd 0; wait 200ms; wc! 0xC0";
    let mut ops: Vec<Op> = console::parse_script(script)
        .expect("script")
        .into_iter()
        .map(|l| console::to_op(l.stmt, &opts))
        .collect();
    let write = ops.len() - 1;
    for _ in 0..24 {
        ops.push(Op::Delay(Duration::from_micros(1)));
        ops.push(Op::ReadPins);
    }
    let replies = t.execute(&ops).expect("runs");
    let rec = t.capture().expect("capture");
    let written = replies[write].at();
    let mut went_off = None;
    for r in &replies[write..] {
        if let Reply::Pins { at, pins } = r {
            assert_eq!(disagreement(pins, &replay(&rec, *at)), None, "at {at}");
            if pins.phases == 0 && went_off.is_none() {
                went_off = Some(at.saturating_since(written));
            }
        }
    }
    assert_eq!(went_off, Some(Duration::from_micros(18)));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn pins_status_and_record_agree_for_random_programs(
        seed in any::<u64>(),
        actions in 1usize..30,
        gaps in proptest::collection::vec(1u64..400_000, 1..4),
    ) {
        let bad = check(seed, actions, &gaps);
        prop_assert!(bad.is_empty(), "seed {seed}, {actions} actions, gaps {gaps:?}:\n{}", bad.join("\n"));
    }
}

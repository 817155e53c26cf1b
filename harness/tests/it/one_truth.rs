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
use ppmc::protocol::{OutputRecord, Pin, Pins, Status, Straps, Winding};
use ppmc::time::{Duration, Instant};
use proptest::prelude::*;

/// The output pins as the record says they stood at an instant, replayed
/// from the record alone: pin changes and every pulse (one phase step of
/// its move's winding from the move's phase index). `switching` says
/// whether stop switching was chopping the phases.
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

/// One of the record's events: a pulse (of the move whose runs hold it),
/// a pin change.
enum Ev {
    Pulse(ppmc::protocol::Direction, Option<usize>),
    Pin(Pin, u8),
}

/// The record replayed forward, once: [`Replayer::at`] takes the instants
/// in order (as a program's replies come), so a program of long moves
/// costs its pulses once, not once per sample.
struct Replayer<'a> {
    rec: &'a OutputRecord,
    /// (time, order at that time, what): pulses, then pins.
    evs: Vec<(Instant, u8, Ev)>,
    next: usize,
    last: Instant,
    s: Replayed,
    /// The move the last pulse was of, its winding and phase step.
    stepping: Option<usize>,
    winding: Option<Winding>,
    index: u32,
}

impl<'a> Replayer<'a> {
    fn new(rec: &'a OutputRecord) -> Replayer<'a> {
        // A pulse is of the move whose runs hold it: a move's `at` is when
        // its command was written, and a command the chip takes only once
        // the move before it ends (IBF held) starts later than that.
        let mut evs: Vec<(Instant, u8, Ev)> = Vec::new();
        let owner = |run: usize| rec.moves.iter().rposition(|m| m.first_run <= run);
        for (k, r) in rec.runs.iter().enumerate() {
            for i in 0..r.count {
                evs.push((r.at(i), 1, Ev::Pulse(r.dir, owner(k))));
            }
        }
        for p in &rec.pins {
            evs.push((p.at, 2, Ev::Pin(p.pin, p.value)));
        }
        evs.sort_by_key(|(at, order, _)| (*at, *order));
        Replayer {
            rec,
            evs,
            next: 0,
            last: Instant::ZERO,
            s: Replayed::default(),
            stepping: None,
            winding: None,
            index: 0,
        }
    }

    /// The pins as the record says they stood at `t` (events at `t`
    /// included); an instant before the last asked starts over.
    fn at(&mut self, t: Instant) -> Replayed {
        if t < self.last {
            self.next = 0;
            self.s = Replayed::default();
            self.stepping = None;
            self.winding = None;
            self.index = 0;
        }
        self.last = t;
        while let Some((at, _, ev)) = self.evs.get(self.next) {
            if *at > t {
                break;
            }
            match ev {
                Ev::Pulse(dir, of) => {
                    if *of != self.stepping {
                        // The move's first pulse: its winding from its
                        // phase step.
                        self.stepping = *of;
                        let m = of.map(|k| self.rec.moves[k]);
                        self.winding = m.and_then(|m| m.winding);
                        self.index = m.map_or(0, |m| m.phase_index);
                    }
                    if let Some(w) = self.winding {
                        self.index = w.advance(self.index, *dir, 1);
                        self.s.phases = w.pattern(self.index);
                    }
                }
                Ev::Pin(pin, v) => {
                    let on = *v != 0;
                    match pin {
                        Pin::Busy => self.s.busy = on,
                        Pin::Int => self.s.int = on,
                        Pin::Hold => self.s.hold = on,
                        Pin::Aux => self.s.aux = on,
                        Pin::Auxo => self.s.auxo = *v,
                        Pin::Dir => self.s.dir_ccw = on,
                        Pin::Phases => self.s.phases = *v,
                        Pin::Switching => self.s.switching = on,
                    }
                }
            }
            self.next += 1;
        }
        self.s
    }
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
    let mut replay = Replayer::new(&rec);
    for (op, r) in ops.iter().zip(&replies) {
        match (op, r) {
            (Op::ReadPins, Reply::Pins { at, pins }) => {
                if let Some(d) = disagreement(pins, &replay.at(*at)) {
                    bad.push(format!("pins at {at}: {d}"));
                }
            }
            (Op::ReadStatus, Reply::Status { at, status }) => {
                let line = replay.at(*at).busy;
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
    let mut replay = Replayer::new(&rec);
    for r in &replies[write..] {
        if let Reply::Pins { at, pins } = r {
            assert_eq!(disagreement(pins, &replay.at(*at)), None, "at {at}");
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

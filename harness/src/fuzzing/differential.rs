//! Differential runs: a seeded stream of typed actions
//! ([`super::actions`]) on a target and on the reference emulator side by
//! side, compared after every action with `ppmc compare`'s rules (status
//! bytes, read data, waits and pulse timing within the tolerances, pulse
//! counts exactly). The seed alone replays a run.

use super::actions::{self, Action};
use super::reference;
use crate::backend::{EmuTarget, Op, Reply, Target, TargetError, TargetErrorKind};
use crate::bus_program::BusOp;
use crate::compare::{compare_from, Divergence, Resume, Tolerances};
use crate::console::{self, ConsoleOptions};
use crate::emu::ModelConfig;
use crate::protocol::{OutputMark, OutputRecord, Status, Straps};
use crate::time::{Duration, Instant};
use crate::trace::{uncertainty_entry, Event, EventKind, Trace};
use rand::{Rng, SeedableRng};
use std::fmt::Write as _;

/// The actions of run `seed`, generated as they are taken: a valid
/// initialization, then actions decoded from the seed's random bytes, for
/// ever. `program(seed).take(n)` is the run of `n` actions; memory does not
/// grow with `n`.
pub fn program(seed: u64) -> Program {
    let init = Action::default_init();
    Program {
        rng: rand::rngs::StdRng::seed_from_u64(seed),
        pending: std::collections::VecDeque::from([init]),
        ramp: Ramp::of(&init),
    }
}

/// The endless action stream of one seed (see [`program`]).
#[derive(Debug, Clone)]
pub struct Program {
    rng: rand::rngs::StdRng,
    pending: std::collections::VecDeque<Action>,
    /// The ramp of the last initialization generated.
    ramp: Option<Ramp>,
}

/// What a generated initialization sets: RH and PA as written.
#[derive(Debug, Clone, Copy)]
struct Ramp {
    rh: u8,
    pa: u16,
}

impl Ramp {
    fn of(a: &Action) -> Option<Ramp> {
        let stmts = a.stmts();
        let byte = |i: usize| match stmts.get(i) {
            Some(crate::console::Stmt::WriteData { byte, .. }) => Some(*byte),
            _ => None,
        };
        match a {
            Action::Init { .. } => Some(Ramp {
                rh: byte(2)?,
                pa: u16::from_le_bytes([byte(3)?, byte(4)?]),
            }),
            _ => None,
        }
    }
}

impl Iterator for Program {
    type Item = Action;

    fn next(&mut self) -> Option<Action> {
        while self.pending.is_empty() {
            let bytes: Vec<u8> = (0..256).map(|_| self.rng.random()).collect();
            for a in actions::decode(&bytes) {
                self.push(a);
            }
        }
        self.pending.pop_front()
    }
}

impl Program {
    fn push(&mut self, a: Action) {
        if let Some(r) = Ramp::of(&a) {
            self.ramp = Some(r);
        }
        match (a, self.ramp) {
            // A probe of the stop latencies: a 1,000-step move and a
            // Decelerating Stop written so that, on the reference board
            // (Tclock 2 us), it takes effect 1 us before a pulse at high
            // speed (Table 3-3: 17 us after the write). A stop that acts
            // even 1 us late acts after that pulse instead, and the move
            // ends a pulse later: the one departure a stop latency makes
            // that the tolerances cannot absorb.
            (Action::StopNearPulse { pulse, .. }, Some(r)) => {
                let period = 2 * (u32::from(r.rh) + 1);
                let cruise = 1_000u16.saturating_sub(2 * r.pa + 2).max(1);
                self.pending.push_back(Action::AwaitIdle);
                self.pending.push_back(Action::Move {
                    kind: 1,
                    ccw: pulse % 2 == 1,
                    interrupt: true,
                    pout: false,
                    rate: 0,
                    steps: 999,
                });
                self.pending.push_back(Action::StopNearPulse {
                    decel: true,
                    pulse: r.pa + pulse % cruise,
                    micros: u8::try_from(period.saturating_sub(18)).unwrap_or(u8::MAX),
                });
            }
            _ => self.pending.push_back(a),
        }
    }
}

/// Where a run first departed from the emulator.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Departure {
    /// Index of the action after which it was seen.
    pub action: usize,
    pub divergence: Divergence,
}

impl std::fmt::Display for Departure {
    /// `departs after action N at T: <quantity>: emulator X, target Y (allowed Z)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let dv = &self.divergence;
        write!(
            f,
            "departs after action {} at {}: {}: emulator {}, target {} (allowed {})",
            self.action + 1,
            dv.at,
            dv.quantity,
            dv.golden,
            dv.got,
            dv.allowed
        )
    }
}

/// One side of a run: a target and what it has shown since the last
/// checkpoint (both sides at rest, everything before compared equal).
struct Side<'a> {
    target: &'a mut dyn Target,
    /// Bus events since the checkpoint.
    bus: Vec<Event>,
    /// The capture since the checkpoint, and where the checkpoint cut the
    /// whole.
    capture: OutputRecord,
    mark: OutputMark,
    /// The last action's traffic as bus ops, and the time of its last
    /// reply (the target's clock since its chip reset).
    ops: Vec<BusOp>,
    at: Instant,
    /// The last action's replies.
    replies: Vec<Reply>,
}

impl Side<'_> {
    /// Runs `ops` (one action's, `stmts` as written) in one batch; the
    /// closing status read's status.
    fn run(&mut self, stmts: &[console::Stmt], ops: &[Op]) -> Result<Status, TargetError> {
        let (replies, capture) = self.target.execute_then_capture_since(ops, self.mark)?;
        self.take(stmts, ops, replies, capture)
    }

    /// Runs `ops` as [`Side::run`] does, each begun no earlier than
    /// `starts` says ([`reference::run_at`]).
    fn run_at(
        &mut self,
        stmts: &[console::Stmt],
        ops: &[Op],
        starts: &[Instant],
    ) -> Result<Status, TargetError> {
        let replies = reference::run_at(self.target, ops, starts, self.at)?;
        let (_, capture) = self.target.execute_then_capture_since(&[], self.mark)?;
        self.take(stmts, ops, replies, capture)
    }

    fn take(
        &mut self,
        stmts: &[console::Stmt],
        ops: &[Op],
        replies: Vec<Reply>,
        capture: OutputRecord,
    ) -> Result<Status, TargetError> {
        if replies.len() != ops.len() {
            return Err(TargetError::new(
                TargetErrorKind::Other,
                format!(
                    "target answered {} of {} operations",
                    replies.len(),
                    ops.len()
                ),
            ));
        }
        self.ops.clear();
        for (s, r) in stmts.iter().zip(&replies) {
            let gap = r.at().saturating_since(self.at);
            if gap > Duration::ZERO {
                self.ops.push(BusOp::Advance(gap));
            }
            self.at = self.at.max(r.at());
            self.ops.extend(bus_op(*s, r));
            if let Some(kind) = console::bus_event(*s, r) {
                self.bus.push(Event {
                    at: r.at(),
                    kind: EventKind::Bus(kind),
                });
            }
        }
        self.capture = capture;
        self.replies = replies;
        match self.replies.last() {
            Some(Reply::Status { status, .. }) => Ok(*status),
            other => Err(TargetError::new(
                TargetErrorKind::Other,
                match other {
                    Some(r) => format!("expected the closing status read, got `{r}`"),
                    None => "no reply to the closing status read".into(),
                },
            )),
        }
    }

    /// The trace since the checkpoint: the bus, and the capture too if
    /// `with_capture`.
    fn trace(&self, name: &str, with_capture: bool) -> Trace {
        let empty = OutputRecord::default();
        let capture = if with_capture { &self.capture } else { &empty };
        let info = self.target.info();
        // The target's declared uncertainty, which the compare widens each
        // timing by: a board measured through a bridge is not exact.
        let u = self.target.uncertainty();
        let details = vec![uncertainty_entry(&u)];
        Trace::new(name, "-", info.name.as_str(), info.straps, details).assemble(
            self.bus.clone(),
            capture,
            Vec::new(),
        )
    }

    /// Everything so far was compared: the next window starts here, and
    /// the target may drop what came before (its record then keeps about
    /// the last move: memory stays flat however long the run).
    fn checkpoint(&mut self) {
        self.bus.clear();
        let window = self.capture.mark();
        let mark = OutputMark {
            runs: self.mark.runs + window.runs,
            pins: self.mark.pins + window.pins,
            moves: self.mark.moves + window.moves,
        };
        let dropped = self.target.forget_capture_before(mark);
        self.mark = OutputMark {
            runs: mark.runs - dropped.runs.min(mark.runs),
            pins: mark.pins - dropped.pins.min(mark.pins),
            moves: mark.moves - dropped.moves.min(mark.moves),
        };
        self.capture = OutputRecord::default();
    }
}

/// What a statement did on the bus, as the bus op that does it
/// ([`crate::bus_program`]): a write or read that happened, an input
/// driven; nothing for a wait (its time is the gap before the next) or
/// an access that timed out.
fn bus_op(s: console::Stmt, r: &Reply) -> Option<BusOp> {
    use console::Stmt;
    match (s, r) {
        (Stmt::WriteCommand { byte, .. }, Reply::Written { .. }) => Some(BusOp::Command(byte)),
        (Stmt::WriteData { byte, .. }, Reply::Written { .. }) => Some(BusOp::Data(byte)),
        (Stmt::ReadStatus, _) => Some(BusOp::ReadStatus),
        (Stmt::ReadData { .. }, Reply::Data { .. }) => Some(BusOp::ReadData),
        (Stmt::Set { input, asserted }, _) => Some(BusOp::Input { input, asserted }),
        _ => None,
    }
}

/// Where a differential run is, told after each action.
#[derive(Debug)]
pub struct Step<'a> {
    /// Actions done.
    pub actions: usize,
    /// The target's own time since its chip reset: a budget of board time
    /// is spent against it.
    pub board_time: Duration,
    /// The action's traffic on the reference emulator as bus ops, the
    /// time between them included: what [`super::campaign::Walk`] counts
    /// the run's domain coverage from.
    pub ops: &'a [BusOp],
}

/// A differential run's settings.
#[derive(Debug, Clone, Default)]
pub struct DiffSettings {
    pub straps: Straps,
    /// The reference model (the clean emulator by default).
    pub reference: ModelConfig,
    pub tolerances: Tolerances,
    pub console: ConsoleOptions,
}

/// Runs `acts` on `target` (from a chip reset) and on a fresh reference
/// emulator, comparing after every action; stops at the first departure.
/// `progress` is called after each action with the number done, and may
/// stop the run early by returning false.
pub fn run(
    target: &mut dyn Target,
    acts: impl IntoIterator<Item = Action>,
    s: &DiffSettings,
    mut progress: impl FnMut(&Step<'_>) -> bool,
) -> Result<Option<Departure>, TargetError> {
    let mut reference = EmuTarget::new(s.straps, s.reference.clone()).map_err(|e| {
        TargetError::new(TargetErrorKind::Other, format!("reference emulator: {e}"))
    })?;
    target.execute(&[Op::Reset])?;
    let mut got = Side {
        target,
        bus: Vec::new(),
        capture: OutputRecord::default(),
        mark: OutputMark::default(),
        ops: Vec::new(),
        at: Instant::ZERO,
        replies: Vec::new(),
    };
    let mut want = Side {
        target: &mut reference,
        bus: Vec::new(),
        capture: OutputRecord::default(),
        mark: OutputMark::default(),
        ops: Vec::new(),
        at: Instant::ZERO,
        replies: Vec::new(),
    };
    // What was compared before the windows begin: each compare looks at
    // what came since the last time both sides were at rest and agreed, so
    // a run costs time linear in its length.
    let mut from = Resume::default();
    let mut last = 0;
    let mut at_rest = true;
    // A board whose times are exact waited for its flags as the model does.
    let exact = got.target.uncertainty() == crate::backend::Uncertainty::ZERO;
    for (i, a) in acts.into_iter().enumerate() {
        last = i;
        let mut stmts = a.stmts();
        // Every action ends with a status read: what the host sees, and
        // whether the chip is idle so that the pulses can be compared.
        stmts.push(console::Stmt::ReadStatus);
        let ops: Vec<Op> = stmts
            .iter()
            .map(|st| console::to_op(*st, &s.console))
            .collect();
        // The board first; the reference then meets each input when the
        // board's chip did.
        let before = got.at;
        got.run(&stmts, &ops)?;
        let starts = reference::starts(&ops, &got.replies, before, exact);
        let status = want.run_at(&stmts, &ops, &starts)?;
        // Pulses are compared when the chip is idle, so a board's clock
        // a hair off the emulator's cannot split a move differently; and
        // with no byte waiting for it (IBF = 0): a move command written
        // while the chip was busy starts when the chip takes it (3-1-1),
        // which a bridge, recording moves from the bus, has already
        // recorded at the write (note N47).
        let idle = reference::at_rest(status);
        at_rest = idle;
        match compare_from(
            &want.trace("differential", idle),
            &got.trace("differential", idle),
            &s.tolerances,
            &from,
        ) {
            Err(divergence) => {
                return Ok(Some(Departure {
                    action: i,
                    divergence,
                }))
            }
            Ok(next) if idle => {
                from = next;
                want.checkpoint();
                got.checkpoint();
            }
            Ok(_) => {}
        }
        let step = Step {
            actions: i + 1,
            board_time: got.at.saturating_since(Instant::ZERO),
            ops: &want.ops,
        };
        if !progress(&step) {
            break;
        }
    }
    // At the end, everything since the last checkpoint: the capture too
    // if the chip is at rest (as after each action).
    if let Err(divergence) = compare_from(
        &want.trace("differential", at_rest),
        &got.trace("differential", at_rest),
        &s.tolerances,
        &from,
    ) {
        return Ok(Some(Departure {
            action: last,
            divergence,
        }));
    }
    Ok(None)
}

/// Shrinks a departing run on the target: drops chunks of actions (halving
/// the chunk size down to single actions) while the run still departs, at
/// most `budget` replays. Returns the actions and their departure.
pub fn minimize(
    target: &mut dyn Target,
    acts: &[Action],
    s: &DiffSettings,
    budget: usize,
) -> Result<(Vec<Action>, Option<Departure>), TargetError> {
    let mut tries = 1;
    let departs =
        |target: &mut dyn Target, acts: &[Action]| run(target, acts.iter().cloned(), s, |_| true);
    let Some(mut d) = departs(target, acts)? else {
        return Ok((acts.to_vec(), None));
    };
    let mut best: Vec<Action> = acts[..=d.action.min(acts.len() - 1)].to_vec();
    let mut chunk = best.len().div_ceil(2).max(1);
    'outer: loop {
        let mut i = 1; // the initialization stays
        while i < best.len() {
            if tries >= budget {
                break 'outer;
            }
            let mut cand = best.clone();
            cand.drain(i..(i + chunk).min(cand.len()));
            tries += 1;
            match departs(target, &cand)? {
                Some(nd) => {
                    cand.truncate(nd.action + 1);
                    best = cand;
                    d = nd;
                }
                None => i += chunk,
            }
        }
        if chunk == 1 {
            break;
        }
        chunk = chunk.div_ceil(2);
    }
    Ok((best, Some(d)))
}

/// The reproducer: a console script of the actions, headed by how to
/// replay it and what departed. After each action it reads the status,
/// the output pins and the pulses of the latest move (`rs`, `pins`,
/// `pulses`), so that the two replays print what a departure is made of
/// (a read byte, a pin, a pulse count or interval) and their diff shows it.
pub fn script(acts: &[Action], d: &Departure, seed: u64, target: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# differential reproducer: seed {seed}, target {target}, {} actions",
        acts.len()
    );
    let _ = writeln!(out, "# {d}");
    let _ = writeln!(
        out,
        "# replay: ppmc console --target emu FILE; ppmc console --target {target} FILE; diff the two"
    );
    for (i, a) in acts.iter().enumerate() {
        let _ = writeln!(out, "# action {}", i + 1);
        for st in a.stmts() {
            let _ = writeln!(out, "{st}");
        }
        let _ = writeln!(out, "rs");
        let _ = writeln!(out, "pins");
        let _ = writeln!(out, "pulses");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::faults;

    fn emu(cfg: ModelConfig) -> EmuTarget {
        EmuTarget::new(Straps::default(), cfg).expect("emulator")
    }

    #[test]
    fn a_seed_gives_one_program() {
        let take = |seed, n| program(seed).take(n).collect::<Vec<_>>();
        assert_eq!(take(7, 50), take(7, 50));
        assert_ne!(take(7, 50), take(8, 50));
        assert_eq!(take(7, 50)[0], Action::default_init());
        assert_eq!(take(7, 50).len(), 50);
        // A longer run starts with the shorter one: the seed alone replays
        // the prefix that departed.
        assert_eq!(take(7, 500)[..50], take(7, 50)[..]);
    }

    #[test]
    fn the_emulator_against_itself_never_departs() {
        let mut t = emu(ModelConfig::default());
        for seed in 0..4 {
            let d = run(
                &mut t,
                program(seed).take(120),
                &DiffSettings::default(),
                |_| true,
            );
            assert_eq!(d.expect("runs"), None, "seed {seed}");
        }
    }

    /// What the target holds of its capture: its records of every kind.
    fn held(t: &EmuTarget) -> usize {
        let r = t.board().record();
        r.runs.len() + r.pins.len() + r.moves.len()
    }

    /// A long run keeps a window of the capture, not its history: the
    /// target's record stays small however many actions run (here 20,000,
    /// whose whole record would be several times the bound), also on a
    /// board whose miswired output keeps a record of its own.
    #[test]
    fn a_long_run_keeps_only_a_window_of_the_capture() {
        for fault in [None, Some("dir-inverted")] {
            let cfg = fault.map_or_else(ModelConfig::default, |f| {
                faults::find(f).expect("fault").model()
            });
            let s = DiffSettings {
                reference: cfg.clone(),
                ..DiffSettings::default()
            };
            let mut t = emu(cfg);
            let mut seen = 0;
            let d = run(&mut t, program(5).take(20_000), &s, |n| {
                seen = n.actions;
                true
            });
            assert_eq!(d.expect("runs"), None, "{fault:?}");
            assert_eq!(seen, 20_000);
            let held = held(&t);
            assert!(held <= 2_000, "{fault:?}: {held} records held");
        }
    }

    /// A board that reads remaining pulses one too many departs, and the
    /// minimized run still does, in fewer actions, with the departure in a
    /// read byte.
    #[test]
    fn a_faulty_board_departs_and_minimizes() {
        let cfg = faults::find("remaining-off-by-one").expect("fault").model();
        let mut t = emu(cfg);
        let s = DiffSettings::default();
        let found = (0..40).find_map(|seed| {
            let acts: Vec<Action> = program(seed).take(300).collect();
            run(&mut t, acts.iter().cloned(), &s, |_| true)
                .expect("runs")
                .map(|d| (seed, acts, d))
        });
        let (seed, acts, d) = found.expect("some seed of 40 finds it");
        let (small, d2) = minimize(&mut t, &acts, &s, 300).expect("runs");
        let d2 = d2.expect("still departs");
        assert!(small.len() <= d.action + 1, "{} actions", small.len());
        assert!(d2.divergence.quantity.contains("bus transaction"), "{d2:?}");
        let text = script(&small, &d2, seed, "emu");
        assert!(text.contains(&format!("seed {seed}")));
        assert!(console::parse_script(&text).is_ok(), "{text}");
    }

    /// Issue 29: the reproducer said "diff the two", but printed no pulse
    /// or pin, so a departure in the pulses made an empty diff. Replayed
    /// on the clean model and on the faulty board, as the header says, its
    /// outputs now differ where the departure is.
    #[test]
    fn the_reproducers_two_replays_differ_where_the_boards_do() {
        let faulty = || faults::find("drop-last-pulse").expect("fault").model();
        let mut t = emu(faulty());
        let s = DiffSettings::default();
        let (seed, acts, d) = (0..40)
            .find_map(|seed| {
                let acts: Vec<Action> = program(seed).take(300).collect();
                run(&mut t, acts.iter().cloned(), &s, |_| true)
                    .expect("runs")
                    .map(|d| (seed, acts, d))
            })
            .expect("some seed of 40 finds the lost pulse");
        let (small, d) = match minimize(&mut t, &acts, &s, 300).expect("runs") {
            (small, Some(d2)) => (small, d2),
            (_, None) => (acts, d),
        };
        let text = script(&small, &d, seed, "emu");
        let lines = console::parse_script(&text).expect("the reproducer parses");
        let replay = |cfg: ModelConfig| {
            let mut out = Vec::new();
            let opts = console::ConsoleOptions::default();
            console::run(&mut emu(cfg), &lines, &opts, &mut out).expect("replays");
            String::from_utf8(out).expect("text")
        };
        let (clean, board) = (replay(ModelConfig::default()), replay(faulty()));
        let differ: Vec<(&str, &str)> = clean
            .lines()
            .zip(board.lines())
            .filter(|(a, b)| a != b)
            .collect();
        assert!(
            !differ.is_empty(),
            "the two replays print the same:\n{clean}"
        );
        assert!(
            differ.iter().any(|(a, _)| a.starts_with("pulses")),
            "{differ:?}"
        );
    }
}

//! The invariant oracle: runs bus ops on a fresh emulator and checks,
//! after every op, the invariants of `docs/invariants.md`. Each invariant
//! has a stable id; a finding is bucketed by it.

use crate::emu::{Board, ChipError, ModelConfig};
use crate::fuzzing::bus::{self, BusOp};
use crate::protocol::capture::{MoveStart, Pin, PulseRun, Record};
use crate::protocol::{
    ClockSource, Command, FinishStatus, InitData, MoveKind, Register, Status, StatusField, Straps,
};
use crate::time::{Duration, Instant};
use std::cell::Cell;
use std::fmt;

/// Largest number of parameter bytes any command takes (Initialization,
/// Section 3-2): the most bits 6-4 can show without an error.
const MAX_PARAMS: u8 = 4;

/// Every invariant id with the datasheet section it comes from.
pub const INVARIANTS: &[(&str, &str)] = &[
    ("status-bit3", "3-1-1"),
    ("status-params", "3-1-1"),
    ("busy-status-matches", "3-1-1"),
    ("remaining-pulses", "3-4-4"),
    ("finish-flag-once", "3-4-1"),
    ("busy-covers-pulses", "3-1-1"),
    ("int-mask", "3-3-1"),
    ("int-release", "3-4-1"),
    ("phase-pattern", "3-2-1"),
    ("min-interval", "3-2-2"),
    ("time-monotonic", "model"),
    ("record-ordered", "model"),
];

/// The datasheet section an invariant comes from.
pub fn section(invariant: &str) -> &'static str {
    INVARIANTS
        .iter()
        .find(|(id, _)| *id == invariant)
        .map_or("model", |(_, s)| s)
}

/// An invariant break: which invariant, after which op, and what was seen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Violation {
    /// The invariant's id in `docs/invariants.md`, e.g. `status-bit3`.
    pub invariant: &'static str,
    /// Index of the op after which it was seen.
    pub op: usize,
    pub detail: String,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} after op {}: {}",
            self.invariant, self.op, self.detail
        )
    }
}

/// Runs `ops` on a fresh chip and returns the first invariant break.
pub fn check(ops: &[BusOp], cfg: ModelConfig) -> Result<Option<Violation>, ChipError> {
    check_ops(ops.iter().copied(), cfg)
}

/// [`check`] on ops as they come (a fuzz input's, as they are decoded).
pub fn check_ops(
    ops: impl IntoIterator<Item = BusOp>,
    cfg: ModelConfig,
) -> Result<Option<Violation>, ChipError> {
    // A fuzz target checks an input after another on one thread: the
    // checker of the last one, reset, keeps the memory it grew (and stays
    // off the stack, where AddressSanitizer's fake stack makes a large
    // frame costly).
    thread_local! {
        static SPARE: Cell<Option<Box<Checker>>> = const { Cell::new(None) };
    }
    let mut c = match SPARE.take() {
        Some(mut c) if *c.board.chip().config() == cfg => {
            c.reset();
            c
        }
        _ => Box::new(Checker::new(cfg)?),
    };
    let verdict = c.run(ops);
    SPARE.set(Some(c));
    Ok(verdict)
}

/// A byte the host wrote, to the command or the data register.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Written {
    Command(u8),
    Data(u8),
}

/// A register read in progress, as the host sees it.
#[derive(Debug)]
struct Reading {
    command: u8,
    /// IBF has been seen at 0 since the command was written, so the chip
    /// took it (rather than losing it to a later write).
    taken: bool,
    /// The bytes read so far (a register has at most three) and how many.
    bytes: [u8; 3],
    got: usize,
}

/// What the host saw of one op: the status register just before and just
/// after it (reading it has no side effect, Section 3-1-1), what a read
/// returned, and the time the op ended.
#[derive(Debug, Clone, Copy)]
pub struct Seen {
    pub before: Status,
    pub after: Status,
    /// The status byte of a `ReadStatus`, the byte of a `ReadData`.
    pub value: Option<u8>,
    pub at: Instant,
}

/// The invariants, judged from what the host sees of each op and from the
/// capture (as of each op's time). The same judge runs on the emulator's
/// chip ([`Checker`]) and on any target's replies ([`super::replay`]).
#[derive(Debug, Default)]
pub struct Judge {
    /// The board's straps: they fix the pulse clock (`min-interval`).
    straps: Straps,
    ops: usize,
    last_at: Instant,
    reading: Option<Reading>,
    /// Moves ended (BUSY falls) when the finish status was last read.
    stops_at_finish_read: usize,
    /// Every byte the chip took, with the time it was written: IBF was
    /// seen at 0 after it and no later write replaced it.
    taken: Vec<(Instant, Written)>,
    /// The last byte written, until the chip takes it (IBF seen at 0) or a
    /// later write replaces it (Section 3-1-1 (2)).
    pending: Option<(Instant, Written)>,
    /// When each finish status read command (0x80) was written.
    finish_reads: Vec<Instant>,
}

impl Judge {
    /// A judge for a board with these straps.
    pub fn new(straps: Straps) -> Judge {
        Judge {
            straps,
            ..Judge::default()
        }
    }

    /// Back to a new judge, keeping the memory of its byte lists.
    pub fn reset(&mut self) {
        let mut taken = std::mem::take(&mut self.taken);
        let mut finish_reads = std::mem::take(&mut self.finish_reads);
        taken.clear();
        finish_reads.clear();
        *self = Judge {
            taken,
            finish_reads,
            ..Judge::new(self.straps)
        };
    }

    /// The byte written last was taken (IBF seen at 0).
    fn take_pending(&mut self) {
        if let Some(p) = self.pending.take() {
            self.taken.push(p);
        }
    }

    /// Judges op number `self.ops` given what was seen of it and the
    /// capture, which may run past `seen.at` (it is looked at as of then).
    pub fn op(&mut self, op: BusOp, seen: Seen, rec: &Record) -> Result<(), Violation> {
        let i = self.ops;
        self.ops += 1;
        let fail = |invariant, detail: String| Violation {
            invariant,
            op: i,
            detail,
        };
        if !seen.before.ibf() {
            self.take_pending();
        } else if matches!(op, BusOp::Command(_) | BusOp::Data(_)) {
            // The byte waiting may be the read command: it could be lost.
            if self.reading.as_ref().is_some_and(|r| !r.taken) {
                self.reading = None;
            }
            // Whatever it was, this write replaces it.
            self.pending = None;
        }
        match (op, seen.value) {
            (BusOp::Data(b), _) => self.pending = Some((seen.at, Written::Data(b))),
            (BusOp::Command(b), _) => {
                if Command::decode(b) == Command::Read(Register::FinishStatus) {
                    self.finish_reads.push(seen.at);
                }
                self.pending = Some((seen.at, Written::Command(b)));
                self.reading = Some(Reading {
                    command: b,
                    taken: false,
                    bytes: [0; 3],
                    got: 0,
                });
            }
            (BusOp::ReadStatus, Some(v)) => {
                let s = Status(v);
                if let Some((invariant, detail)) = status_breaks(s) {
                    return Err(fail(invariant, detail));
                }
                let line = busy_level(rec, seen.at);
                if s.busy() != line {
                    return Err(fail(
                        "busy-status-matches",
                        format!(
                            "status 0x{:02X} reads BUSY={} at {} while the BUSY line is {}",
                            s.0,
                            u8::from(s.busy()),
                            seen.at,
                            u8::from(line)
                        ),
                    ));
                }
            }
            (BusOp::ReadData, Some(byte)) if seen.before.obf() => {
                if let Some(r) = self.reading.as_mut().filter(|r| r.taken) {
                    if let Some(slot) = r.bytes.get_mut(r.got) {
                        *slot = byte;
                    }
                    r.got += 1;
                }
                if let Some((invariant, detail)) = self.register_breaks(rec, seen.at) {
                    return Err(fail(invariant, detail));
                }
            }
            _ => {}
        }
        if let Some(r) = self.reading.as_mut() {
            r.taken |= !seen.after.ibf();
        }
        if !seen.after.ibf() {
            self.take_pending();
        }
        if seen.at < self.last_at {
            return Err(fail(
                "time-monotonic",
                format!("the clock went from {} back to {}", self.last_at, seen.at),
            ));
        }
        self.last_at = seen.at;
        Ok(())
    }

    /// The whole capture's invariants, once at the end (per op they would
    /// cost time quadratic in its length).
    pub fn finish(&self, rec: &Record) -> Result<(), Violation> {
        let at_end = |invariant, detail| Violation {
            invariant,
            op: self.ops.saturating_sub(1),
            detail,
        };
        if let Some(d) = pulse_outside_busy(rec) {
            return Err(at_end("busy-covers-pulses", d));
        }
        if let Some(d) = record_breaks(rec) {
            return Err(at_end("record-ordered", d));
        }
        if let Some((invariant, d)) = self.int_breaks(rec) {
            return Err(at_end(invariant, d));
        }
        if let Some(d) = phase_breaks(rec) {
            return Err(at_end("phase-pattern", d));
        }
        if let Some(d) = self.interval_breaks(rec) {
            return Err(at_end("min-interval", d));
        }
        Ok(())
    }

    /// INT* (Section 3-3, the operation commands' bit 4; 3-4-1): it is
    /// asserted only at the end of a move whose operation command asked for
    /// the termination interrupt (a stop command's own bit has no effect,
    /// 3-3-1, 3-3-2: the original command's counts), and released only
    /// by a finish status read: one written since the last release (it may
    /// come before INT* rises, taken after). One-sided as the finish flag
    /// is: a read command the chip lost cannot release it, so "still
    /// asserted after a read" is not claimed.
    fn int_breaks(&self, rec: &Record) -> Option<(&'static str, String)> {
        let mut asserted_at = None;
        let mut released_at = Instant::ZERO;
        for p in rec.pins.iter().filter(|p| p.pin == Pin::Int) {
            if p.value != 0 {
                asserted_at = Some(p.at);
                // The move that ended: the last one written by then, if it
                // had pulsed by then. A move's command may be written while
                // the one before still runs (its `at` is the write), so a
                // last move with no pulse yet may not have begun: no claim.
                let Some((m, runs)) = rec.move_written_by(p.at) else {
                    continue;
                };
                let pulsed = runs.first().is_some_and(|r| r.start <= p.at);
                if !pulsed {
                    continue;
                }
                // The operation command that started it: the last one
                // written by its final byte.
                let interrupt = self.taken.iter().rev().find_map(|&(t, w)| match w {
                    Written::Command(b) if t <= m.at => match Command::decode(b) {
                        Command::Move(c) => Some(c.flags.interrupt),
                        _ => None,
                    },
                    _ => None,
                });
                let Some(interrupt) = interrupt else {
                    continue;
                };
                if !interrupt {
                    return Some((
                        "int-mask",
                        format!(
                            "INT* asserted at {} at the end of a {} move whose command masks the termination interrupt (bit 4 = 1)",
                            p.at,
                            m.kind.name()
                        ),
                    ));
                }
            } else if let Some(from) = asserted_at.take() {
                // The read may have been written before INT* rose (during
                // the move) and taken after: any read since the last
                // release counts, but each release needs one of its own.
                let read = self
                    .finish_reads
                    .iter()
                    .any(|t| *t >= released_at && *t <= p.at);
                if !read {
                    return Some((
                        "int-release",
                        format!(
                            "INT* (asserted at {from}) released at {} without a finish status read written since {}",
                            p.at,
                            if released_at == Instant::ZERO {
                                "the start".to_string()
                            } else {
                                format!("the last release at {released_at}")
                            }
                        ),
                    ));
                }
                released_at = p.at;
            }
        }
        None
    }

    /// Section 3-2-2 and Equations 3-1 to 3-4: within a move, no pulse
    /// interval is shorter than the move's rate allows: the high speed
    /// rate RH of an initialization for the ramped moves (acceleration only
    /// ever lengthens it), the command's own rate byte for the constant
    /// ones. The judge knows those from the bytes the chip took; since it
    /// cannot see which initialization the chip kept (one refused with
    /// error 1 or 5 keeps the one before), it takes the fastest of every
    /// initialization taken before the move with rates the datasheet allows
    /// (255 > RL > RH > 0), on the clock each selects. A move whose
    /// command bytes it did not see all taken is not judged.
    fn interval_breaks(&self, rec: &Record) -> Option<String> {
        // The initializations taken so far, as the moves come (both in time
        // order): the fastest RH period among them, and the clocks they
        // chose. One pass, however many moves and bytes.
        let mut next_init = self.inits().peekable();
        let mut fastest_rh: Option<Duration> = None;
        // The pulse clock of each source chosen (internal, external).
        let mut tclocks: [Option<Duration>; 2] = [None; 2];
        for (k, m) in rec.moves.iter().enumerate() {
            while let Some((_, clock, data)) = next_init.next_if(|(done, _, _)| *done <= m.at) {
                if let Some(tclock) = self.straps.tclock(clock) {
                    let rh = self.straps.pulse_interval(data.rh, tclock);
                    fastest_rh = Some(fastest_rh.map_or(rh, |f| f.min(rh)));
                    tclocks[usize::from(clock == ClockSource::External)] = Some(tclock);
                }
            }
            let Some(params) = self.params_of(m) else {
                continue;
            };
            // The constant-rate moves' own rate byte; the ramped ones run
            // up to an initialization's RH.
            let own_rate = match m.kind {
                MoveKind::SingleStep => continue,
                MoveKind::AccelDecel | MoveKind::ContinuousHigh => None,
                MoveKind::Constant | MoveKind::ContinuousConstant | MoveKind::OriginSearch => {
                    Some(params[0])
                }
            };
            let bound = match own_rate {
                // The period is not monotonic in Tclock (VSEL low's term
                // shrinks as it grows): every clock chosen is tried.
                Some(rate) => tclocks
                    .iter()
                    .flatten()
                    .map(|t| self.straps.pulse_interval(rate, *t))
                    .min(),
                None => fastest_rh,
            };
            let Some(bound) = bound else {
                continue;
            };
            let runs = rec.runs_of_move(k);
            if let Some(d) = shortest_interval_below(runs, bound) {
                let rate = match own_rate {
                    Some(r) => format!("its rate byte {r}"),
                    None => "the fastest high speed rate RH initialized".into(),
                };
                return Some(format!(
                    "{d} in the {} move written at {}, shorter than the {bound} of {rate}",
                    m.kind.name(),
                    m.at
                ));
            }
        }
        None
    }

    /// The parameter bytes of move `m`: the data bytes the chip took after
    /// the last command byte it took by `m.at`, if that command is the
    /// move's and they are all there.
    fn params_of(&self, m: &MoveStart) -> Option<[u8; MAX_PARAMS as usize]> {
        let upto = self.taken.partition_point(|(t, _)| *t <= m.at);
        let taken = &self.taken[..upto];
        let k = taken
            .iter()
            .rposition(|(_, w)| matches!(w, Written::Command(_)))?;
        let Written::Command(c) = taken[k].1 else {
            return None;
        };
        let Command::Move(mc) = Command::decode(c) else {
            return None;
        };
        let mut params = [0; MAX_PARAMS as usize];
        let mut n = 0;
        for (_, w) in &taken[k + 1..] {
            if let Written::Data(b) = w {
                if let Some(slot) = params.get_mut(n) {
                    *slot = *b;
                }
                n += 1;
            }
        }
        (mc.kind == m.kind && n == usize::from(mc.kind.param_count())).then_some(params)
    }

    /// Every initialization the chip took with rates Section 3-2-2 allows,
    /// in time order: when its fourth data byte was taken, its clock and
    /// its data.
    fn inits(&self) -> impl Iterator<Item = (Instant, ClockSource, InitData)> + '_ {
        self.taken.iter().enumerate().filter_map(|(k, &(_, w))| {
            let Written::Command(c) = w else {
                return None;
            };
            let Command::Init(ic) = Command::decode(c) else {
                return None;
            };
            let mut data = [0u8; 4];
            let mut done = None;
            for (i, slot) in data.iter_mut().enumerate() {
                match self.taken.get(k + 1 + i) {
                    Some(&(t, Written::Data(b))) => {
                        *slot = b;
                        done = Some(t);
                    }
                    _ => return None,
                }
            }
            let d = InitData::from_bytes(data);
            let legal = 0 < d.rh && d.rh < d.rl && d.rl < 255;
            legal.then_some((done?, ic.clock, d))
        })
    }

    /// Checks a register read once all its bytes are in: the remaining
    /// pulses (Section 3-4-4) and the finish status polling flag (3-4-1).
    /// The chip takes a read command only when BUSY = 0, so the move the
    /// register tells of has ended by `at`.
    fn register_breaks(&mut self, rec: &Record, at: Instant) -> Option<(&'static str, String)> {
        let Reading {
            command,
            bytes,
            got,
            ..
        } = self.reading.as_ref()?;
        match Command::decode(*command) {
            Command::Read(Register::RemainingPulses) if *got == 3 => {
                let read = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], 0]);
                let (m, runs) = rec.move_written_by(at)?;
                let out: u64 = runs.iter().map(|r| u64::from(r.count_until(at))).sum();
                let steps = u64::from(m.steps);
                let want = if out >= steps { 0 } else { steps - out - 1 };
                (u64::from(read) != want).then(|| {
                    (
                        "remaining-pulses",
                        format!(
                            "remaining pulses read {read} after a move of {steps} steps \
                             that output {out} pulses; expected {want}"
                        ),
                    )
                })
            }
            Command::Read(Register::FinishStatus) if *got == 1 => {
                let stops = rec
                    .pins
                    .iter()
                    .filter(|p| p.pin == Pin::Busy && p.value == 0 && p.at <= at)
                    .count();
                let since = stops.saturating_sub(self.stops_at_finish_read);
                self.stops_at_finish_read = stops;
                let flag = FinishStatus(bytes[0]).polling();
                (flag && since == 0).then(|| {
                    (
                        "finish-flag-once",
                        format!(
                            "finish status 0x{:02X} has the polling flag set, but no move \
                             ended since the last finish status read",
                            bytes[0]
                        ),
                    )
                })
            }
            _ => None,
        }
    }
}

/// The oracle on the emulator: a fresh chip, fed one op at a time, each
/// judged as it goes; [`Checker::finish`] judges the whole record.
#[derive(Debug)]
pub struct Checker {
    /// The model on its board: the oracle reads status as a host does.
    board: Board,
    judge: Judge,
    /// The status register after the last op (none before the first).
    status: Option<Status>,
}

impl Checker {
    pub fn new(cfg: ModelConfig) -> Result<Checker, ChipError> {
        Ok(Checker {
            board: Board::new(Straps::default(), cfg)?,
            judge: Judge::new(Straps::default()),
            status: None,
        })
    }

    /// The chip under test, on its board.
    pub fn board(&self) -> &Board {
        &self.board
    }

    /// Ops applied so far.
    pub fn ops(&self) -> usize {
        self.judge.ops
    }

    /// Back to a fresh chip and judge, keeping the memory they grew.
    pub fn reset(&mut self) {
        self.board.reset();
        self.judge.reset();
        self.status = None;
    }

    /// Applies every op, judging each, then the whole record: the first
    /// invariant broken.
    pub fn run(&mut self, ops: impl IntoIterator<Item = BusOp>) -> Option<Violation> {
        for op in ops {
            if let Err(v) = self.apply(op) {
                return Some(v);
            }
        }
        self.finish().err()
    }

    /// Applies one op and judges it.
    pub fn apply(&mut self, op: BusOp) -> Result<(), Violation> {
        let chip = &mut self.board;
        // Nothing happens between two ops, and reading the status register
        // has no side effect (Section 3-1-1): the status after one op is
        // the status before the next.
        let before = self.status.unwrap_or_else(|| chip.read_status());
        let value = bus::apply(chip, op);
        // A status read's own value is the status after it.
        let after = match (op, value) {
            (BusOp::ReadStatus, Some(v)) => Status(v),
            _ => chip.read_status(),
        };
        self.status = Some(after);
        let seen = Seen {
            before,
            after,
            value,
            at: chip.now(),
        };
        self.judge.op(op, seen, chip.record())
    }

    /// The record's own invariants, checked once at the end.
    pub fn finish(&self) -> Result<(), Violation> {
        self.judge.finish(self.board.record())
    }
}

/// Section 3-1-1, Diagram 3-1: bit 3 reads 0; without an error, bits 6-4
/// count parameter bytes still due, never more than a command takes.
fn status_breaks(s: Status) -> Option<(&'static str, String)> {
    if s.reserved() {
        return Some(("status-bit3", format!("status 0x{:02X} has bit 3 set", s.0)));
    }
    match s.field() {
        StatusField::ParamsRemaining(n) if n > MAX_PARAMS => Some((
            "status-params",
            format!(
                "status 0x{:02X} asks for {n} more parameter bytes; no command takes more than {MAX_PARAMS}",
                s.0
            ),
        )),
        _ => None,
    }
}

/// The level of the recorded BUSY line at `t` (changes at `t` included).
fn busy_level(rec: &Record, t: Instant) -> bool {
    rec.pins
        .iter()
        .rev()
        .filter(|p| p.pin == Pin::Busy && p.at <= t)
        .map(|p| p.value != 0)
        .next()
        .unwrap_or(false)
}

/// Section 3-1-1 (3): BUSY is 1 "in the middle of pulse output", so every
/// pulse lies in an interval where the BUSY line is 1.
fn pulse_outside_busy(rec: &Record) -> Option<String> {
    let mut busy = rec.pins.iter().filter(|p| p.pin == Pin::Busy).peekable();
    let mut level = false;
    let mut since = Instant::ZERO;
    for r in &rec.runs {
        // The BUSY line as it stands at the run's first pulse.
        while let Some(p) = busy.next_if(|p| p.at <= r.start) {
            level = p.value != 0;
            since = p.at;
        }
        if !level {
            return Some(format!(
                "a pulse at {} while the BUSY line is 0 (since {since})",
                r.start
            ));
        }
        // It must not fall before the run's last pulse.
        if let Some(p) = busy.peek().filter(|p| p.at < r.last() && p.value == 0) {
            return Some(format!(
                "the BUSY line fell at {} with pulses until {}",
                p.at,
                r.last()
            ));
        }
    }
    None
}

/// The first interval among `runs` (one move's pulses) that is surely
/// shorter than `bound`: within a run, its mean interval less what its
/// jitter leaves unknown; between runs, the gap less both runs' jitter.
fn shortest_interval_below(runs: &[PulseRun], bound: Duration) -> Option<String> {
    let mut prev: Option<&PulseRun> = None;
    for r in runs {
        if let Some(p) = prev {
            let gap = r.start.saturating_since(p.last());
            if gap + p.jitter + r.jitter < bound {
                return Some(format!(
                    "pulses at {} and {}, {gap} apart,",
                    p.last(),
                    r.start
                ));
            }
        }
        if r.count > 1 {
            let spread = if r.is_exact() {
                Duration::ZERO
            } else {
                r.jitter.saturating_mul(2) + Duration::from_nanos(1)
            };
            if r.interval() + spread < bound {
                return Some(format!(
                    "{} pulses from {} every {}",
                    r.count,
                    r.start,
                    r.interval()
                ));
            }
        }
        prev = Some(r);
    }
    None
}

/// Section 3-2-1 (the excitation sequences) and 3-3: each pulse of a move
/// in phase excitation mode steps the phases once, in the move's
/// direction, so a move starts where the one before left the phases: its
/// start index is the last one's advanced by that move's pulses. Moves in
/// POUT mode hold the phases. Where the phases were set outside stepping
/// between two moves (initialization, excitation off), the move starts at
/// the pattern last set, which must be a step of its sequence. No claim
/// for a move written before the one before it put out its last pulse, or
/// while the phases were still being set (a change after its command and
/// before its first pulse), nor for the move after it.
fn phase_breaks(rec: &Record) -> Option<String> {
    let mut pins = rec.pins.iter().filter(|p| p.pin == Pin::Phases).peekable();
    // Where the last stepping move left the phases: its winding, index and
    // last pulse.
    let mut left: Option<(crate::protocol::Winding, u32, Instant)> = None;
    let mut set: Option<u8> = None;
    for (k, m) in rec.moves.iter().enumerate() {
        while let Some(p) = pins.next_if(|p| p.at <= m.at) {
            set = Some(p.value);
            left = None;
        }
        let runs = rec.runs_of_move(k);
        let horizon = runs.first().map_or(m.at, |r| r.start);
        let mut unsettled = false;
        while let Some(p) = pins.next_if(|p| p.at <= horizon) {
            set = Some(p.value);
            unsettled = true;
        }
        if let Some(r) = runs.iter().find(|r| r.dir != m.dir) {
            return Some(format!(
                "the {} move written at {} is commanded {}, but its pulses from {} go {}",
                m.kind.name(),
                m.at,
                m.dir.name(),
                r.start,
                r.dir.name()
            ));
        }
        let Some(w) = m.winding else {
            continue; // POUT mode: the phases hold
        };
        if unsettled {
            left = None;
            set = None;
            continue;
        }
        let start = m.phase_index % w.steps_per_cycle();
        if let Some(v) = set.take().filter(|v| *v != 0) {
            if w.pattern(start) != v {
                let legal = (0..w.steps_per_cycle()).any(|i| w.pattern(i) == v);
                return Some(format!(
                    "the {} move written at {} starts at step {start} of {} ({:05b}), but the phases were last set to {v:05b}{}",
                    m.kind.name(),
                    m.at,
                    w.name(),
                    w.pattern(start),
                    if legal { "" } else { ", which is no step of that sequence" }
                ));
            }
        } else if let Some((_, index, last)) = left.filter(|(lw, ..)| *lw == w) {
            if last <= m.at && start != index {
                return Some(format!(
                    "the {} move written at {} starts at step {start} of {}, but the pulses before it left the phases at step {index}",
                    m.kind.name(),
                    m.at,
                    w.name()
                ));
            }
        }
        let mut index = start;
        let mut last = m.at;
        for r in runs {
            index = w.advance(index, r.dir, u64::from(r.count));
            last = r.last();
        }
        left = Some((w, index, last));
    }
    None
}

/// Pulse runs do not overlap and come in time order; pin changes and move
/// starts come in time order.
fn record_breaks(rec: &Record) -> Option<String> {
    for w in rec.runs.windows(2) {
        if w[1].start <= w[0].last() {
            return Some(format!(
                "pulse run at {} starts before the previous one ends at {}",
                w[1].start,
                w[0].last()
            ));
        }
    }
    for w in rec.pins.windows(2) {
        if w[1].at < w[0].at {
            return Some(format!(
                "pin change at {} recorded after one at {}",
                w[1].at, w[0].at
            ));
        }
    }
    for w in rec.moves.windows(2) {
        if w[1].at < w[0].at {
            return Some(format!(
                "move start at {} recorded after one at {}",
                w[1].at, w[0].at
            ));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::{BoardFaults, Chip};
    use crate::fuzzing::bus::BusOp::*;
    use crate::time::Duration;

    /// Initialization (Section 3-2, the values of `capture_comes_in_chunks`)
    /// then a single step, with status reads between.
    fn init_and_step() -> Vec<BusOp> {
        let gap = Advance(Duration::from_millis(1));
        vec![
            Command(0x06),
            gap,
            Data(100),
            gap,
            Data(20),
            gap,
            Data(100),
            gap,
            Data(0),
            Advance(Duration::from_millis(200)),
            ReadStatus,
            Command(0x4A),
            Advance(Duration::from_millis(5)),
            ReadStatus,
            Advance(Duration::from_millis(5)),
            ReadStatus,
        ]
    }

    /// The sequence is a real one: the chip accepts it without error and
    /// the step comes out.
    #[test]
    fn the_sample_sequence_initializes_and_steps() {
        let mut chip = Chip::new(Straps::default(), ModelConfig::default()).expect("chip");
        for op in init_and_step() {
            match op {
                Command(b) => chip.write_command(b),
                Data(b) => chip.write_data(b),
                ReadStatus => assert_eq!(chip.read_status().0 & 0x80, 0, "no error"),
                Advance(d) => chip.advance_to(chip.now() + d),
                _ => {}
            }
        }
        assert_eq!(chip.record().pulse_count(), 1);
    }

    #[test]
    fn the_clean_model_keeps_every_invariant() {
        let r = check(&init_and_step(), ModelConfig::default()).expect("chip");
        assert_eq!(r, None);
    }

    /// Section 3-1-1: a data line stuck high on bit 3 is an invariant break.
    #[test]
    fn a_stuck_status_bit_is_caught() {
        let cfg = ModelConfig {
            board: BoardFaults {
                status_stuck_high: 0x08,
                ..BoardFaults::default()
            },
            ..ModelConfig::default()
        };
        let v = check(&init_and_step(), cfg)
            .expect("chip")
            .expect("a break");
        assert_eq!((v.invariant, v.op), ("status-bit3", 10));
    }

    #[test]
    fn parameter_counts_beyond_four_are_caught() {
        let cfg = ModelConfig {
            board: BoardFaults {
                status_stuck_high: 0x50,
                ..BoardFaults::default()
            },
            ..ModelConfig::default()
        };
        let v = check(&init_and_step(), cfg)
            .expect("chip")
            .expect("a break");
        assert_eq!(v.invariant, "status-params");
    }

    /// `init_and_step` with the step's termination interrupt masked
    /// (0x5A: bit 4 = 1, Section 3-3-8).
    fn init_and_masked_step() -> Vec<BusOp> {
        init_and_step()
            .into_iter()
            .map(|op| {
                if op == Command(0x4A) {
                    Command(0x5A)
                } else {
                    op
                }
            })
            .collect()
    }

    /// Section 3-3 (bit 4 of an operation command): a board that asserts
    /// INT* at the end of a masked move breaks `int-mask`; the clean model
    /// keeps it, masked or not.
    #[test]
    fn int_asserted_despite_the_mask_is_caught() {
        assert_eq!(
            check(&init_and_masked_step(), ModelConfig::default()).expect("chip"),
            None
        );
        let v = check(&init_and_masked_step(), faulty("int-ignores-mask"))
            .expect("chip")
            .expect("a break");
        assert_eq!(v.invariant, "int-mask", "{v}");
        assert!(v.detail.contains("masks the termination interrupt"), "{v}");
        // Unmasked, the same board asserts INT* rightly.
        assert_eq!(
            check(&init_and_step(), faulty("int-ignores-mask")).expect("chip"),
            None
        );
    }

    /// Section 3-4-1: the finish status read releases INT*; a release with
    /// no such read since INT* was asserted breaks `int-release`.
    #[test]
    fn int_released_only_by_a_finish_status_read() {
        let read = then_read(0x80, 1);
        assert_eq!(check(&read, ModelConfig::default()).expect("chip"), None);
        let mut rec = Record::default();
        rec.pin(Instant::from_nanos(1_000), Pin::Int, 1);
        rec.pin(Instant::from_nanos(5_000), Pin::Int, 0);
        let v = Judge::default().finish(&rec).expect_err("a break");
        assert_eq!(v.invariant, "int-release", "{v}");
        // Released after a finish status read written since the start
        // (here before INT* rose, taken after): kept.
        let judge = Judge {
            finish_reads: vec![Instant::from_nanos(500)],
            ..Judge::default()
        };
        assert_eq!(judge.finish(&rec), Ok(()));
        // A second release needs a read of its own.
        rec.pin(Instant::from_nanos(7_000), Pin::Int, 1);
        rec.pin(Instant::from_nanos(9_000), Pin::Int, 0);
        let v = judge.finish(&rec).expect_err("a break");
        assert_eq!(v.invariant, "int-release", "{v}");
        assert!(
            v.detail.contains("since the last release at 5.000us"),
            "{v}"
        );
    }

    /// `init_and_step`, then a second single step.
    fn init_and_two_steps() -> Vec<BusOp> {
        let mut ops = init_and_step();
        ops.extend([Command(0x4A), Advance(Duration::from_millis(5)), ReadStatus]);
        ops
    }

    /// Section 3-2-1: each pulse steps the phases once, so the second step
    /// (0x4A: CCW, 1-2 phase on a 4-phase motor, 8 steps a cycle) starts
    /// where the first left them, one step back from 0. A board whose phases miss the
    /// first step of every move breaks `phase-pattern` at the second.
    #[test]
    fn a_skipped_phase_step_is_caught_at_the_next_move() {
        assert_eq!(
            check(&init_and_two_steps(), ModelConfig::default()).expect("chip"),
            None
        );
        let v = check(&init_and_two_steps(), faulty("phase-step-skipped"))
            .expect("chip")
            .expect("a break");
        assert_eq!(v.invariant, "phase-pattern", "{v}");
        assert!(
            v.detail.contains("starts at step 0 of 4ph-12")
                && v.detail.contains("left the phases at step 7"),
            "{v}"
        );
        // One move alone shows nothing: the skip shows where the next
        // move starts.
        assert_eq!(
            check(&init_and_step(), faulty("phase-step-skipped")).expect("chip"),
            None
        );
    }

    /// Section 3-2-1: a move starts at the pattern the phases were set to;
    /// a pattern of no step of the sequence breaks `phase-pattern`.
    #[test]
    fn phases_set_to_no_step_of_the_sequence_are_caught() {
        use crate::protocol::{Direction, Excitation, MotorType, Winding};
        let w = Winding {
            motor: MotorType::FourPhase,
            excitation: Excitation::TwoPhase,
        };
        let mut rec = Record::default();
        rec.pin(Instant::from_nanos(1_000), Pin::Phases, 0b11000);
        rec.moves.push(MoveStart {
            at: Instant::from_nanos(5_000),
            kind: MoveKind::SingleStep,
            dir: Direction::Cw,
            pout: false,
            steps: 1,
            first_run: 0,
            phase_index: 0,
            winding: Some(w),
        });
        assert_eq!(phase_breaks(&rec), None);
        rec.pins[0].value = 0b10100;
        let d = phase_breaks(&rec).expect("a break");
        assert!(d.contains("no step of that sequence"), "{d}");
    }

    /// Section 3-2-2: init RL 100, RH 20 on the internal 2 us clock (a
    /// high speed interval of 21 x 2 us = 42 us), then an acceleration/
    /// deceleration move; a run of pulses 40 us apart breaks
    /// `min-interval`, 42 us apart keeps it.
    #[test]
    fn pulses_faster_than_the_high_speed_rate_are_caught() {
        use crate::protocol::{Command as C, Direction, MoveCommand};
        let t = |us: u64| Instant::from_nanos(us * 1_000);
        let accel = C::Move(MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, false)).encode();
        let taken = [
            (t(0), Written::Command(0x06)),
            (t(1), Written::Data(100)),
            (t(2), Written::Data(20)),
            (t(3), Written::Data(100)),
            (t(4), Written::Data(0)),
            (t(500), Written::Command(accel)),
            (t(501), Written::Data(10)),
            (t(502), Written::Data(0)),
            (t(503), Written::Data(0)),
        ];
        let judge = Judge {
            taken: taken.to_vec(),
            ..Judge::new(Straps::default())
        };
        let record = |interval_us| {
            let mut rec = Record::default();
            rec.pin(t(490), Pin::Busy, 1);
            rec.moves.push(MoveStart {
                at: t(503),
                kind: MoveKind::AccelDecel,
                dir: Direction::Cw,
                pout: true,
                steps: 11,
                first_run: 0,
                phase_index: 0,
                winding: None,
            });
            rec.push_pulses(
                t(600),
                Duration::from_micros(interval_us),
                11,
                Direction::Cw,
                true,
            );
            rec.pin(t(2_000), Pin::Busy, 0);
            rec
        };
        assert_eq!(judge.finish(&record(42)), Ok(()));
        let v = judge.finish(&record(40)).expect_err("a break");
        assert_eq!(v.invariant, "min-interval", "{v}");
        assert!(v.detail.contains("every 40.000us"), "{v}");
        // An initialization with RH = 0 is refused (error 5): it does not
        // lower the bound.
        let mut bad = taken.to_vec();
        bad.splice(
            5..5,
            [
                (t(10), Written::Command(0x06)),
                (t(11), Written::Data(100)),
                (t(12), Written::Data(0)),
                (t(13), Written::Data(100)),
                (t(14), Written::Data(0)),
            ],
        );
        let judge = Judge {
            taken: bad,
            ..Judge::new(Straps::default())
        };
        assert_eq!(
            judge.finish(&record(40)).map_err(|v| v.invariant),
            Err("min-interval")
        );
    }

    /// `init_and_step`, then a register read: command, wait, its bytes.
    fn then_read(register: u8, bytes: usize) -> Vec<BusOp> {
        let mut ops = init_and_step();
        ops.push(Command(register));
        for _ in 0..bytes {
            ops.push(Advance(Duration::from_micros(50)));
            ops.push(ReadData);
        }
        ops
    }

    fn faulty(name: &str) -> ModelConfig {
        crate::faults::find(name).expect("in the catalogue").model()
    }

    /// Section 3-4-4: a constant-speed move of 101 steps (count 100)
    /// stopped by L1;
    /// the remaining pulses read one less than the remainder. A board
    /// reading the remainder itself breaks the invariant.
    #[test]
    fn remaining_pulses_off_by_one_is_caught_at_the_third_byte() {
        use crate::protocol::{Command as C, Direction, Input as In, MoveCommand, MoveKind};
        let mut ops = init_and_step();
        let constant = C::Move(MoveCommand::new(MoveKind::Constant, Direction::Cw, false));
        ops.push(Command(constant.encode()));
        for b in [60, 100, 0, 0] {
            ops.extend([Advance(Duration::from_micros(50)), Data(b)]);
        }
        ops.push(Advance(Duration::from_millis(3)));
        ops.push(Input {
            input: In::L1,
            asserted: true,
        });
        ops.push(Advance(Duration::from_millis(5)));
        ops.push(Command(0x83));
        for _ in 0..3 {
            ops.extend([Advance(Duration::from_micros(50)), ReadData]);
        }
        assert_eq!(check(&ops, ModelConfig::default()).expect("chip"), None);
        let v = check(&ops, faulty("remaining-off-by-one"))
            .expect("chip")
            .expect("a break");
        assert_eq!((v.invariant, v.op), ("remaining-pulses", ops.len() - 1));
        assert!(v.detail.contains("after a move of 101 steps"), "{v}");
    }

    /// Section 3-4-1: the polling flag is set once per stop; a second read
    /// with no move in between must show it cleared.
    #[test]
    fn a_sticky_polling_flag_is_caught_on_the_second_read() {
        let mut ops = then_read(0x80, 1);
        ops.push(Command(0x80));
        ops.push(Advance(Duration::from_micros(50)));
        ops.push(ReadData);
        assert_eq!(check(&ops, ModelConfig::default()).expect("chip"), None);
        let v = check(&ops, faulty("finish-flag-sticky"))
            .expect("chip")
            .expect("a break");
        assert_eq!((v.invariant, v.op), ("finish-flag-once", ops.len() - 1));
    }

    /// A read command lost to a later write (IBF = 1) says nothing about
    /// the bytes that follow: stale output is not taken for its answer.
    #[test]
    fn bytes_of_a_lost_read_command_are_not_judged() {
        let mut ops = then_read(0x83, 1);
        // A remaining-pulses read, overwritten at once by a data byte: the
        // chip never takes it, and the stale bytes are not its answer.
        ops.extend([Command(0x83), Data(0), Advance(Duration::from_micros(50))]);
        ops.extend([ReadData, ReadData, ReadData]);
        let cfg = faulty("remaining-off-by-one");
        let v = check(&ops, cfg).expect("chip");
        assert_eq!(v, None);
    }

    #[test]
    fn pulses_outside_busy_are_found() {
        use crate::protocol::{Direction, PinEvent};
        let mut rec = Record::default();
        let busy = |at, value| PinEvent {
            at: Instant::from_nanos(at),
            pin: Pin::Busy,
            value,
        };
        rec.pins.push(busy(900, 1));
        rec.pins.push(busy(1_500, 0));
        rec.push_pulses(
            Instant::from_nanos(1_000),
            Duration::from_nanos(100),
            5,
            Direction::Cw,
            true,
        );
        assert_eq!(pulse_outside_busy(&rec), None);
        assert!(busy_level(&rec, Instant::from_nanos(1_000)));
        assert!(!busy_level(&rec, Instant::from_nanos(1_500)));
        // BUSY falling before the run ends.
        rec.pins[1] = busy(1_300, 0);
        assert!(pulse_outside_busy(&rec).is_some_and(|d| d.contains("fell at")));
        // A later run with BUSY at 0.
        rec.pins[1] = busy(1_500, 0);
        rec.push_pulses(
            Instant::from_nanos(2_000),
            Duration::from_nanos(100),
            1,
            Direction::Cw,
            true,
        );
        assert!(pulse_outside_busy(&rec).is_some_and(|d| d.contains("BUSY line is 0")));
    }
}

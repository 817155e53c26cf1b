//! The rules: the invariants of `docs/invariants.md` checked from what the
//! host sees of each op (the status register before and after it, the
//! bytes read) and from the capture, and what a break of one is
//! ([`Violation`]). The same rules run on the emulator's chip
//! ([`super::oracle::Checker`]) and on any target's replies
//! ([`super::replay`]).

use super::capture::{
    busy_level, phase_breaks, pulse_outside_busy, record_breaks, shortest_interval_below,
};
use super::ids::Invariant;
use crate::bus_program::BusOp;
use crate::protocol::capture::{MoveStart, OutputRecord, Pin};
use crate::protocol::{
    ClockSource, Command, FinishStatus, InitData, MoveKind, Register, Status, StatusField, Straps,
};
use crate::time::{Duration, Instant};
use std::fmt;

/// Largest number of parameter bytes any command takes (Initialization,
/// Section 3-2): the most bits 6-4 can show without an error.
const MAX_PARAMS: u8 = 4;

/// An invariant break: which invariant, after which op, and what was seen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Violation {
    /// The invariant broken; its id (`Display`) is the one of
    /// `docs/invariants.md`, e.g. `status-bit3`.
    pub invariant: Invariant,
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
/// capture (as of each op's time). The same rules run on the emulator's
/// chip ([`super::oracle::Checker`]) and on any target's replies ([`super::replay`]).
#[derive(Debug, Default)]
pub struct Rules {
    /// The board's straps: they fix the pulse clock (`min-interval`).
    straps: Straps,
    pub(super) ops: usize,
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

impl Rules {
    /// The rules for a board with these straps.
    pub fn new(straps: Straps) -> Rules {
        Rules {
            straps,
            ..Rules::default()
        }
    }

    /// Back to the start, keeping the memory of its byte lists.
    pub fn reset(&mut self) {
        let mut taken = std::mem::take(&mut self.taken);
        let mut finish_reads = std::mem::take(&mut self.finish_reads);
        taken.clear();
        finish_reads.clear();
        *self = Rules {
            taken,
            finish_reads,
            ..Rules::new(self.straps)
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
    pub fn op(&mut self, op: BusOp, seen: Seen, rec: &OutputRecord) -> Result<(), Violation> {
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
                        Invariant::BusyStatusMatches,
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
                Invariant::TimeMonotonic,
                format!("the clock went from {} back to {}", self.last_at, seen.at),
            ));
        }
        self.last_at = seen.at;
        Ok(())
    }

    /// The whole capture's invariants, once at the end (per op they would
    /// cost time quadratic in its length).
    pub fn finish(&self, rec: &OutputRecord) -> Result<(), Violation> {
        let at_end = |invariant, detail| Violation {
            invariant,
            op: self.ops.saturating_sub(1),
            detail,
        };
        if let Some(d) = pulse_outside_busy(rec) {
            return Err(at_end(Invariant::BusyCoversPulses, d));
        }
        if let Some(d) = record_breaks(rec) {
            return Err(at_end(Invariant::RecordOrdered, d));
        }
        if let Some((invariant, d)) = self.int_breaks(rec) {
            return Err(at_end(invariant, d));
        }
        if let Some(d) = phase_breaks(rec) {
            return Err(at_end(Invariant::PhasePattern, d));
        }
        if let Some(d) = self.interval_breaks(rec) {
            return Err(at_end(Invariant::MinInterval, d));
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
    fn int_breaks(&self, rec: &OutputRecord) -> Option<(Invariant, String)> {
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
                        Invariant::IntMask,
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
                        Invariant::IntRelease,
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
    fn interval_breaks(&self, rec: &OutputRecord) -> Option<String> {
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
    fn register_breaks(&mut self, rec: &OutputRecord, at: Instant) -> Option<(Invariant, String)> {
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
                        Invariant::RemainingPulses,
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
                        Invariant::FinishFlagOnce,
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

/// Section 3-1-1, Diagram 3-1: bit 3 reads 0; without an error, bits 6-4
/// count parameter bytes still due, never more than a command takes.
fn status_breaks(s: Status) -> Option<(Invariant, String)> {
    if s.reserved() {
        return Some((
            Invariant::StatusBit3,
            format!("status 0x{:02X} has bit 3 set", s.0),
        ));
    }
    match s.field() {
        StatusField::ParamsRemaining(n) if n > MAX_PARAMS => Some((
            Invariant::StatusParams,
            format!(
                "status 0x{:02X} asks for {n} more parameter bytes; no command takes more than {MAX_PARAMS}",
                s.0
            ),
        )),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::ModelConfig;
    use crate::invariants::oracle::check;
    use crate::invariants::oracle::tests::then_read;

    /// Section 3-4-1: the finish status read releases INT*; a release with
    /// no such read since INT* was asserted breaks `int-release`.
    #[test]
    fn int_released_only_by_a_finish_status_read() {
        let read = then_read(0x80, 1);
        assert_eq!(check(&read, ModelConfig::default()).expect("chip"), None);
        let mut rec = OutputRecord::default();
        rec.pin(Instant::from_nanos(1_000), Pin::Int, 1);
        rec.pin(Instant::from_nanos(5_000), Pin::Int, 0);
        let v = Rules::default().finish(&rec).expect_err("a break");
        assert_eq!(v.invariant, Invariant::IntRelease, "{v}");
        // Released after a finish status read written since the start
        // (here before INT* rose, taken after): kept.
        let judge = Rules {
            finish_reads: vec![Instant::from_nanos(500)],
            ..Rules::default()
        };
        assert_eq!(judge.finish(&rec), Ok(()));
        // A second release needs a read of its own.
        rec.pin(Instant::from_nanos(7_000), Pin::Int, 1);
        rec.pin(Instant::from_nanos(9_000), Pin::Int, 0);
        let v = judge.finish(&rec).expect_err("a break");
        assert_eq!(v.invariant, Invariant::IntRelease, "{v}");
        assert!(
            v.detail.contains("since the last release at 5.000us"),
            "{v}"
        );
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
        let judge = Rules {
            taken: taken.to_vec(),
            ..Rules::new(Straps::default())
        };
        let record = |interval_us| {
            let mut rec = OutputRecord::default();
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
        assert_eq!(v.invariant, Invariant::MinInterval, "{v}");
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
        let judge = Rules {
            taken: bad,
            ..Rules::new(Straps::default())
        };
        assert_eq!(
            judge.finish(&record(40)).map_err(|v| v.invariant),
            Err(Invariant::MinInterval)
        );
    }
}

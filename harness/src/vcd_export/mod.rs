//! Exporting a trace as a VCD waveform for GTKWave, PulseView and
//! sigrok-cli.
//!
//! One 1-bit wire per signal: `pout`, `dir`, `s1`..`s5` (energized phases,
//! as the trace records them, independent of the output logic level),
//! `int`, `hold`, `aux` (1 = asserted), `busy`, `switching` (stop switching
//! active; the chopping itself is not expanded), and `auxo0`..`auxo3`.
//! With the bus, every pin is at its level instead: `s1`..`s5` under the
//! output logic, chopped while stop switching is on (`phases.rs`).
//! There are no vectors (libsigrok's VCD reader loads a file with a vector
//! as zero samples, without a word), and a value is written only when it
//! changes, with a timestamp only where something changes. Timescale 1 ns,
//! the trace's own resolution. The initial values are at `#0`, and a last,
//! empty timestamp [`TAIL`] after the trace's end (its last event: a bus
//! access, a measurement) closes the file, so that a viewer shows the
//! whole trace and a converter that samples it (sigrok-cli, which drops
//! the changes at a file's last timestamp) keeps the last access. POUT is drawn as a
//! pulse of 1 us, or half the period when pulses come faster: the trace
//! records rising edges only, and the file's header says so, since a viewer
//! that samples coarser than the width drawn loses pulses. The file is
//! written as a stream, so a 16-million-pulse trace costs time but not
//! memory.
//!
//! With the bus ([`Export::bus`], `ppmc export --bus`), the host's side is
//! drawn too: `cs`, `rd`, `wr` (active low, 1 = high), `a0` and `d0`..`d7`,
//! one bus cycle per register access of the trace, at [`BUS_TIMING_NOTE`]'s
//! timing: what a logic analyzer on the chip's bus would record, for
//! `ppmc decode` and `ppmc judge` to read back (`docs/capture.md`).

mod phases;

use crate::protocol::{Direction, Pin, Winding};
use crate::time::{Duration, Instant};
use crate::trace::{BusEvent, EventKind, Trace};
use phases::PhasePins;
use std::io::{self, Write};
use vcd::{IdCode, TimescaleUnit, Value};

/// The wires of the export, in declaration order.
pub const SIGNALS: [&str; 16] = [
    "pout",
    "dir",
    "s1",
    "s2",
    "s3",
    "s4",
    "s5",
    "int",
    "hold",
    "aux",
    "busy",
    "switching",
    "auxo0",
    "auxo1",
    "auxo2",
    "auxo3",
];

/// The bus's wires, after [`SIGNALS`], when the export draws the bus.
pub const BUS_SIGNALS: [&str; 12] = [
    "cs", "rd", "wr", "a0", "d0", "d1", "d2", "d3", "d4", "d5", "d6", "d7",
];

/// The inputs the board drives into the chip, after the bus's wires, when
/// the export draws the bus: each at its electrical level, low while
/// asserted (the pins are active low, Section 3-3).
pub const INPUT_SIGNALS: [&str; 10] = [
    "l1", "l2", "l3", "l4", "alm", "cnp", "auxi0", "auxi1", "auxi2", "auxi3",
];

const WIRES: usize = SIGNALS.len() + BUS_SIGNALS.len() + INPUT_SIGNALS.len();
const CS: usize = SIGNALS.len();
const RD: usize = CS + 1;
const WR: usize = CS + 2;
const A0: usize = CS + 3;
const D0: usize = CS + 4;
const L1: usize = D0 + 8;

/// A bus cycle of the export, in ns: CS* falls `BUS_SETUP` before the
/// strobe, the strobe (RD* or WR*) lasts `BUS_STROBE` and rises at the
/// access's time in the trace, CS* rises `BUS_HOLD` after it; cycles that
/// share a time in the trace are laid out `BUS_CYCLE` apart, ending at it.
/// The whole file is then late by the whole microseconds the first cycles
/// need before the trace's time 0 ([`bus_lead`]).
pub const BUS_SETUP: u64 = 50;
pub const BUS_STROBE: u64 = 100;
pub const BUS_HOLD: u64 = 20;
pub const BUS_CYCLE: u64 = 200;

/// The most accesses at one time laid out before it; more end together.
const MAX_LAID_OUT: u64 = 8;

/// How far before an event a bus cycle may begin, in ns.
const LOOK_BACK: u64 = MAX_LAID_OUT * BUS_CYCLE + BUS_SETUP + BUS_STROBE;

/// The header's word on the bus's timing.
pub const BUS_TIMING_NOTE: &str = "bus: one cycle per register access: CS* low 50 ns before the strobe, RD* or WR* low for 100 ns rising at the access's time in the trace (the data held from the strobe's fall to CS* rising 20 ns after it), A0 high for the command and status registers; accesses at one time in the trace are laid out 200 ns apart, the last ending at that time. A status wait (await) is drawn as the one status read that ended it. Every pin is drawn at its level, as a logic analyzer sees it: the active-low outputs (int, aux, auxo0..auxo3) and the inputs the board drives (l1..l4, alm, cnp, auxi0..auxi3) low while asserted; s1..s5 under the output logic of the initialization, chopped edge by edge while stop switching is on. Every time in this file is the trace's plus the lead in the comment below, which makes room for the cycles at the trace's start.";

const POUT: usize = 0;
const DIR: usize = 1;
const S1: usize = 2;
const INT: usize = 7;
const HOLD: usize = 8;
const AUX: usize = 9;
const BUSY: usize = 10;
const SWITCHING: usize = 11;
const AUXO0: usize = 12;

fn bit(b: bool) -> Value {
    if b {
        Value::V1
    } else {
        Value::V0
    }
}

/// Writes `trace` as VCD to `out`.
pub fn export(trace: &Trace, out: impl Write) -> io::Result<()> {
    export_window(trace, None, out)
}

/// What an export draws.
#[derive(Debug, Clone, Copy, Default)]
pub struct Export {
    /// Only the trace from `.0` to `.1` ([`export_window`]).
    pub window: Option<(Instant, Instant)>,
    /// The host's bus too: CS*, RD*, WR*, A0, D0-D7.
    pub bus: bool,
}

/// Writes `trace` as VCD to `out`, as `what` says.
pub fn export_with(trace: &Trace, what: Export, out: impl Write) -> io::Result<()> {
    write(trace, what, out)
}

/// Writes the part of `trace` from `window.0` to `window.1` as VCD to
/// `out` (the whole trace with `None`): the signals' values at the
/// window's start come first, at its start time, and only what changes
/// within it follows, so that a failure an hour into a long move costs a
/// small file. Pulses outside the window are skipped by arithmetic, not
/// one by one.
pub fn export_window(
    trace: &Trace,
    window: Option<(Instant, Instant)>,
    out: impl Write,
) -> io::Result<()> {
    write(trace, Export { window, bus: false }, out)
}

fn write(trace: &Trace, what: Export, out: impl Write) -> io::Result<()> {
    let window = what.window;
    let mut w = vcd::Writer::new(io::BufWriter::new(out));
    w.comment(&format!(
        "ppmc trace of {} (section {})",
        trace.scenario, trace.section
    ))?;
    if let Some((from, to)) = window {
        w.comment(&format!("the trace from {from} to {to} only"))?;
    }
    w.comment(POUT_WIDTH_NOTE)?;
    let lead = if what.bus { bus_lead(trace) } else { 0 };
    if what.bus {
        w.comment(BUS_TIMING_NOTE)?;
        w.comment(&format!("lead: {lead} ns (the trace's time 0 is #{lead})"))?;
    }
    w.timescale(1, TimescaleUnit::NS)?;
    w.add_module("ppmc")?;
    let mut ids = Vec::with_capacity(WIRES);
    let (bus_names, input_names) = if what.bus {
        (&BUS_SIGNALS[..], &INPUT_SIGNALS[..])
    } else {
        (&[][..], &[][..])
    };
    for name in SIGNALS.iter().chain(bus_names).chain(input_names) {
        ids.push(w.add_wire(1, name)?);
    }
    w.upscope()?;
    w.enddefinitions()?;
    let (from, to) = window.unwrap_or((Instant::ZERO, Instant::from_nanos(u64::MAX)));
    let mut state = Emitter {
        w,
        ids,
        values: [false; WIRES],
        last_time: 0,
        lead,
        reorder: what.bus.then(std::collections::BTreeMap::new),
        seq: 0,
        from: from.as_nanos(),
        to: to.as_nanos(),
        started: false,
    };
    // An idle bus (CS*, RD* and WR* high), no input asserted; drawn as a
    // logic analyzer sees them, the active-low outputs high while not
    // asserted.
    for i in [CS, RD, WR].into_iter().chain(L1..L1 + INPUT_SIGNALS.len()) {
        state.values[i] = true;
    }
    if what.bus {
        for i in [INT, AUX].into_iter().chain(AUXO0..AUXO0 + 4) {
            state.values[i] = true;
        }
    }
    let mut pulses = Pulses::default();
    if what.bus {
        // The phases' levels where the file starts (de-energized: all
        // high in the negative logic a chip starts in).
        let pins = PhasePins::new(trace)?;
        let start = pins.levels(Instant::ZERO);
        for k in 0..5 {
            state.values[S1 + k] = start & (0b1_0000 >> k) != 0;
        }
        pulses.pins = Some(pins);
    }
    if from == Instant::ZERO {
        state.start()?;
    }
    for (k, e) in trace.events.iter().enumerate() {
        // A run's pulses come in time order with the events logged after
        // it (a stop written while it runs).
        pulses.draw_until(&mut state, e.at)?;
        if let Some(pins) = &mut pulses.pins {
            pins.chop_until(&mut state, e.at)?;
            // The model takes an access where the file's strobe ends.
            let (at, bus) = match &e.kind {
                EventKind::Bus(b) if bus_cycle(b).is_some() => {
                    let early = laid_before(trace, k) * BUS_CYCLE;
                    (
                        Instant::from_nanos(e.at.as_nanos().saturating_sub(early)),
                        Some(b),
                    )
                }
                EventKind::Bus(b) => (e.at, Some(b)),
                _ => (e.at, None),
            };
            pins.event(&mut state, at, bus)?;
        }
        state.drain_before((e.at.as_nanos() + state.lead).saturating_sub(LOOK_BACK))?;
        match &e.kind {
            EventKind::Move {
                dir,
                winding: wd,
                phase: p,
                ..
            } => {
                pulses.draw_until(&mut state, Instant::from_nanos(u64::MAX))?;
                state.flush_before(&mut pulses.pending_fall, e.at)?;
                pulses.winding = *wd;
                pulses.dir = Some(*dir);
                pulses.phase = *p;
                state.set(e.at, DIR, *dir == Direction::Ccw)?;
            }
            EventKind::Pulses { dir, count, .. } => {
                let Some(run) = e.pulse_run() else { continue };
                // A run still being drawn ends before this one starts.
                pulses.draw_until(&mut state, Instant::from_nanos(u64::MAX))?;
                let width = if *count > 1 {
                    Duration::from_micros(1)
                        .min(Duration::from_nanos(run.interval().as_nanos() / 2))
                } else {
                    Duration::from_micros(1)
                };
                // The pulses in the window (and the one whose fall may
                // cross into it): the phases advance over the rest at once.
                let early = Instant::from_nanos(from.as_nanos().saturating_sub(width.as_nanos()));
                let first_in = first_at_or_after(&run, *count, early);
                let late = Instant::from_nanos(to.as_nanos().saturating_add(1));
                let past = first_at_or_after(&run, *count, late).max(first_in);
                if first_in > 0 {
                    if let Some(wd) = pulses.winding {
                        let step = pulses.dir.unwrap_or(*dir);
                        pulses.phase = wd.advance(pulses.phase, step, u64::from(first_in));
                    }
                }
                pulses.run = Some(RunDrawing {
                    run,
                    dir: *dir,
                    next: first_in,
                    past,
                    width,
                });
            }
            EventKind::Pin { pin, value } => {
                state.flush_before(&mut pulses.pending_fall, e.at)?;
                let v = *value != 0;
                match pin {
                    Pin::Busy => state.set(e.at, BUSY, v)?,
                    // As a logic analyzer sees them, the active-low
                    // outputs are low while asserted.
                    Pin::Int => state.set(e.at, INT, v != what.bus)?,
                    Pin::Hold => state.set(e.at, HOLD, v)?,
                    Pin::Aux => state.set(e.at, AUX, v != what.bus)?,
                    Pin::Switching => {
                        state.set(e.at, SWITCHING, v)?;
                        if let Some(pins) = &mut pulses.pins {
                            pins.switching(&mut state, e.at, v)?;
                        }
                    }
                    Pin::Dir => state.set(e.at, DIR, v)?,
                    Pin::Phases => match &mut pulses.pins {
                        Some(pins) => pins.pattern(&mut state, e.at, *value)?,
                        None => state.set_bits(e.at, S1, 5, *value)?,
                    },
                    // auxo0 is bit 0.
                    Pin::Auxo => {
                        for k in 0..4 {
                            state.set(e.at, AUXO0 + k, (value & (1 << k) != 0) != what.bus)?;
                        }
                    }
                }
            }
            EventKind::Bus(BusEvent::SetInput { input, asserted }) => {
                if what.bus {
                    state.set(e.at, L1 + usize::from(input.index()), !asserted)?;
                }
            }
            EventKind::Bus(b) => {
                let Some((read, a0, byte)) = bus_cycle(b) else {
                    continue;
                };
                let end = (e.at.as_nanos() + state.lead)
                    .saturating_sub(laid_before(trace, k) * BUS_CYCLE);
                let strobe = if read { RD } else { WR };
                let setup = end.saturating_sub(BUS_SETUP + BUS_STROBE);
                let fall = end.saturating_sub(BUS_STROBE);
                state.set_file(setup, CS, false)?;
                state.set_file(setup, A0, a0)?;
                state.set_file(fall, strobe, false)?;
                for i in 0..8 {
                    state.set_file(fall, D0 + i, byte >> i & 1 == 1)?;
                }
                state.set_file(end, strobe, true)?;
                state.set_file(end + BUS_HOLD, CS, true)?;
            }
            EventKind::Measure { .. } => {}
        }
    }
    pulses.draw_until(&mut state, Instant::from_nanos(u64::MAX))?;
    if let Some(f) = pulses.pending_fall.take() {
        state.set(f, POUT, false)?;
    }
    // The trace's end (or the window's), where nothing changes.
    let end = trace
        .events
        .iter()
        .map(|e| e.at.as_nanos())
        .max()
        .unwrap_or(0);
    if let Some(pins) = &mut pulses.pins {
        let last = Instant::from_nanos(end.min(state.to));
        pins.chop_until(&mut state, last)?;
    }
    state.drain_before(u64::MAX)?;
    let end = end.min(state.to).max(state.from);
    if !state.started {
        state.start()?;
    }
    let end = end.max(state.last_time.saturating_sub(state.lead)) + state.lead + TAIL;
    state.w.timestamp(end)?;
    state.w.flush()
}

/// How long the file goes on after the trace's last event (and its last
/// change), in ns: a sampling converter keeps every change before it.
pub const TAIL: u64 = 1_000;

/// How many bus cycles before its time in the trace the access of event
/// `k` is laid out: one for each access after it at the same time (they
/// come first), at most [`MAX_LAID_OUT`].
fn laid_before(trace: &Trace, k: usize) -> u64 {
    let at = trace.events[k].at;
    let later = trace.events[k + 1..]
        .iter()
        .take_while(|n| n.at == at)
        .filter(|n| matches!(&n.kind, EventKind::Bus(nb) if bus_cycle(nb).is_some()))
        .count() as u64;
    later.min(MAX_LAID_OUT)
}

/// How late the bus export writes every time, in ns: the whole
/// microseconds that the cycles laid out before the earliest accesses
/// need (three accesses at the trace's time 0 need 600 ns, and CS*
/// falls 150 ns before the first strobe ends: 1 us).
pub fn bus_lead(trace: &Trace) -> u64 {
    let mut need = 0u64;
    let mut group: Option<(Instant, u64)> = None;
    for e in &trace.events {
        let EventKind::Bus(b) = &e.kind else { continue };
        if bus_cycle(b).is_none() {
            continue;
        }
        let n = match group {
            Some((t, n)) if t == e.at => n + 1,
            _ => 1,
        };
        group = Some((e.at, n));
        let before = (n - 1).min(MAX_LAID_OUT) * BUS_CYCLE + BUS_SETUP + BUS_STROBE;
        need = need.max(before.saturating_sub(e.at.as_nanos()));
    }
    need.div_ceil(1000) * 1000
}

/// The bus cycle a bus event is drawn as: a read or not, A0, the byte on
/// D0-D7. `None` for what puts no cycle on the bus (a write or read that
/// timed out, an input driven, a reset).
fn bus_cycle(b: &BusEvent) -> Option<(bool, bool, u8)> {
    Some(match *b {
        BusEvent::WriteCommand { byte, .. } => (false, true, byte),
        BusEvent::WriteData { byte, .. } => (false, false, byte),
        BusEvent::ReadStatus(s) => (true, true, s),
        BusEvent::ReadData { byte, .. } => (true, false, byte),
        BusEvent::Await { status, .. } => (true, true, status),
        _ => return None,
    })
}

/// The run of pulses being drawn, and the phase outputs it steps.
#[derive(Default)]
struct Pulses {
    run: Option<RunDrawing>,
    winding: Option<Winding>,
    phase: u32,
    /// The move's direction, which the phases step in (a run's is DIR's
    /// as the capture saw it, which a miswired DIR line inverts).
    dir: Option<Direction>,
    /// S1..S5 at their levels (with the bus).
    pins: Option<PhasePins>,
    /// The falling edge of the last pulse drawn, not yet written.
    pending_fall: Option<Instant>,
}

struct RunDrawing {
    run: crate::protocol::PulseRun,
    dir: Direction,
    /// The next pulse to draw, and the first past the window.
    next: u32,
    past: u32,
    width: Duration,
}

impl Pulses {
    /// Draws the run's pulses before `until` (all of them, and the phase
    /// steps of those past the window, once it is done).
    fn draw_until<W: Write>(&mut self, state: &mut Emitter<W>, until: Instant) -> io::Result<()> {
        let Some(r) = &mut self.run else {
            return Ok(());
        };
        while r.next < r.past {
            let t = r.run.at(r.next);
            if t >= until {
                return Ok(());
            }
            state.drain_before((t.as_nanos() + state.lead).saturating_sub(LOOK_BACK))?;
            state.flush_before(&mut self.pending_fall, t)?;
            state.set(t, POUT, true)?;
            if let Some(wd) = self.winding {
                self.phase = wd.advance(self.phase, self.dir.unwrap_or(r.dir), 1);
                match &mut self.pins {
                    Some(pins) => pins.pattern(state, t, wd.pattern(self.phase))?,
                    None => state.set_bits(t, S1, 5, wd.pattern(self.phase))?,
                }
            }
            self.pending_fall = Some(t + r.width.max(Duration::from_nanos(1)));
            r.next += 1;
        }
        if r.past < r.run.count {
            if let Some(wd) = self.winding {
                let step = self.dir.unwrap_or(r.dir);
                self.phase = wd.advance(self.phase, step, u64::from(r.run.count - r.past));
            }
        }
        self.run = None;
        Ok(())
    }
}

/// The first pulse of `run` (of `count`) at or after `t`: `count` if none.
fn first_at_or_after(run: &crate::protocol::PulseRun, count: u32, t: Instant) -> u32 {
    let (mut lo, mut hi) = (0u32, count);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if run.at(mid) < t {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The header's word on how POUT is drawn.
pub const POUT_WIDTH_NOTE: &str = "pout: the trace records each pulse's rising edge; each is drawn 1 us wide (half the period when pulses come faster). A viewer sampling coarser than that width loses pulses: count them at the trace's timescale (1 ns).";

struct Emitter<W: Write> {
    w: vcd::Writer<W>,
    ids: Vec<IdCode>,
    /// Every wire's value as last written.
    values: [bool; WIRES],
    /// The last timestamp written (the window's start is the `$dumpvars`
    /// block's).
    last_time: u64,
    /// What every time of the trace is written late by, in ns.
    lead: u64,
    /// With the bus, changes wait here in time order (file time, order of
    /// arrival) until nothing earlier can come: a bus cycle is laid out
    /// before the access it ends at.
    reorder: Option<std::collections::BTreeMap<(u64, u64), (usize, bool)>>,
    seq: u64,
    /// The window, in ns: changes before `from` only set the values the
    /// `$dumpvars` block starts with; changes after `to` are not written.
    from: u64,
    to: u64,
    /// The `$dumpvars` block is written.
    started: bool,
}

impl<W: Write> Emitter<W> {
    /// Writes a pending POUT falling edge if it comes before `t`.
    fn flush_before(&mut self, pending: &mut Option<Instant>, t: Instant) -> io::Result<()> {
        if let Some(f) = *pending {
            if f <= t {
                *pending = None;
                self.set(f, POUT, false)?;
            }
        }
        Ok(())
    }

    /// The window's start: every wire's value as it stands, at its time.
    fn start(&mut self) -> io::Result<()> {
        self.started = true;
        self.last_time = self.from;
        self.w.timestamp(self.from)?;
        self.w.begin(vcd::SimulationCommand::Dumpvars)?;
        for (id, v) in self.ids.iter().zip(self.values) {
            self.w.change_scalar(*id, bit(v))?;
        }
        self.w.end()
    }

    /// Sets wire `i` at `at` (the trace's time).
    fn set(&mut self, at: Instant, i: usize, v: bool) -> io::Result<()> {
        self.set_file(at.as_nanos() + self.lead, i, v)
    }

    /// Sets wire `i` at `t`, the file's time: at once, or through the
    /// reorder buffer when there is one.
    fn set_file(&mut self, t: u64, i: usize, v: bool) -> io::Result<()> {
        if let Some(q) = &mut self.reorder {
            self.seq += 1;
            q.insert((t, self.seq), (i, v));
            return Ok(());
        }
        self.write(t, i, v)
    }

    /// Writes the buffered changes before `t` (the file's time).
    fn drain_before(&mut self, t: u64) -> io::Result<()> {
        let Some(mut q) = self.reorder.take() else {
            return Ok(());
        };
        let mut result = Ok(());
        while let Some(entry) = q.first_entry() {
            if entry.key().0 >= t {
                break;
            }
            let ((at, _), (i, v)) = entry.remove_entry();
            result = self.write(at, i, v);
            if result.is_err() {
                break;
            }
        }
        self.reorder = Some(q);
        result
    }

    /// Writes wire `i`'s value at `t`, the file's time: nothing unless it
    /// changes.
    fn write(&mut self, t: u64, i: usize, v: bool) -> io::Result<()> {
        if i >= self.ids.len() || self.values[i] == v {
            return Ok(());
        }
        let trace_t = t.saturating_sub(self.lead);
        if trace_t < self.from {
            self.values[i] = v;
            return Ok(());
        }
        if trace_t > self.to {
            return Ok(());
        }
        if !self.started {
            self.start()?;
        }
        if t > self.last_time {
            self.w.timestamp(t)?;
            self.last_time = t;
        }
        self.values[i] = v;
        self.w.change_scalar(self.ids[i], bit(v))
    }

    /// Sets the `n` wires from `first` to a pattern whose most significant
    /// of `n` bits is the first wire (the phases: bit 4 is S1).
    fn set_bits(&mut self, at: Instant, first: usize, n: usize, pattern: u8) -> io::Result<()> {
        for k in 0..n {
            self.set(at, first + k, pattern & (1 << (n - 1 - k)) != 0)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::Trace;
    use vcd::{Command, Parser};

    const TRACE: &str = "ppmc-trace 1
scenario demo
section 3-3-3
target emu
detail sysclk_hz 16000000
detail csel high
detail vsel high
detail ext_clock_hz none
events
0.000us reset
68.000us pin s 0b11000
100.000us move accel-decel ccw steps=3 pout=0 winding=4ph-2 phase=0
160.000us pin busy 1
300.000us pulses ccw n=3 dt=50.000us
426.000us pin busy 0
426.000us pin int 1
500.000us pin auxo 0b0101
600.000us rs 0x00
end
";

    /// Rising POUT edges and the last value of each wire, from a VCD.
    fn rises_and_last(buf: &[u8]) -> (Vec<u64>, std::collections::BTreeMap<String, bool>) {
        let mut parser = Parser::new(buf);
        let header = parser.parse_header().expect("VCD header parses");
        let names: std::collections::HashMap<IdCode, String> = SIGNALS
            .iter()
            .map(|n| {
                (
                    header.find_var(&["ppmc", n]).expect("declared").code,
                    n.to_string(),
                )
            })
            .collect();
        let (mut now, mut rises, mut last) = (0, Vec::new(), std::collections::BTreeMap::new());
        for cmd in parser {
            match cmd.expect("VCD body parses") {
                Command::Timestamp(t) => now = t,
                Command::ChangeScalar(i, v) => {
                    let name = names[&i].clone();
                    if name == "pout" && v == Value::V1 {
                        rises.push(now);
                    }
                    last.insert(name, v == Value::V1);
                }
                _ => {}
            }
        }
        (rises, last)
    }

    const LONG: &str = "ppmc-trace 1
scenario long
section 3-3-3
target emu
detail sysclk_hz 16000000
detail csel high
detail vsel high
detail ext_clock_hz none
events
0.000us reset
100.000us move accel-decel cw steps=16777216 pout=0 winding=4ph-2 phase=0
1000.000us pulses cw n=16777216 dt=10.000us
167773150.000us rs 0x00
end
";

    #[test]
    fn a_window_of_a_long_move_is_small_and_has_the_pulses_and_phases_of_the_whole() {
        // Issue 29: a failure in the 16,777,216-step move once wrote a VCD
        // of some 650 MB. A millisecond around a time five seconds in: its
        // hundred pulses, each where the whole trace has it.
        let trace = Trace::parse(LONG).expect("valid");
        let (from, to) = (
            Instant::from_nanos(5_001_000_000),
            Instant::from_nanos(5_002_000_000),
        );
        let mut buf = Vec::new();
        export_window(&trace, Some((from, to)), &mut buf).expect("export");
        assert!(buf.len() < 20_000, "{} bytes", buf.len());
        let (rises, _) = rises_and_last(&buf);
        let want: Vec<u64> = (0..16_777_216u64)
            .map(|k| 1_000_000 + 10_000 * k)
            .skip_while(|t| *t + 1_000 < from.as_nanos())
            .take_while(|t| *t <= to.as_nanos())
            .collect();
        assert_eq!(rises, want);
        // The phases at a window's end are the whole trace's at that time:
        // a short move, whole and in a window that ends with it.
        let short = LONG.replace("16777216", "1003");
        let trace = Trace::parse(&short).expect("valid");
        let mut whole = Vec::new();
        export(&trace, &mut whole).expect("export");
        let mut part = Vec::new();
        let end = Instant::from_nanos(1_000_000 + 10_000 * 1_002 + 5_000);
        export_window(
            &trace,
            Some((Instant::from_nanos(9_000_000), end)),
            &mut part,
        )
        .expect("export");
        let (whole_rises, whole_last) = rises_and_last(&whole);
        let (part_rises, part_last) = rises_and_last(&part);
        assert_eq!(whole_rises.len(), 1003);
        assert_eq!(part_rises, whole_rises[800..].to_vec());
        for s in ["s1", "s2", "s3", "s4", "s5", "dir"] {
            assert_eq!(part_last[s], whole_last[s], "{s} at the end");
        }
    }

    #[test]
    fn export_parses_back_with_every_pulse_and_pin() {
        let trace = Trace::parse(TRACE).expect("valid");
        let mut buf = Vec::new();
        export(&trace, &mut buf).expect("export");
        let mut parser = Parser::new(&buf[..]);
        let header = parser.parse_header().expect("VCD header parses");
        let id = |name: &str| header.find_var(&["ppmc", name]).expect("declared").code;
        let (pout, busy, s1, s4, dir) = (id("pout"), id("busy"), id("s1"), id("s4"), id("dir"));
        let auxo: Vec<IdCode> = (0..4).map(|k| id(&format!("auxo{k}"))).collect();
        let mut now = 0u64;
        let mut rises = Vec::new();
        let mut busy_changes = Vec::new();
        let mut last_s = (0, 0);
        let mut dir_high = false;
        let mut auxo_seen = [false; 4];
        // Every value written is a change, and every timestamp has one but
        // the last, the trace's end. The initial values are at #0.
        let mut values = std::collections::HashMap::new();
        let mut changes_since_timestamp = 1;
        let mut stamps = Vec::new();
        for cmd in parser {
            let cmd = cmd.expect("VCD body parses");
            match cmd {
                Command::Timestamp(t) => {
                    assert!(
                        changes_since_timestamp > 0 || stamps == [0],
                        "an empty timestamp before #{t}"
                    );
                    changes_since_timestamp = 0;
                    now = t;
                    stamps.push(t);
                }
                Command::ChangeScalar(i, v) => {
                    changes_since_timestamp += 1;
                    assert_ne!(
                        values.insert(i, v),
                        Some(v),
                        "{i} rewritten unchanged at {now}"
                    );
                }
                Command::ChangeVector(..) => panic!("a vector in the export"),
                _ => {}
            }
            match cmd {
                Command::ChangeScalar(i, Value::V1) if i == pout => rises.push(now),
                Command::ChangeScalar(i, v) if i == busy => busy_changes.push((now, v)),
                Command::ChangeScalar(i, v) if i == s1 => last_s.0 = u8::from(v == Value::V1),
                Command::ChangeScalar(i, v) if i == s4 => last_s.1 = u8::from(v == Value::V1),
                Command::ChangeScalar(i, Value::V1) if i == dir => dir_high = true,
                Command::ChangeScalar(i, v) => {
                    if let Some(k) = auxo.iter().position(|a| *a == i) {
                        auxo_seen[k] = v == Value::V1;
                    }
                }
                _ => {}
            }
        }
        assert_eq!(stamps.first(), Some(&0), "the initial values at #0");
        assert_eq!(changes_since_timestamp, 0, "a last, empty timestamp");
        assert_eq!(
            now,
            600_000 + TAIL,
            "the trace's end: its last event, and the tail"
        );
        let text = String::from_utf8(buf.clone()).expect("utf-8");
        assert!(
            text.contains(POUT_WIDTH_NOTE),
            "the header says how POUT is drawn"
        );
        assert!(
            text.contains("$enddefinitions $end\n#0\n$dumpvars"),
            "{text}"
        );
        assert_eq!(rises, vec![300_000, 350_000, 400_000]);
        assert_eq!(
            busy_changes,
            vec![(0, Value::V0), (160_000, Value::V1), (426_000, Value::V0)]
        );
        // Three CCW steps from S1S2 end at S2S3... index 1: S2 S3, so S1 = 0, S4 = 0.
        assert_eq!(last_s, (0, 0));
        assert!(dir_high, "DIR shows CCW");
        // 0b0101: AUXO0 and AUXO2.
        assert_eq!(auxo_seen, [true, false, true, false]);
    }

    /// What the trace logs after a run of pulses began, while it runs (a
    /// Decelerating Stop written, 3-3-2; a limit asserted, 3-3-6), is
    /// drawn at its own time, among the run's pulses; the inputs and the
    /// active-low outputs at their level, low while asserted.
    #[test]
    fn what_happens_during_a_run_is_drawn_at_its_time() {
        let text = "ppmc-trace 1
scenario during
section 3-3-2
target emu
detail sysclk_hz 16000000
detail csel high
detail vsel high
detail ext_clock_hz none
events
0.000us reset
100.000us move constant cw steps=100 pout=0 winding=4ph-2 phase=0
300.000us pulses cw n=100 dt=50.000us
2000.000us wc 0x41 waited=0.000us
3000.000us set l1 on
5300.000us pin int 1
end
";
        let trace = Trace::parse(text).expect("trace");
        let mut buf = Vec::new();
        let what = Export {
            window: None,
            bus: true,
        };
        export_with(&trace, what, &mut buf).expect("export");
        let lead = bus_lead(&trace);
        let mut parser = Parser::new(&buf[..]);
        let header = parser.parse_header().expect("header");
        let code = |n: &str| header.find_var(&["ppmc", n]).expect("declared").code;
        let (wr, l1, int, pout) = (code("wr"), code("l1"), code("int"), code("pout"));
        let (mut now, mut last) = (0u64, 0u64);
        let mut seen = Vec::new();
        let mut rises_before_wr = 0;
        let at = |us: u64| us * 1000 + lead;
        for cmd in parser {
            match cmd.expect("body") {
                Command::Timestamp(t) => {
                    assert!(t >= last, "time goes back: {t} after {last}");
                    (now, last) = (t, t);
                }
                Command::ChangeScalar(id, v) if id == wr || id == l1 || id == int => {
                    seen.push((now, id, v));
                }
                Command::ChangeScalar(id, Value::V1) if id == pout && now < at(2000) => {
                    rises_before_wr += 1;
                }
                _ => {}
            }
        }
        // Idle: WR*, L1* and INT* high.
        let start: Vec<_> = seen.iter().filter(|s| s.0 == 0).map(|s| s.2).collect();
        assert_eq!(start, [Value::V1; 3]);
        let changes: Vec<_> = seen.into_iter().filter(|s| s.0 > 0).collect();
        assert_eq!(
            changes,
            [
                (at(2000) - BUS_STROBE, wr, Value::V0),
                (at(2000), wr, Value::V1),
                (at(3000), l1, Value::V0),
                (at(5300), int, Value::V0),
            ]
        );
        // The pulses from 300 us, 50 us apart, before the write at 2000 us.
        assert_eq!(rises_before_wr, 34);
    }

    /// The bus as a logic analyzer would record it: decoded back (Table
    /// 3-1) it gives every access of the trace, its byte and its time (the
    /// last of those at one time ending at it, all late by the lead).
    /// Section 3-2-1 (N36): with the bus, S1..S5 are drawn at their
    /// levels. Before the first initialization the phases are de-energized
    /// in negative logic, all high from the file's start, however late the
    /// lead makes the trace's time 0; energized S1 and S2 go low.
    #[test]
    fn the_bus_export_draws_the_phases_at_their_levels_from_the_start() {
        let text = "ppmc-trace 1
scenario levels
section 3-2-1
target emu
detail sysclk_hz 16000000
detail csel high
detail vsel high
detail ext_clock_hz none
events
0.000us reset
0.000us await busy=0 after 0.000us status=0x00
0.000us await ibf=0 after 0.000us status=0x00
0.000us wc 0x02 waited=0.000us
6.000us wd 0x64 waited=6.000us
12.000us wd 0x14 waited=6.000us
18.000us wd 0x64 waited=6.000us
24.000us wd 0x00 waited=6.000us
68.000us pin s 0b11000
100.000us rs 0x00
end
";
        let trace = Trace::parse(text).expect("trace");
        let mut buf = Vec::new();
        let what = Export {
            window: None,
            bus: true,
        };
        export_with(&trace, what, &mut buf).expect("export");
        assert_eq!(bus_lead(&trace), 1000);
        let mut parser = Parser::new(&buf[..]);
        let header = parser.parse_header().expect("header");
        let phases: Vec<IdCode> = ["s1", "s2", "s3", "s4", "s5"]
            .iter()
            .map(|n| header.find_var(&["ppmc", n]).expect("declared").code)
            .collect();
        let (mut now, mut levels) = (0u64, Vec::new());
        for cmd in parser {
            match cmd.expect("body") {
                Command::Timestamp(t) => now = t,
                Command::ChangeScalar(id, v) => {
                    if let Some(k) = phases.iter().position(|p| *p == id) {
                        levels.push((now, k + 1, v == Value::V1));
                    }
                }
                _ => {}
            }
        }
        let at_start: Vec<bool> = levels.iter().filter(|l| l.0 == 0).map(|l| l.2).collect();
        assert_eq!(at_start, [true; 5], "{levels:?}");
        let later: Vec<(u64, usize, bool)> = levels.into_iter().filter(|l| l.0 > 0).collect();
        assert_eq!(later, [(69_000, 1, false), (69_000, 2, false)]);
    }

    #[test]
    fn the_bus_export_decodes_to_the_traces_accesses() {
        use ppmc_logic::decode::{Access, BusDecoder};
        use ppmc_logic::map::BusChannels;
        use ppmc_logic::source::{Change, LogicInfo};
        let text = "ppmc-trace 1
scenario bus
section 3-1
target emu
detail sysclk_hz 16000000
detail csel high
detail vsel high
detail ext_clock_hz none
events
0.000us reset
0.000us await busy=0 after 0.000us status=0x00
0.000us await ibf=0 after 0.000us status=0x00
0.000us wc 0x02 waited=0.000us
6.000us wd 0x64 waited=6.000us
68.000us pin s 0b11000
90.000us pin hold 1
90.000us rs 0x80
95.000us rd 0x5a waited=1.000us
end
";
        let trace = Trace::parse(text).expect("trace");
        let mut buf = Vec::new();
        export_with(
            &trace,
            Export {
                window: None,
                bus: true,
            },
            &mut buf,
        )
        .expect("export");
        let lead = bus_lead(&trace);
        assert_eq!(lead, 1000);
        let mut parser = Parser::new(&buf[..]);
        let header = parser.parse_header().expect("header");
        let code = |n: &str| header.find_var(&["ppmc", n]).expect("declared").code;
        let wires: Vec<IdCode> = BUS_SIGNALS.iter().map(|n| code(n)).collect();
        let info = LogicInfo {
            channels: BUS_SIGNALS.iter().map(|n| n.to_string()).collect(),
            resolution_ps: 1000,
            sample_rate_hz: None,
            format: "test".into(),
        };
        let bus = BusChannels {
            cs: 0,
            rd: 1,
            wr: 2,
            a0: 3,
            d: [4, 5, 6, 7, 8, 9, 10, 11],
        };
        let mut dec = BusDecoder::new(bus, &info, 20_000);
        let (mut now, mut levels, mut got) = (0u64, 0u64, Vec::new());
        let mut pending = false;
        for cmd in parser {
            match cmd.expect("body") {
                Command::Timestamp(t) => {
                    if pending {
                        got.extend(dec.push(Change {
                            time_ps: now * 1000,
                            levels,
                            unknown: 0,
                        }));
                        pending = false;
                    }
                    now = t;
                }
                Command::ChangeScalar(id, v) => {
                    if let Some(k) = wires.iter().position(|w| *w == id) {
                        levels = (levels & !(1 << k)) | (u64::from(v == Value::V1) << k);
                        pending = true;
                    }
                }
                _ => {}
            }
        }
        if pending {
            got.extend(dec.push(Change {
                time_ps: now * 1000,
                levels,
                unknown: 0,
            }));
        }
        let want: Vec<(Access, u8, u64)> = vec![
            (Access::ReadStatus, 0x00, 600),
            (Access::ReadStatus, 0x00, 800),
            (Access::WriteCommand, 0x02, 1000),
            (Access::WriteData, 0x64, 7000),
            (Access::ReadStatus, 0x80, 91_000),
            (Access::ReadData, 0x5A, 96_000),
        ];
        let got: Vec<(Access, u8, u64)> = got
            .iter()
            .map(|t| (t.access, t.byte, t.end_ps / 1000))
            .collect();
        assert_eq!(got, want);
        assert_eq!(dec.summary().one_sample, 0);
        // Without the bus, the bus wires are not there.
        let mut plain = Vec::new();
        export(&trace, &mut plain).expect("export");
        let plain = String::from_utf8(plain).expect("text");
        assert!(!plain.contains(" cs $end"), "{plain}");
    }
}

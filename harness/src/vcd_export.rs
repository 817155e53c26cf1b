//! Exporting a trace as a VCD waveform for GTKWave or PulseView.
//!
//! One wire per signal: `pout`, `dir`, `s1`..`s5` (energized phases, as the
//! trace records them, independent of the output logic level), `int`,
//! `hold`, `aux` (1 = asserted), `busy`, `switching` (stop switching active;
//! the chopping itself is not expanded), and `auxo` as a 4-bit vector.
//! Timescale 1 ns, the trace's own resolution. POUT is drawn as a pulse of
//! 1 us, or half the period when pulses come faster. The file is written as
//! a stream, so a 16-million-pulse trace costs time but not memory.

use crate::protocol::{Direction, Pin, Winding};
use crate::time::{Duration, Instant};
use crate::trace::{EventKind, Trace};
use std::io::{self, Write};
use vcd::{IdCode, TimescaleUnit, Value};

/// The wires of the export, in declaration order.
pub const SIGNALS: [&str; 13] = [
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
    "auxo",
];

/// A change to emit at a time.
#[derive(Debug, Clone, Copy)]
enum Change {
    Pout(bool),
    Dir(bool),
    Phases(u8),
    Wire(usize, bool),
    Auxo(u8),
}

struct Ids {
    wires: Vec<IdCode>,
}

impl Ids {
    fn get(&self, name: &str) -> IdCode {
        let i = SIGNALS.iter().position(|s| *s == name).unwrap_or(0);
        self.wires[i]
    }
}

fn bit(b: bool) -> Value {
    if b {
        Value::V1
    } else {
        Value::V0
    }
}

/// Writes `trace` as VCD to `out`.
pub fn export(trace: &Trace, out: impl Write) -> io::Result<()> {
    let mut w = vcd::Writer::new(io::BufWriter::new(out));
    w.comment(&format!(
        "ppmc trace of {} (section {})",
        trace.scenario, trace.section
    ))?;
    w.timescale(1, TimescaleUnit::NS)?;
    w.add_module("ppmc")?;
    let mut wires = Vec::new();
    for name in SIGNALS {
        let width = if name == "auxo" { 4 } else { 1 };
        wires.push(w.add_wire(width, name)?);
    }
    let ids = Ids { wires };
    w.upscope()?;
    w.enddefinitions()?;
    w.begin(vcd::SimulationCommand::Dumpvars)?;
    for name in SIGNALS {
        if name == "auxo" {
            w.change_vector(ids.get(name), [Value::V0; 4])?;
        } else {
            w.change_scalar(ids.get(name), Value::V0)?;
        }
    }
    w.end()?;

    let mut state = Emitter {
        w,
        ids,
        last_time: None,
    };
    let mut winding: Option<Winding> = None;
    let mut phase: u32 = 0;
    let mut dir_bit = false;
    // Falling edge of the last POUT, not yet written.
    let mut pending_fall: Option<Instant> = None;
    for e in &trace.events {
        match &e.kind {
            EventKind::Move {
                dir,
                winding: wd,
                phase: p,
                ..
            } => {
                state.flush_before(&mut pending_fall, e.at)?;
                winding = *wd;
                phase = *p;
                let b = *dir == Direction::Ccw;
                if b != dir_bit {
                    dir_bit = b;
                    state.emit(e.at, Change::Dir(b))?;
                }
            }
            EventKind::Pulses {
                dir,
                count,
                interval,
            } => {
                let width = if *count > 1 {
                    Duration::from_micros(1).min(Duration::from_nanos(interval.as_nanos() / 2))
                } else {
                    Duration::from_micros(1)
                };
                for i in 0..*count {
                    let t = e.at + interval.saturating_mul(u64::from(i));
                    state.flush_before(&mut pending_fall, t)?;
                    state.emit(t, Change::Pout(true))?;
                    if let Some(wd) = winding {
                        phase = wd.advance(phase, *dir, 1);
                        state.emit(t, Change::Phases(wd.pattern(phase)))?;
                    }
                    pending_fall = Some(t + width.max(Duration::from_nanos(1)));
                }
            }
            EventKind::Pin { pin, value } => {
                state.flush_before(&mut pending_fall, e.at)?;
                let v = *value != 0;
                let change = match pin {
                    Pin::Busy => Change::Wire(10, v),
                    Pin::Int => Change::Wire(7, v),
                    Pin::Hold => Change::Wire(8, v),
                    Pin::Aux => Change::Wire(9, v),
                    Pin::Switching => Change::Wire(11, v),
                    Pin::Dir => {
                        dir_bit = v;
                        Change::Dir(v)
                    }
                    Pin::Phases => Change::Phases(*value),
                    Pin::Auxo => Change::Auxo(*value),
                };
                state.emit(e.at, change)?;
            }
            EventKind::Bus(_) | EventKind::Measure { .. } => {}
        }
    }
    if let Some(f) = pending_fall.take() {
        state.emit(f, Change::Pout(false))?;
    }
    state.w.flush()
}

struct Emitter<W: Write> {
    w: vcd::Writer<W>,
    ids: Ids,
    last_time: Option<u64>,
}

impl<W: Write> Emitter<W> {
    /// Writes a pending POUT falling edge if it comes before `t`.
    fn flush_before(&mut self, pending: &mut Option<Instant>, t: Instant) -> io::Result<()> {
        if let Some(f) = *pending {
            if f <= t {
                *pending = None;
                self.emit(f, Change::Pout(false))?;
            }
        }
        Ok(())
    }

    fn emit(&mut self, at: Instant, c: Change) -> io::Result<()> {
        let t = at.as_nanos();
        if self.last_time.is_none_or(|l| t > l) {
            self.w.timestamp(t)?;
            self.last_time = Some(t);
        }
        match c {
            Change::Pout(b) => self.w.change_scalar(self.ids.get("pout"), bit(b)),
            Change::Dir(b) => self.w.change_scalar(self.ids.get("dir"), bit(b)),
            Change::Wire(i, b) => self.w.change_scalar(self.ids.wires[i], bit(b)),
            Change::Phases(p) => {
                for (k, name) in ["s1", "s2", "s3", "s4", "s5"].iter().enumerate() {
                    let on = p & (0b1_0000 >> k) != 0;
                    self.w.change_scalar(self.ids.get(name), bit(on))?;
                }
                Ok(())
            }
            Change::Auxo(v) => {
                let bits = (0..4).rev().map(|k| bit(v & (1 << k) != 0));
                self.w.change_vector(self.ids.get("auxo"), bits)
            }
        }
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
end
";

    #[test]
    fn export_parses_back_with_every_pulse_and_pin() {
        let trace = Trace::parse(TRACE).expect("valid");
        let mut buf = Vec::new();
        export(&trace, &mut buf).expect("export");
        let mut parser = Parser::new(&buf[..]);
        let header = parser.parse_header().expect("VCD header parses");
        let id = |name: &str| header.find_var(&["ppmc", name]).expect("declared").code;
        let (pout, busy, s1, s4, dir, auxo) = (
            id("pout"),
            id("busy"),
            id("s1"),
            id("s4"),
            id("dir"),
            id("auxo"),
        );
        let mut now = 0u64;
        let mut rises = Vec::new();
        let mut busy_changes = Vec::new();
        let mut last_s = (0, 0);
        let mut dir_high = false;
        let mut auxo_seen = None;
        for cmd in parser {
            match cmd.expect("VCD body parses") {
                Command::Timestamp(t) => now = t,
                Command::ChangeScalar(i, Value::V1) if i == pout => rises.push(now),
                Command::ChangeScalar(i, v) if i == busy => busy_changes.push((now, v)),
                Command::ChangeScalar(i, v) if i == s1 => last_s.0 = u8::from(v == Value::V1),
                Command::ChangeScalar(i, v) if i == s4 => last_s.1 = u8::from(v == Value::V1),
                Command::ChangeScalar(i, Value::V1) if i == dir => dir_high = true,
                Command::ChangeVector(i, v) if i == auxo => auxo_seen = Some(v.to_string()),
                _ => {}
            }
        }
        assert_eq!(rises, vec![300_000, 350_000, 400_000]);
        assert_eq!(
            busy_changes,
            vec![(0, Value::V0), (160_000, Value::V1), (426_000, Value::V0)]
        );
        // Three CCW steps from S1S2 end at S2S3... index 1: S2 S3, so S1 = 0, S4 = 0.
        assert_eq!(last_s, (0, 0));
        assert!(dir_high, "DIR shows CCW");
        assert_eq!(auxo_seen.as_deref(), Some("0101"));
    }
}

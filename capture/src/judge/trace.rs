//! A capture written as a trace in our format (`ppmc judge --trace`), so
//! that `ppmc compare golden/` judges a board recorded by a logic analyzer
//! as it judges one reached through the bridge. The trace holds what the
//! capture shows of the chip: the register writes and reads, POUT's
//! pulses (with DIR at each), and the outputs the capture has channels
//! for. It also holds the moves the written bytes started, as the
//! reference model took them: the same bytes start the same moves.
//!
//! Its `capture_pins` detail says it came from a capture and which pins
//! it holds. A compare with such a trace looks only at what a capture can
//! say of the chip (`ppmc::compare`): the writes and data reads, not the
//! host's status polling; the moves, the pulses and those pins; no
//! driver's measurement.

use ppmc::bus::Uncertainty;
use ppmc::emu::Board;
use ppmc::protocol::{Direction, EdgeRuns, OutputRecord, Pin, Straps};
use ppmc::time::{Duration, Instant};
use ppmc::trace::{
    uncertainty_detail, BusEvent, Event, EventKind, Trace, CAPTURE_PINS, UNCERTAINTY,
};
use ppmc_logic::decode::{Access, Transaction};
use ppmc_logic::map::{ChannelMap, Signal};
use ppmc_logic::source::{Change, LogicInfo};

/// An output the capture has, as a trace's pin: its channels (AUXO's
/// four make one pin), each active low or not.
struct Output {
    pin: Pin,
    /// `(channel, active low)` for each bit of the pin's value.
    bits: Vec<(usize, bool)>,
    value: u8,
}

/// The trace of a capture, built as the judge reads it.
pub(super) struct CaptureTrace {
    pout: Option<usize>,
    dir: Option<usize>,
    outputs: Vec<Output>,
    edges: EdgeRuns,
    record: OutputRecord,
    bus: Vec<Event>,
    /// The model's moves when the last pulse came: a pulse after a new
    /// one starts a run of its own.
    moves_at_pulse: usize,
}

impl CaptureTrace {
    pub(super) fn new(map: &ChannelMap, info: &LogicInfo) -> CaptureTrace {
        let mut outputs = Vec::new();
        let mut output = |pin: Pin, signals: &[(Signal, bool)]| {
            let bits: Option<Vec<(usize, bool)>> = signals
                .iter()
                .map(|&(s, low)| map.get(s).map(|c| (c, low)))
                .collect();
            if let Some(bits) = bits {
                outputs.push(Output {
                    pin,
                    bits,
                    value: 0,
                });
            }
        };
        output(Pin::Busy, &[(Signal::Busy, false)]);
        output(Pin::Int, &[(Signal::Int, true)]);
        output(Pin::Hold, &[(Signal::Hold, false)]);
        output(Pin::Aux, &[(Signal::Aux, true)]);
        let auxo: Vec<(Signal, bool)> = (0..4).map(|k| (Signal::Auxo(k), true)).collect();
        output(Pin::Auxo, &auxo);
        CaptureTrace {
            pout: map.get(Signal::Pout),
            dir: map.get(Signal::Dir),
            outputs,
            // Two samples either way of the line through a run's pulses.
            edges: EdgeRuns::new(Duration::from_nanos(
                (2 * info.resolution_ps).div_ceil(1000),
            )),
            record: OutputRecord::default(),
            bus: Vec::new(),
            moves_at_pulse: 0,
        }
    }

    /// The capture's change `c` (after `prev`), at model time `at`, with
    /// `model` run up to it.
    pub(super) fn change(&mut self, c: &Change, prev: Option<&Change>, at: Instant, model: &Board) {
        if let Some(ch) = self.pout {
            if c.high(ch) && prev.is_some_and(|p| !p.high(ch)) {
                let dir = match self.dir.is_some_and(|d| c.high(d)) {
                    true => Direction::Ccw,
                    false => Direction::Cw,
                };
                let moves = model.record().moves.len();
                let new_move = moves > self.moves_at_pulse;
                self.moves_at_pulse = moves;
                self.edges.push(&mut self.record, at, dir, new_move);
            }
        }
        for o in &mut self.outputs {
            let value = o.bits.iter().enumerate().fold(0u8, |v, (k, &(ch, low))| {
                v | u8::from(c.high(ch) != low) << k
            });
            if value != o.value {
                o.value = value;
                self.record.pin(at, o.pin, value);
            }
        }
    }

    /// A register access, at model time `at`.
    pub(super) fn access(&mut self, t: &Transaction, at: Instant) {
        let kind = match t.access {
            Access::WriteCommand => BusEvent::WriteCommand {
                byte: t.byte,
                waited: None,
            },
            Access::WriteData => BusEvent::WriteData {
                byte: t.byte,
                waited: None,
            },
            Access::ReadStatus => BusEvent::ReadStatus(t.byte),
            Access::ReadData => BusEvent::ReadData {
                byte: t.byte,
                waited: None,
            },
        };
        self.bus.push(Event {
            at,
            kind: EventKind::Bus(kind),
        });
    }

    /// The trace, named `scenario`, of a capture read as `info` says, its
    /// moves those of `model` (which took its writes), at `straps`.
    pub(super) fn finish(
        mut self,
        scenario: &str,
        info: &LogicInfo,
        model: &Board,
        straps: Straps,
    ) -> Trace {
        self.record.moves = model.record().moves.clone();
        let pins: Vec<&str> = self.outputs.iter().map(|o| o.pin.name()).collect();
        let mut details = vec![
            (CAPTURE_PINS.to_string(), pins.join(",")),
            ("capture_format".to_string(), info.format.replace(' ', "_")),
            (
                "capture_resolution_ps".to_string(),
                info.resolution_ps.to_string(),
            ),
        ];
        // Each edge the capture holds is seen up to a sample late: every
        // path as unsure as a sample (a compare widens by it).
        let sample = Duration::from_nanos(info.resolution_ps.div_ceil(1000));
        if info.resolution_ps > 1000 {
            let u = Uncertainty {
                edge: sample,
                sampled: sample,
                access: sample,
                polled: sample,
            };
            details.push((UNCERTAINTY.to_string(), uncertainty_detail(&u)));
        }
        Trace::new(scenario, "capture", "capture", straps, details).assemble(
            self.bus,
            &self.record,
            Vec::new(),
        )
    }
}

//! S1..S5 at their levels, as a logic analyzer on the chip's pins sees
//! them (the export with the bus, [`super::Export::bus`]): the trace's
//! energized pattern (its phase events, each move's winding and start
//! position, a step per pulse) under the output logic, with stop
//! switching's chopping drawn edge by edge from each switching event
//! (Sections 3-2-1, 3-5-1). A trace records neither the output logic nor
//! the ON and OFF times: the reference model, run through the trace's
//! register accesses, says them as it goes.

use super::{Emitter, LOOK_BACK, S1};
use crate::emu::{Board, ModelConfig};
use crate::protocol::{Chop, PhaseOutputs};
use crate::time::{Duration, Instant};
use crate::trace::{BusEvent, Trace};
use std::io::{self, Write};

pub(super) struct PhasePins {
    /// The model the trace's accesses are replayed on, and the trace's
    /// time of its zero (its last reset).
    model: Board,
    zero: Instant,
    setup: PhaseOutputs,
    pattern: u8,
    chop: Option<Chop>,
    /// Chopping drawn up to here.
    chopped: Instant,
}

impl PhasePins {
    pub(super) fn new(trace: &Trace) -> io::Result<PhasePins> {
        let model = Board::new(trace.straps, ModelConfig::default())
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e.to_string()))?;
        Ok(PhasePins {
            setup: model.phase_outputs(),
            model,
            zero: Instant::ZERO,
            pattern: 0,
            chop: None,
            chopped: Instant::ZERO,
        })
    }

    /// The levels now.
    pub(super) fn levels(&self, at: Instant) -> u8 {
        self.setup
            .logic
            .levels(Chop::energized(self.chop, self.pattern, at))
    }

    fn draw<W: Write>(&self, state: &mut Emitter<W>, at: Instant) -> io::Result<()> {
        state.set_bits(at, S1, 5, self.levels(at))
    }

    /// Draws the chopping's edges before `t`.
    pub(super) fn chop_until<W: Write>(
        &mut self,
        state: &mut Emitter<W>,
        t: Instant,
    ) -> io::Result<()> {
        while let Some(c) = self.chop {
            let edge = c.next_edge(self.chopped);
            if edge >= t {
                break;
            }
            self.chopped = edge;
            // A long stop chops for long: what is drawn goes out as it
            // goes, as the pulses do.
            state.drain_before((edge.as_nanos() + state.lead).saturating_sub(LOOK_BACK))?;
            self.draw(state, edge)?;
        }
        Ok(())
    }

    /// The model run to the trace's `at`, where the trace has an event,
    /// and the levels drawn again from where its output logic changed (an
    /// initialization after a software reset): before anything at `at`
    /// is written out.
    pub(super) fn event<W: Write>(
        &mut self,
        state: &mut Emitter<W>,
        at: Instant,
        bus: Option<&BusEvent>,
    ) -> io::Result<()> {
        self.model.advance_to(Instant::from_nanos(
            at.saturating_since(self.zero).as_nanos(),
        ));
        match bus {
            Some(BusEvent::WriteCommand { byte, .. }) => self.model.write_command(*byte),
            Some(BusEvent::WriteData { byte, .. }) => self.model.write_data(*byte),
            Some(BusEvent::ReadData { .. }) => {
                self.model.read_data();
            }
            Some(BusEvent::SetInput { input, asserted }) => self.model.set_input(*input, *asserted),
            Some(BusEvent::Reset) => {
                self.model.reset();
                self.zero = at;
            }
            _ => {}
        }
        let setup = self.model.phase_outputs();
        if setup.logic != self.setup.logic {
            self.setup.logic = setup.logic;
            let since = self.zero + Duration::from_nanos(setup.logic_since.as_nanos());
            self.draw(state, since)?;
        }
        self.setup.on = setup.on;
        self.setup.off = setup.off;
        Ok(())
    }

    /// The energized pattern `p` from `at` (a phase event, a pulse's
    /// step).
    pub(super) fn pattern<W: Write>(
        &mut self,
        state: &mut Emitter<W>,
        at: Instant,
        p: u8,
    ) -> io::Result<()> {
        self.pattern = p;
        self.draw(state, at)
    }

    /// Stop switching starts (`on`) or ends at `at`.
    pub(super) fn switching<W: Write>(
        &mut self,
        state: &mut Emitter<W>,
        at: Instant,
        on: bool,
    ) -> io::Result<()> {
        self.chop = on.then_some(Chop {
            since: at,
            on: self.setup.on,
            off: self.setup.off,
        });
        self.chopped = at;
        self.draw(state, at)
    }
}

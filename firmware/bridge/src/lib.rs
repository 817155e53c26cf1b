//! The parts of the RP2350 bridge firmware that a host can test: the PIO
//! programs, the bus cycles they play and their timing, and the capture's
//! timebase. `no_std`; the tests run on the host with a small PIO
//! interpreter ([`sim`]) that counts every cycle.
//!
//! - [`bus`]: a bus cycle (write command, write data, read status, read
//!   data) as a few *steps*, each a state of the bus pins held for a number
//!   of cycles; [`programs::bus_player`] plays them. Setup, strobe and hold
//!   times are [`bus::BusTiming`], configurable, with conservative defaults
//!   (the datasheet's bus-timing chapter is not in our hands:
//!   `docs/datasheet-notes.md` N46).
//! - [`programs::edge_capture`]: a state machine that stamps each rising
//!   edge of one pin (POUT, with DIR) or each change of one pin with a
//!   counter that ticks every second system clock cycle on every path.
//! - [`timebase`]: the 31-bit counts the capture pushes, turned into ticks
//!   since the timebase started.

#![no_std]

pub mod bus;
pub mod programs;
#[cfg(test)]
mod sim;
pub mod timebase;

//! Regression scenario from a fuzz finding: invariant `remaining-pulses` (Section 3-4-4,
//! docs/invariants.md) broke after op 23: remaining pulses read 0 after a move of 16777216 steps that output 0 pulses; expected 16777215.
//! Written by `ppmc fuzz to-scenario` from fuzz/regressions/bus_bytes/remaining-pulses-from-empty-corpus.bin.
//! It fails while the bug is there; once fixed, record its golden trace
//! (`ppmc record --filter fuzz_remaining_pulses_2`).
//!
//! Edited by hand: the minimizer left the wait before `wc! 0x83` at 214 us,
//! the very nanosecond at which the chip starts taking commands again after
//! the stop (a nanosecond earlier the read is refused with error 1, not
//! allowed while BUSY, Table 3-2). A bridge whose
//! timer is not locked to the chip (`bridge-sim --timer-hz 133333333`)
//! shortens it by a nanosecond and takes the other path, so the wait is
//! 215 us: still while BUSY, as in the finding, and a microsecond clear of
//! the boundary.

use ppmc::bus_program::BusOp::{self, *};
use ppmc::invariants::replay::regression;
use ppmc::scenario::prelude::*;

pub fn scenarios() -> Vec<Scenario> {
    vec![fuzz_remaining_pulses_2()]
}

/// fuzz finding: remaining-pulses must hold
#[scenario(section = "3-4-4", tags("fuzz", "regression"))]
fn fuzz_remaining_pulses_2(d: &mut Driver) -> Outcome {
    regression(d, OPS)
}

/// The minimized bus script, one op per line (console form in comments).
const OPS: &[BusOp] = &[
    BusOp::Input { input: ppmc::protocol::Input::L1, asserted: true }, // set l1 on
    Command(0x06), // wc! 0x06
    Advance(Duration::from_nanos(6000)), // wait 6us
    Data(0x40), // wd! 0x40
    Advance(Duration::from_nanos(6000)), // wait 6us
    Data(0x01), // wd! 0x01
    Advance(Duration::from_nanos(6000)), // wait 6us
    Data(0xFF), // wd! 0xFF
    Advance(Duration::from_nanos(6000)), // wait 6us
    Data(0x00), // wd! 0x00
    Advance(Duration::from_nanos(6000)), // wait 6us
    Command(0x55), // wc! 0x55
    Advance(Duration::from_nanos(19769000)), // wait 19769us
    Data(0x00), // wd! 0x00
    Advance(Duration::from_nanos(215000)), // wait 215us (214us in the finding)
    Command(0x83), // wc! 0x83
    Advance(Duration::from_nanos(150000)), // wait 150us
    ReadData, // rd!
    Advance(Duration::from_nanos(10000)), // wait 10us
    ReadData, // rd!
    Advance(Duration::from_nanos(10000)), // wait 10us
    ReadData, // rd!
];

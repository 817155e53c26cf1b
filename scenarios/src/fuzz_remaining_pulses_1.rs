//! Regression scenario from a fuzz finding: invariant `remaining-pulses` (Section 3-4-4,
//! docs/invariants.md) broke after op 30: remaining pulses read 1 after a move of 1 steps that output 0 pulses; expected 0.
//! Written by `ppmc fuzz to-scenario` from a minimized bus_bytes input
//! (seed s3_3_1_immediate_stop_and_resume.bin on the injected bug
//! `--chip-fault remaining-off-by-one`).
//! It fails while the bug is there; once fixed, record its golden trace
//! (`ppmc record --filter fuzz_remaining_pulses_1`).

use ppmc::bus_program::BusOp::{self, *};
use ppmc::invariants::replay::regression;
use ppmc::scenario::prelude::*;

pub fn scenarios() -> Vec<Scenario> {
    vec![fuzz_remaining_pulses_1()]
}

/// fuzz finding: remaining-pulses must hold
#[scenario(section = "3-4-4", tags("fuzz", "regression"))]
fn fuzz_remaining_pulses_1(d: &mut Driver) -> Outcome {
    regression(d, OPS)
}

/// The minimized bus script, one op per line (console form in comments).
const OPS: &[BusOp] = &[
    Command(0x02), // wc! 0x02
    Advance(Duration::from_nanos(6000)), // wait 6us
    Data(0x64), // wd! 0x64
    Advance(Duration::from_nanos(6000)), // wait 6us
    Data(0x14), // wd! 0x14
    Advance(Duration::from_nanos(6000)), // wait 6us
    Data(0x64), // wd! 0x64
    Advance(Duration::from_nanos(6000)), // wait 6us
    Data(0x00), // wd! 0x00
    Advance(Duration::from_nanos(17747000)), // wait 17747us
    Command(0x44), // wc! 0x44
    Advance(Duration::from_nanos(6000)), // wait 6us
    Data(0x00), // wd! 0x00
    Advance(Duration::from_nanos(6000)), // wait 6us
    Data(0x00), // wd! 0x00
    Advance(Duration::from_nanos(6000)), // wait 6us
    Data(0x00), // wd! 0x00
    Advance(Duration::from_nanos(6000)), // wait 6us
    Data(0x00), // wd! 0x00
    Advance(Duration::from_nanos(54000)), // wait 54us
    Command(0x40), // wc! 0x40
    Advance(Duration::from_nanos(32000)), // wait 32us
    Command(0x83), // wc! 0x83
    Advance(Duration::from_nanos(144000)), // wait 144us
    ReadData, // rd!
    Advance(Duration::from_nanos(10000)), // wait 10us
    ReadData, // rd!
    Advance(Duration::from_nanos(10000)), // wait 10us
    ReadData, // rd!
];

//! ppmc-core: the portable heart of ppmc, `no_std` with `alloc`, so that the
//! same code runs in the host harness and on a bridge microcontroller.
//!
//! Layers, each depending only on the ones before it:
//! [`time`] (virtual time) ← [`protocol`] (the chip's wire types, equations
//! and Table 3-3 as data) ← [`emu`] (the reference model) ← [`bus`] (bus
//! ops and the [`bus::Bus`] a bridge drives) ← [`bridge`] (link framing,
//! messages and the bridge engine).
//!
//! Nothing here touches a clock, a file or a port: time is passed in, and
//! the model answers with what happened and when it next needs attention.

#![no_std]

extern crate alloc;

// Tests run on the host, with std's macros (`vec!`, `format!`, `println!`).
#[cfg(test)]
#[macro_use]
extern crate std;

pub mod bridge;
pub mod bus;
pub mod emu;
pub mod protocol;
pub mod time;

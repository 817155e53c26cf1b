//! ppmc: a hardware-in-the-loop harness, reference emulator and protocol
//! fuzzer for the PPMC-104BFP stepper-motor pulse controller.
//!
//! Layers, each depending only on the ones before it:
//! [`protocol`] (pure wire types) ← [`emu`] (the chip model) ← [`target`]
//! (one bus abstraction, many backends) ← [`console`] (bus scripts) ← the
//! `ppmc` binary.

pub mod console;
pub mod emu;
pub mod protocol;
pub mod target;
pub mod time;
pub mod trace;

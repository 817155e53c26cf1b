//! The serial bus bridge. The link protocol (framing, messages) and the
//! bridge engine live in `ppmc-core` and are re-exported here; this module
//! adds what needs an operating system: the bridge simulator's I/O loop on
//! a pseudo-terminal ([`sim`]).

pub use ppmc_core::bridge::{abort, engine, frame, move_tracker, timed, wire};

pub mod sim;
pub mod sim_bus;

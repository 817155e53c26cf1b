//! The serial bus bridge: the link protocol a bridge microcontroller speaks
//! (specified in `docs/bridge-protocol.md`), implemented once and shared by
//! the host driver (`ppmc`'s serial backend), the bridge simulator and the
//! bridge firmware.
//!
//! [`frame`] turns payloads into self-delimiting frames and back, [`wire`]
//! turns requests and responses into payloads and back, and [`engine`] is
//! the bridge's request executor over any [`crate::bus::Bus`]; [`timed`]
//! captures a bus's outputs again with a bridge timer's resolution;
//! [`move_tracker`] keeps a capture's move records from the bus traffic, as a
//! bridge firmware must; [`abort`] lets a bridge hear ABORT while it is busy.

pub mod abort;
pub mod abort_line;
pub mod engine;
pub mod frame;
pub mod move_tracker;
pub mod timed;
pub mod wire;

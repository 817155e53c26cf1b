//! The plain model: a second, deliberately simple model of the chip,
//! written from chapter 3 of the datasheet and `docs/datasheet-notes.md`,
//! not from the emulator's code, to check the emulator against
//! ([`twin`]).
//!
//! Where the emulator plans a move in closed form, batches pulses into
//! runs and jumps over stretches of constant rate, this model does one
//! thing at a time: every pulse is an event of its own, the speed after
//! each pulse is found from the one before it (accelerate while there is
//! room to stop, never above RH), and time is whole nanoseconds in plain
//! integers. It keeps no cache and no plan. It is slow on purpose, and
//! meant for short inputs.
//!
//! It shares with the emulator only the vocabulary (the
//! [`Pins`](crate::protocol::Pins) and [`PinEvent`](crate::protocol::PinEvent)
//! it reports, [`Input`](crate::protocol::Input),
//! [`Direction`](crate::protocol::Direction)), the straps' clock periods
//! ([`Straps::tclock`](crate::protocol::Straps::tclock),
//! [`Straps::firmware_time`](crate::protocol::Straps::firmware_time): the
//! clock arithmetic of notes N9, N10, N44) and the latencies of
//! [`ModelConfig`](crate::emu::ModelConfig), which are parameters, not
//! behaviour. Command decoding, errors, the ramp, the phase sequences, the
//! speed limit, the register contents and every timing rule are its own.
//! Deliberate faults (`ModelConfig::faults`, `ModelConfig::board`) are not
//! modelled: it is always a good chip.
//!
//! - [`chip`]: the model, [`chip::PlainChip`] (its command decoding in
//!   `commands.rs`).
//! - [`twin`]: the emulator against the plain model: the same bus ops on
//!   both, compared after every op.

pub mod chip;
mod commands;
pub mod twin;

//! The plain model: a second model of the chip, written from chapter 3 of
//! the datasheet and `docs/datasheet-notes.md`, not from the emulator's
//! code, and the twin check that runs the same bus ops on both.
//!
//! - [`chip`]: the plain model itself, [`chip::PlainChip`].
//! - [`twin`]: the emulator against the plain model, compared after every
//!   op.

pub mod chip;
pub mod twin;

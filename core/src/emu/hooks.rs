//! Deliberate faults inside the reference model, for checking that the
//! suite, the golden comparison and the fuzzers catch a bad board. A clean
//! chip has none ([`ModelFaults::default`]). The named catalogue that sets them
//! is [`crate::emu::faults`] (the harness re-exports it as `ppmc::faults`,
//! and the QEMU board's virtual chip takes the same names).
//!
//! Only faults that need the model's insides are here: its firmware's
//! decisions (what a register read clears, what the mask gates, how a stop
//! decelerates) and which pulse of a move is its last. Faults of the board's
//! wiring, which the model need not know, are [`super::WiringFaults`].

/// Behaviour switches the model consults. Timing faults need none: they
/// are latencies moved out of their Table 3-3 band in
/// [`super::ModelConfig`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ModelFaults {
    /// The last pulse of every move is lost on the POUT wire (the chip
    /// counts it as output).
    pub drop_last_pulse: bool,
    /// The remaining-pulses register reads N - output instead of one less.
    pub remaining_off_by_one: bool,
    /// The phase outputs miss the first step of every move.
    pub phase_step_skipped: bool,
    /// A data register read leaves OBF at 1.
    pub obf_sticky: bool,
    /// The finish status read does not clear the polling flag.
    pub finish_flag_sticky: bool,
    /// INT* asserts at the end of every move, whatever the mask bit.
    pub int_unmasked: bool,
    /// Software reset during BUSY is ignored, not taken as AUX ON (3-5-4).
    pub reset_quirk_missing: bool,
    /// A Decelerating Stop cuts the pulses at once, like Immediate Stop.
    pub decel_stop_immediate: bool,
    /// Bits 6-4 keep showing the full parameter count until the last byte.
    pub params_not_counted: bool,
}

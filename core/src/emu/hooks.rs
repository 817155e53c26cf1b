//! Deliberate faults inside the reference model, for checking that the
//! suite, the golden comparison and the fuzzers catch a bad board. A clean
//! chip has none ([`Faults::default`]). The named catalogue that sets them
//! lives in the harness (`ppmc::faults`).

use crate::protocol::Direction;

/// Behaviour switches the model consults. Timing faults need none: they
/// are latencies moved out of their Table 3-3 band in [`ModelConfig`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Faults {
    /// The last pulse of every move is lost on the POUT wire (the chip
    /// counts it as output).
    pub drop_last_pulse: bool,
    /// The remaining-pulses register reads N - output instead of one less.
    pub remaining_off_by_one: bool,
    /// The limit input for this direction (L1 for CW, L2 for CCW) is never
    /// seen.
    pub limit_ignored: Option<Direction>,
    /// ALM is never seen.
    pub alarm_ignored: bool,
    /// CNP is never seen, so an origin search runs on.
    pub origin_ignored: bool,
    /// The phase outputs miss the first step of every move.
    pub phase_step_skipped: bool,
    /// A data register read leaves OBF at 1.
    pub obf_sticky: bool,
    /// The finish status read does not clear the polling flag.
    pub finish_flag_sticky: bool,
    /// INT* asserts at the end of every move, whatever the mask bit.
    pub int_unmasked: bool,
    /// The DIR output shows the opposite direction.
    pub dir_inverted: bool,
    /// Software reset during BUSY is ignored, not taken as AUX ON (3-5-4).
    pub reset_quirk_missing: bool,
    /// HOLD never turns on.
    pub hold_stuck_off: bool,
    /// AUXO0..3 come out in reverse order.
    pub auxo_reversed: bool,
    /// A Decelerating Stop cuts the pulses at once, like Immediate Stop.
    pub decel_stop_immediate: bool,
    /// Bits 6-4 keep showing the full parameter count until the last byte.
    pub params_not_counted: bool,
}

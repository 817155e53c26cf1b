//! Deliberate board faults: how a real revision of the chip (or its board)
//! can go wrong, for checking that the suite, the golden comparison and the
//! fuzzers catch a bad board. A clean chip has none.
//!
//! The [`CATALOGUE`] names each fault once; `ppmc bridge-sim --chip-fault
//! NAME`, `ppmc fault-matrix` and the QEMU bridge firmware's virtual chip
//! (`firmware/run-qemu --chip-fault NAME`) use those names. `docs/detection.md` shows
//! which check catches which.
//!
//! A [`NamedFault`] is one of three kinds, by where it acts:
//! - a **timing** fault, most of them: a latency of
//!   [`ModelConfig`] moved out of its Table 3-3 band;
//! - a **wiring** fault of the board around the chip
//!   ([`super::WiringFaults`]: a data bus line, an input wire, an output
//!   line), outside the model;
//! - a **model** fault ([`super::ModelFaults`], the hooks): the chip's
//!   firmware deciding wrongly, which needs the model's insides.

use crate::emu::ModelConfig;
use crate::protocol::timing::{figure, Figure, TimingId, TABLE_3_3};
use crate::protocol::{ErrorCode, Input};
use crate::time::Duration;
use alloc::string::String;
use alloc::vec::Vec;

/// One named fault of the catalogue.
#[derive(Debug, Clone, Copy)]
pub struct NamedFault {
    /// Stable name, as given to `--chip-fault`.
    pub name: &'static str,
    /// What the faulty board does, in a user's words.
    pub what: &'static str,
    /// The datasheet section whose behaviour it breaks.
    pub section: &'static str,
    apply: fn(&mut ModelConfig),
}

impl NamedFault {
    /// Puts the fault into a model configuration.
    pub fn apply(&self, cfg: &mut ModelConfig) {
        (self.apply)(cfg)
    }

    /// A clean default model with this fault.
    pub fn model(&self) -> ModelConfig {
        let mut cfg = ModelConfig::default();
        self.apply(&mut cfg);
        cfg
    }
}

/// `d` scaled by `percent` / 100, to the nanosecond.
fn pct(d: Duration, percent: u64) -> Duration {
    d.scale(percent, 100)
}

macro_rules! fault {
    ($name:literal, $section:literal, $what:literal, |$c:ident| $body:expr) => {
        NamedFault {
            name: $name,
            what: $what,
            section: $section,
            apply: |$c: &mut ModelConfig| $body,
        }
    };
}

/// Every named board fault.
pub const CATALOGUE: &[NamedFault] = &[
    fault!(
        "busy-rise-early",
        "Table 3-3",
        "BUSY rises 5% before the bottom of its Table 3-3 band",
        |c| {
            let bottom = figure(TABLE_3_3, TimingId::BusyRise, Figure::Min);
            c.busy_rise = pct(bottom.unwrap_or(c.busy_rise), 95);
        }
    ),
    fault!(
        "first-pout-slow",
        "Table 3-3",
        "first POUT of a constant-speed move 5% late",
        |c| c.constant_first_pout = pct(c.constant_first_pout, 105)
    ),
    fault!(
        "accel-first-pout-slow",
        "Table 3-3",
        "first POUT of an accel/decel move 5% late",
        |c| {
            c.accel_first_pout = pct(c.accel_first_pout, 105);
            c.accel_first_pout_triangle_max = pct(c.accel_first_pout_triangle_max, 105);
        }
    ),
    fault!(
        "init-slow",
        "Table 3-3",
        "initialization processing 6% longer than its band",
        |c| {
            c.init_time_min = pct(c.init_time_min, 106);
            c.init_time_max = pct(c.init_time_max, 106);
        }
    ),
    fault!(
        "int-late",
        "Table 3-3",
        "INT* and BUSY = 0 come 8% late after the final POUT",
        |c| c.interrupt_delay = pct(c.interrupt_delay, 108)
    ),
    fault!(
        "decel-stop-slow",
        "Table 3-3",
        "Decelerating Stop acts 6% late",
        |c| c.decel_stop = pct(c.decel_stop, 106)
    ),
    fault!(
        "hold-on-early",
        "Table 3-3",
        "HOLD turns on 6% early after the final POUT",
        |c| c.hold_on = pct(c.hold_on, 94)
    ),
    fault!(
        "excitation-off-slow",
        "Table 3-3",
        "software reset de-energizes the phases 6% late",
        |c| c.excitation_off = pct(c.excitation_off, 106)
    ),
    fault!(
        "single-step-slow",
        "Table 3-3",
        "single step processing 5% longer than Table 3-3 gives",
        |c| c.single_step_done = pct(c.single_step_done, 105)
    ),
    fault!(
        "drop-last-pulse",
        "3-3-1",
        "the last pulse of every move is lost on the POUT wire",
        |c| c.faults.drop_last_pulse = true
    ),
    fault!(
        "remaining-off-by-one",
        "3-4-4",
        "remaining pulses read one too many (N - output, not one less)",
        |c| c.faults.remaining_off_by_one = true
    ),
    fault!(
        "swap-error-2-3",
        "Table 3-2",
        "a move before initialization reports error 3, not 2",
        |c| c.board.swap_error = Some((ErrorCode::NotInitialized, ErrorCode::TooManyParameters))
    ),
    fault!(
        "swap-error-1-6",
        "Table 3-2",
        "a command during BUSY reports error 6, not 1",
        |c| c.board.swap_error = Some((ErrorCode::NotAllowedWhileBusy, ErrorCode::DataWhileBusy))
    ),
    fault!(
        "status-bit3-stuck",
        "3-1-1",
        "status bit 3 (data line D3) stuck high",
        |c| c.board.status_stuck_high = 0x08
    ),
    fault!(
        "ccw-limit-ignored",
        "3-3-2",
        "L2 (CCW limit) is never seen: CCW moves run through it",
        |c| c.board.inputs_cut.set(Input::L2, true)
    ),
    fault!("alarm-ignored", "3-3-2", "ALM is never seen", |c| c
        .board
        .inputs_cut
        .set(Input::Alm, true)),
    fault!(
        "origin-ignored",
        "3-3-8",
        "CNP is never seen: origin search runs on",
        |c| c.board.inputs_cut.set(Input::Cnp, true)
    ),
    fault!(
        "phase-step-skipped",
        "3-2-1",
        "the phase outputs miss the first step of every move",
        |c| c.faults.phase_step_skipped = true
    ),
    fault!(
        "obf-never-cleared",
        "3-1-2",
        "a data register read leaves OBF at 1",
        |c| c.faults.obf_sticky = true
    ),
    fault!(
        "finish-flag-sticky",
        "3-4-1",
        "the finish status read does not clear the polling flag",
        |c| c.faults.finish_flag_sticky = true
    ),
    fault!(
        "int-ignores-mask",
        "3-3-1",
        "INT* asserts at the end of every move, masked or not",
        |c| c.faults.int_unmasked = true
    ),
    fault!(
        "dir-inverted",
        "3-3-1",
        "the DIR output shows the opposite direction",
        |c| c.board.dir_inverted = true
    ),
    fault!(
        "reset-quirk-missing",
        "3-5-4",
        "software reset during BUSY is ignored instead of acting as AUX ON",
        |c| c.faults.reset_quirk_missing = true
    ),
    fault!(
        "hold-stuck-off",
        "3-2-1",
        "the HOLD output never turns on",
        |c| c.board.hold_stuck_off = true
    ),
    fault!(
        "auxo-reversed",
        "3-5-5",
        "AUXO0..3 come out in reverse bit order",
        |c| c.board.auxo_reversed = true
    ),
    fault!(
        "decel-stop-immediate",
        "3-3-2",
        "Decelerating Stop cuts the pulses at once, like Immediate Stop",
        |c| c.faults.decel_stop_immediate = true
    ),
    fault!(
        "params-not-counted",
        "3-1-1",
        "status bits 6-4 do not count down as parameter bytes arrive",
        |c| c.faults.params_not_counted = true
    ),
];

/// The catalogue entry called `name`.
pub fn find(name: &str) -> Option<&'static NamedFault> {
    CATALOGUE.iter().find(|f| f.name == name)
}

/// A fault name that is not in the catalogue nor one of its parameterized
/// forms.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FaultNameError {
    #[error("fault `{0}`: write swap-error-A-B with A, B in 0..=7")]
    BadSwap(String),
    #[error("fault `{0}`: write status-stuck-0xNN")]
    BadStuck(String),
    #[error(
        "unknown fault `{0}`: one of {known}, or swap-error-A-B, status-stuck-0xNN \
         (`ppmc fault-matrix --list` describes them)",
        known = CATALOGUE.iter().map(|f| f.name).collect::<Vec<_>>().join(", ")
    )]
    Unknown(String),
}

/// Puts the fault called `name` into `cfg`: a catalogue name, or one of the
/// parameterized forms `swap-error-A-B` (A, B in 0..=7) and
/// `status-stuck-0xNN`.
pub fn apply_named(name: &str, cfg: &mut ModelConfig) -> Result<(), FaultNameError> {
    if let Some(f) = find(name) {
        f.apply(cfg);
        return Ok(());
    }
    if let Some(rest) = name.strip_prefix("swap-error-") {
        let (a, b) = rest
            .split_once('-')
            .and_then(|(a, b)| Some((a.parse::<u8>().ok()?, b.parse::<u8>().ok()?)))
            .filter(|(a, b)| *a < 8 && *b < 8)
            .ok_or_else(|| FaultNameError::BadSwap(name.into()))?;
        cfg.board.swap_error = Some((ErrorCode::from_number(a), ErrorCode::from_number(b)));
        return Ok(());
    }
    if let Some(hex) = name.strip_prefix("status-stuck-0x") {
        cfg.board.status_stuck_high =
            u8::from_str_radix(hex, 16).map_err(|_| FaultNameError::BadStuck(name.into()))?;
        return Ok(());
    }
    Err(FaultNameError::Unknown(name.into()))
}

/// Puts every named fault into `cfg` ([`apply_named`] each, in order); the
/// error names the first fault that is not known.
pub fn apply_all<S: AsRef<str>>(names: &[S], cfg: &mut ModelConfig) -> Result<(), FaultNameError> {
    names.iter().try_for_each(|n| apply_named(n.as_ref(), cfg))
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::string::ToString;

    #[test]
    fn the_catalogue_has_twenty_distinct_faults_each_changing_the_model() {
        assert!(CATALOGUE.len() >= 20);
        let mut names: Vec<&str> = CATALOGUE.iter().map(|f| f.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), CATALOGUE.len(), "names are unique");
        for f in CATALOGUE {
            assert_ne!(
                f.model(),
                ModelConfig::default(),
                "{} changes nothing",
                f.name
            );
            assert!(f.model().validate().is_ok(), "{} is a valid model", f.name);
        }
    }

    #[test]
    fn named_and_parameterized_faults_apply_and_unknown_ones_are_refused() {
        let mut c = ModelConfig::default();
        apply_named("swap-error-3-4", &mut c).expect("parameterized");
        assert_eq!(
            c.board.swap_error,
            Some((ErrorCode::TooManyParameters, ErrorCode::AccelPulsesTooMany))
        );
        apply_named("status-stuck-0x40", &mut c).expect("stuck");
        assert_eq!(c.board.status_stuck_high, 0x40);
        apply_named("dir-inverted", &mut c).expect("catalogue");
        assert!(c.board.dir_inverted);
        let e = apply_named("no-such", &mut c)
            .expect_err("unknown")
            .to_string();
        assert!(e.contains("unknown fault `no-such`") && e.contains("drop-last-pulse"));
        assert!(apply_named("swap-error-9-1", &mut c).is_err());
    }
}

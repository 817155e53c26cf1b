//! What a report draws of a scenario, kept in its run record (`figures`):
//! each move's pulse runs, the board's and the golden trace's, and the
//! pins around the point where the scenario failed.
//!
//! Runs, not pulses: a move of 16,777,216 steps is a few thousand runs of
//! equally spaced pulses, so the record stays small whatever the move's
//! length, and a report reduces them for drawing itself. The harness
//! draws them from a trace (`ppmc::trace::figures`).

use serde::{Deserialize, Serialize};

/// What a report draws of one scenario.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Figures {
    /// Each move of the scenario, in order.
    pub moves: Vec<MoveFigure>,
    /// The pins around the failure, when the scenario failed at a time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub waveform: Option<Waveform>,
}

/// One move's pulses: the board's and, when the run compared with golden
/// traces, the golden trace's move of the same place (the n-th move of
/// each, as `ppmc compare` aligns them).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MoveFigure {
    /// When the move's last byte was written, on the target's clock; the
    /// runs' times count from here.
    pub at_ns: u64,
    /// `accel-decel`, `constant`, ...
    pub kind: String,
    /// `cw` or `ccw`.
    pub dir: String,
    /// The steps asked for (0 for a continuous move).
    pub steps: u32,
    /// The board's pulse runs: `[first pulse from at_ns, count, span from
    /// the first pulse to the last]`, nanoseconds.
    pub runs: Vec<[u64; 3]>,
    /// The golden trace's runs of this move, times from its own move.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub golden: Option<Vec<[u64; 3]>>,
}

impl MoveFigure {
    /// The pulses of the board's runs.
    pub fn pulses(&self) -> u64 {
        self.runs.iter().fold(0u64, |n, r| n.saturating_add(r[1]))
    }
}

/// The pins around the failure: every change in `from_ns..=to_ns`, and
/// each pin's level at `from_ns`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Waveform {
    pub from_ns: u64,
    pub to_ns: u64,
    /// The failure's time, which the window is centred on.
    pub mark_ns: u64,
    /// Each POUT pulse in the window (at most [`MAX_WAVE_PULSES`]).
    pub pout: Vec<u64>,
    /// The golden trace's pulses of the same move, moved to the board's
    /// move start, when the run compared with golden traces.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub golden_pout: Option<Vec<u64>>,
    /// Every output pin that has a level: its name, its value at
    /// `from_ns`, its changes `[time, value]` in the window.
    pub pins: Vec<PinWave>,
    /// The host's bus accesses in the window: `[time, what]`.
    pub bus: Vec<(u64, String)>,
}

/// One pin of a [`Waveform`].
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PinWave {
    pub name: String,
    /// How many bits its value has (1 for a plain pin; 4 for AUXO, 5 for
    /// the phases).
    pub bits: u8,
    pub initial: u8,
    pub changes: Vec<[u64; 2]>,
}

/// Pulses drawn in a waveform at most: the window is a few pulses either
/// side of the failure, so only a pulse train far faster than its
/// neighbours' events reaches this.
pub const MAX_WAVE_PULSES: usize = 400;

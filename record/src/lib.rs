//! The ppmc run record: what a run learned, owned and plain, written by
//! every producer (a run of boards, a golden comparison, a capture's
//! judge, a soak) and read by every report (JUnit, JSON, HTML, the results
//! store).
//!
//! A [`RunRecord`] holds the run's facts ([`RunInfo`]: the harness, the
//! boards, the options, a judged capture), its [`Tally`], each result
//! ([`ScenarioRecord`]: its [`Status`], the device's failure or the error
//! that kept it from a verdict, its graded [`Measurement`]s with their
//! uncertainty, its attempts, what a report draws of it) and, under
//! `--repeat`, the runs it counted rather than listed. It is the JSON run
//! record (`ppmc-run-record/4`, `docs/run-record.schema.json`) as types:
//! [`RunRecord::to_json`] writes it and [`RunRecord::parse`] reads it
//! back, format 3 too.
//!
//! The decision rule that grades a measurement ([`Grading`], ISO 14253-1's
//! with the instrument's uncertainty) lives here with the measurement it
//! grades. This crate depends on `ppmc-core`'s time and protocol types and
//! on nothing of the harness.

mod deviation;
mod figures;
mod info;
pub mod measurement;
mod result;
mod run;
mod tally;

pub use deviation::{human_ns, signed_ns, Bound, Deviation, DeviationUnit, Reference};
pub use figures::{Figures, MoveFigure, PinWave, Waveform, MAX_WAVE_PULSES};
pub use info::{check_label, rfc3339, BoardInfo, CaptureSource, RunInfo, RunOptions, MAX_LABEL};
pub use measurement::{Grade, Grading, Measurement, MARGINAL_PCT};
pub use result::{
    AttemptRecord, Blame, ErrorKind, ErrorRecord, FailureRecord, HostFindingRecord, RangeRecord,
    RepeatedRecord, ScenarioRecord, MAX_LISTED,
};
pub use run::{printable, RecordError, RunRecord, Shortfall, FORMAT, FORMATS, MAX_RECORD_BYTES};
pub use tally::{Status, Tally};

//! Run reports: JUnit XML for CI systems, a JSON run record with every
//! measurement and its limits, and an offline HTML page drawn from run
//! records.
//!
//! `info.rs` holds what every report says of the run, `tally.rs` the
//! verdict counts, `listing.rs` what the formats list and share;
//! `junit.rs` and `json.rs` write them. `figures.rs` is what a record
//! keeps for drawing (each move's pulse runs, the pins around a failure),
//! `record.rs` a record read back; `html.rs` the page, `plots.rs` its
//! plots, `svg.rs` the drawing and the reduction of long series;
//! `history.rs` the page of a results store ([`crate::store`]).

mod figures;
mod history;
mod html;
mod info;
mod json;
mod junit;
mod listing;
mod plots;
mod record;
mod svg;
pub(crate) mod tally;

pub use figures::{Figures, MoveFigure, PinWave, Waveform, MAX_WAVE_PULSES};
pub use history::history_html;
pub use html::html;
pub use info::{rfc3339, BoardInfo, CaptureSource, RunInfo, RunOptions};
pub use json::{json, json_listing};
pub use junit::{junit, junit_listing};
pub use listing::{Blame, Judged, Listing, ReportError};
pub use record::{printable, Record, RecordError, FORMATS as RECORD_FORMATS};
pub use svg::{reduce, Reduced, Segment};
pub use tally::Tally;

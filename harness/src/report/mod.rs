//! Run reports: JUnit XML for CI systems, and a JSON run record with every
//! measurement and its limits.
//!
//! `info.rs` holds what every report says of the run, `tally.rs` the
//! verdict counts, `listing.rs` what both formats list and share;
//! `junit.rs` and `json.rs` write them.

mod info;
mod json;
mod junit;
mod listing;
pub(crate) mod tally;

pub use info::{rfc3339, BoardInfo, CaptureSource, RunInfo, RunOptions};
pub use json::{json, json_listing};
pub use junit::{junit, junit_listing};
pub use listing::{Blame, Judged, Listing, ReportError};
pub use tally::Tally;

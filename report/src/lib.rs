//! Reports of ppmc run records ([`ppmc_record::RunRecord`]): JUnit XML for
//! CI systems ([`junit`]), the offline HTML page ([`html`]), and the
//! results store that keeps every record of a lab in SQLite ([`store`])
//! with its page ([`history_html`]). The JSON record is the record itself
//! ([`ppmc_record::RunRecord::to_json`]).
//!
//! `junit.rs` writes JUnit; `html.rs` the page, `plots.rs` its plots,
//! `svg.rs` the drawing and the reduction of long series; `history.rs`
//! the page of a results store; `store/` the store and what it says across
//! runs. Nothing here depends on the harness: a report is drawn from what
//! the record holds.

mod history;
mod html;
mod junit;
mod plots;
pub mod store;
mod svg;

pub use history::history_html;
pub use html::html;
pub use junit::junit;
pub use svg::{reduce, Reduced, Segment};

/// This crate's version, which the pages name.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

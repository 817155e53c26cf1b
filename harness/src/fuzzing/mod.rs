//! Fuzzing: the fuzz target bodies and what a campaign makes of its
//! findings. The checks the targets run live in their own rooms: the
//! invariant oracle in [`crate::invariants`], the second model of the chip
//! and its comparison with the emulator in [`crate::plain_model`].
//!
//! - [`targets`]: one function per `fuzz/fuzz_targets/*.rs`.
//! - The bus-op language (`BusOp`) and the byte-stream grammar of a
//!   `bus_bytes` input, what the oracle judges and the twin compares, is
//!   [`crate::bus_program`], below all three rooms.
//! - [`actions`]: typed host actions (the `typed_actions` target, the
//!   differential runs), and their lowering to bus ops under the oracle.
//! - [`finding`]: from a finding to a regression: minimizers,
//!   reproducers, regression scenario files.
//! - [`campaign`]: findings bucketed by invariant, a corpus's domain
//!   coverage.
//! - [`seeds`]: the targets' seed corpora, made from the protocol and the
//!   suite (`ppmc fuzz seeds`).
//! - [`differential`]: seeded runs of typed actions on a target beside the
//!   reference emulator (`ppmc fuzz run`).
//! - [`reference`](mod@reference): the reference model run beside a board on the
//!   board's timeline, and where the two depart (what differential runs
//!   and campaigns judge a board by besides the invariants).
//! - [`guided`]: a campaign of `bus_bytes` inputs on any target, judged by
//!   the invariants on the board's own answers, guided by the model's
//!   coverage, on a budget of board time (`ppmc fuzz campaign`);
//!   [`schedule`]: which input it mutates next.

pub mod actions;
pub mod campaign;
pub mod differential;
pub mod finding;
pub mod guided;
pub mod reference;
pub mod schedule;
pub mod seeds;
pub mod targets;

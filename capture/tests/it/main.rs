//! The integration tests of ppmc-capture, one binary (as cargo's own
//! `tests/testsuite`): boards judged from captures written by ppmc's
//! export and by other tools, the capture readers held against sigrok-cli,
//! and the fault matrix.

mod fault_matrix;
mod judge_capture;
mod judge_host;
mod judge_timing;
mod judge_uncertainty;
mod logic_readers;
mod logic_sigrok;

//! A PPMC-104BFP board judged from a logic-analyzer capture of its bus and
//! pins, where no bridge is wired (`docs/capture.md`), and the fault
//! matrix that holds every way of judging a board to the catalogue of
//! board faults (`docs/detection.md`).
//!
//! [`judge`] replays the capture's decoded writes into the reference model
//! at their captured times and compares what the board did with what the
//! model does, within what the capture can tell (its sample period, the
//! latency tolerances); a judgement blames the board, the host firmware or
//! the capture, and becomes a run record (`judge/record.rs`).
//! [`fault_matrix`] runs every fault of the catalogue through the suite,
//! golden traces, the fuzzer's oracle and this judge, and says which
//! catches it where.
//!
//! Built on the harness (`ppmc`: the model, traces, the suite's runner)
//! and `ppmc-logic` (the capture readers and the bus decoder).

pub mod fault_matrix;
pub mod judge;

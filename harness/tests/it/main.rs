//! The integration tests of the harness, one binary (as cargo's own
//! `tests/testsuite`): the datasheet's behaviour by section (`s3_*`), the
//! suite on the emulator, golden traces, bridges over pseudo-terminals and
//! on the firmware's boards, the two models side by side, the fuzz corpora.

mod bridge_moves;
mod bridge_pty;
mod firmware_qemu;
mod firmware_twin;
mod fuzz_corpus;
mod golden;
mod model_twin;
mod mutation;
mod one_truth;
mod robustness;
mod s3_1_host_interface;
mod s3_2_initialization;
mod s3_3_operations;
mod s3_4_register_reads;
mod s3_5_auxiliary;
mod s3_6_command_process_time;
mod suite_on_emulator;

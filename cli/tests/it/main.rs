//! The integration tests of the `ppmc` command line, one binary (as
//! cargo's own `tests/testsuite`): every command as a user runs it, the
//! reports as their consumers read them, bridges over serial, TCP, RFC 2217
//! and labgrid, the docs' commands, and the repository's shape.

mod architecture_map;
mod board;
mod cli_behaves;
mod cli_boards;
mod cli_bridge;
mod cli_capture;
mod cli_chaos;
mod cli_conformance;
mod cli_fault_matrix;
mod cli_fuzz;
mod cli_labgrid;
mod cli_network;
mod cli_outputs;
mod cli_power;
mod cli_selftest;
mod cli_signals;
mod code_shape;
mod common;
mod console_cli;
mod docs_commands;
mod layers;
mod report_html;
mod reports;
mod results_store;
mod shared_store;
mod suite_captures;
mod vcd_sigrok;

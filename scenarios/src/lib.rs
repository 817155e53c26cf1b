//! The PPMC-104BFP conformance suite: one module per area of datasheet
//! chapter 3, each scenario a function declared with `#[scenario]` where it
//! is written, naming the section it proves. `fuzz_*` modules are
//! regression scenarios made from fuzz findings (`ppmc fuzz to-scenario`).
//!
//! This crate uses nothing of `ppmc` that a board team's crate cannot:
//! `examples/board-suite` builds its own suite the same way.

/// The suite's modules, in run order; each has `pub fn scenarios()`.
macro_rules! suite {
    ($($module:ident),* $(,)?) => {
        $(pub mod $module;)*

        /// Every scenario of the suite, module by module, in run order.
        pub fn all() -> Vec<ppmc::scenario::Scenario> {
            let mut v = Vec::new();
            $(v.extend($module::scenarios());)*
            v
        }
    };
}

suite![
    fuzz_remaining_pulses_1,
    fuzz_remaining_pulses_2,
    s3_1_host_interface,
    s3_2_excitation,
    s3_2_initialization,
    s3_3_operations,
    s3_4_register_reads,
    s3_5_auxiliary,
    s3_6_detection_latency,
];

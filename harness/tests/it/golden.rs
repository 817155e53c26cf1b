//! The emulator's trace of every scenario, checked against `golden/` with
//! insta. After an intended model change, `cargo insta review` shows each
//! changed trace and accepts it; CI never writes golden files.

use ppmc_test_support as common;

#[test]
fn emulator_traces_match_golden() {
    let results = common::suite_in_process();
    let mut settings = insta::Settings::clone_current();
    settings.set_snapshot_path("../../../golden");
    settings.set_prepend_module_to_snapshot(false);
    settings.set_omit_expression(true);
    settings.bind(|| {
        for r in &results {
            let trace = r.trace.as_ref().expect("the emulator always captures");
            insta::assert_snapshot!(r.name, trace.render());
        }
    });
}

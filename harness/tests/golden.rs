//! The emulator's trace of every scenario, checked against `golden/` with
//! insta. After an intended model change, `cargo insta review` shows each
//! changed trace and accepts it; CI never writes golden files.

use ppmc::emu::ModelConfig;
use ppmc::protocol::Straps;
use ppmc::runner::run_suite;
use ppmc::scenario::DriverOptions;
use ppmc::target::EmuTarget;

#[test]
fn emulator_traces_match_golden() {
    let all = ppmc::suite::all();
    let mut t = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    let results = run_suite(&mut t, &all, 1, DriverOptions::default(), |_| {});
    let mut settings = insta::Settings::clone_current();
    settings.set_snapshot_path("../../golden");
    settings.set_prepend_module_to_snapshot(false);
    settings.set_omit_expression(true);
    settings.bind(|| {
        for r in &results {
            let trace = r.trace.as_ref().expect("the emulator always captures");
            insta::assert_snapshot!(r.name, trace.render());
        }
    });
}

//! `ppmc selftest` as a user runs it: on the board twin (the RP2350
//! image's board code on a model of the RP2350's PIO and GPIOs, whose
//! TEST_GEN drives the capture inputs of POUT and INT* through the same
//! wiring as `docs/bridge-hardware.md`), on a bridge with no generator,
//! and on the emulator.

use crate::common;

use common::{ppmc, text, BridgeSim};
use ppmc_test_support::served::Served;

/// The twin's address as the command line takes it.
fn target(twin: &Served) -> String {
    format!("serial:{}", twin.link.display())
}

#[test]
fn selftest_passes_on_the_twin_and_says_the_captures_offset_and_jitter() {
    // Issue 28, item 7: the generator's pulses at 10, 100 and 403 kpps and
    // in bursts, all captured on POUT and INT* at their times; a rate
    // beyond the capture reported as an overrun; the next capture on time.
    let twin = Served::start("run-twin", &[]);
    let out = ppmc(&["selftest", "--target", &target(&twin)]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("ppmc-bridge-twin"), "{stdout}");
    let checks: Vec<&str> = stdout.lines().filter(|l| l.starts_with("  ")).collect();
    assert_eq!(checks.len(), 5, "{stdout}");
    assert!(checks.iter().all(|l| l.ends_with(": ok")), "{stdout}");
    // Every pulse of the 3 x 100 at the chip's fastest rate, its offset
    // and jitter measured.
    assert!(
        stdout.contains("POUT 300/300, offset +") && stdout.contains("INT* 600/600, offset +"),
        "{stdout}"
    );
    assert!(
        stdout.contains("beyond the capture") && stdout.contains("capture overrun reported"),
        "{stdout}"
    );
    assert!(
        stdout.ends_with("selftest: passed: 5 checks (limits: offset 100 ns, jitter 30 ns)\n"),
        "{stdout}"
    );
    // Limits tighter than the twin's own offset (some 40 ns): the same
    // run fails, and says where.
    let out = ppmc(&[
        "selftest",
        "--target",
        &target(&twin),
        "--max-offset",
        "20ns",
    ]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("over the 20 ns limit"), "{stdout}");
    assert!(
        text(&out.stderr).contains("checks failed (limits: offset 20 ns, jitter 30 ns)"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn selftest_on_a_bridge_without_a_generator_or_on_the_emulator_says_why() {
    let sim = BridgeSim::start(&[]);
    let out = ppmc(&["selftest", "--target", &sim.target()]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("infrastructure error") && stderr.contains("no self-test generator"),
        "{stderr}"
    );
    let out = ppmc(&["selftest"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("no bus bridge to self-test"), "{stderr}");
    // Issue 42: no heading of a self-test that never ran.
    assert_eq!(text(&out.stdout), "", "{stderr}");
}

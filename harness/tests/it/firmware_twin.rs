//! The RP2350 bridge's board code on the board twin: `firmware/run-twin`
//! runs `ppmc_bridge_fw::board` (the image's board code) on a model of the
//! RP2350's PIO blocks and GPIOs wired pin by pin to the reference chip
//! model, behind the image's `BridgeEngine`, on a pseudo-terminal
//! (firmware/README.md). These tests go through it as a host goes
//! through a board.
//!
//! The whole suite (`--skip-tag long`) passes through it with the
//! emulator's verdicts. The twin runs slower than real time (a
//! scenario's 1.3 s move takes it about a minute, more on a busy machine);
//! it says so with WORKING messages, and the host waits by the twin's
//! clock instead of its own (`docs/bridge-protocol.md` section 5), so the
//! default link settings do, whatever the machine's load.

use ppmc_test_support as common;

use common::served::{only_error_3_fails, Served};
use ppmc::backend::EmuTarget;
use ppmc::runner::run_suite;
use ppmc::scenario::{DriverOptions, Verdict};
use ppmc_core::emu::ModelConfig;
use ppmc_core::protocol::Straps;

#[test]
fn the_suite_passes_through_the_board_code_on_the_twin_with_the_emulators_verdicts() {
    let twin = Served::start("run-twin", &[]);
    let mut t = twin.target();
    let hello = t.hello().clone();
    assert!(
        hello.firmware.starts_with("ppmc-bridge-twin "),
        "{}",
        hello.firmware
    );
    assert_eq!(hello.timer_hz, 75_000_000, "the PIO counters' timebase");
    let chosen: Vec<_> = ppmc_scenarios::all()
        .into_iter()
        .filter(|s| !s.has_tag("long"))
        .collect();
    assert!(chosen.len() > 80, "{}", chosen.len());
    let mut emu = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    let want = run_suite(&mut emu, &chosen, 1, DriverOptions::default(), |_| {});
    let got = run_suite(&mut t, &chosen, 1, DriverOptions::default(), |_| {});
    // Every measurement the twin makes lies within the uncertainty it
    // declares of the emulator's (exact) figure.
    let mut far = Vec::new();
    for (w, g) in want.iter().zip(&got) {
        assert_eq!(w.measurements.len(), g.measurements.len(), "{}", w.name);
        for (a, b) in w.measurements.iter().zip(&g.measurements) {
            assert_eq!(a.name, b.name);
            if a.value.as_nanos().abs_diff(b.value.as_nanos()) > b.u.as_nanos() {
                far.push(format!(
                    "{}: {} {} on the twin, {} on the emulator",
                    w.name,
                    b.name,
                    b.shown(),
                    a.value
                ));
            }
        }
    }
    assert!(far.is_empty(), "{}", far.join("\n"));
    // The verdicts are the emulator's, but where a band is narrower than
    // the twin can tell (docs/conformance.md): MARGINAL, never FAIL.
    let differ: Vec<String> = want
        .iter()
        .zip(&got)
        .filter(|(w, g)| w.verdict != g.verdict)
        .filter(|(w, g)| !(w.verdict == Verdict::Passed && g.verdict == Verdict::Marginal))
        .map(|(w, g)| format!("{}: emulator {:?}, twin {:?}", w.name, w.verdict, g.verdict))
        .collect();
    assert!(differ.is_empty(), "{}", differ.join("\n"));
    assert!(want.iter().all(|r| r.verdict == Verdict::Passed));
    let marginal: Vec<&str> = got
        .iter()
        .filter(|r| r.verdict == Verdict::Marginal)
        .map(|r| r.name)
        .collect();
    // The bands of a few microseconds that a CPU-sampled path (5 us)
    // or a polled flag (1 us) cannot prove (the scenarios named in
    // docs/conformance.md).
    assert!(marginal.len() <= 6, "{marginal:?}");
    drop(t);
    let link = twin.link.clone();
    drop(twin);
    assert!(!link.exists(), "run-twin removes its link when stopped");
}

#[test]
fn a_host_waits_by_the_twins_clock_not_its_own() {
    // A host far less patient than the default (a reply within 300 ms,
    // two silent tries) through the scenario the twin takes longest over
    // (1.3 s of a move simulated cycle by cycle, a minute of wall time or
    // more): the twin's WORKING messages carry it through, and the verdict
    // is the emulator's.
    let twin = Served::start("run-twin", &[]);
    let mut t = twin.target_with(ppmc::backend::BridgeOptions {
        reply_timeout: std::time::Duration::from_millis(300),
        retries: 2,
        ..ppmc::backend::BridgeOptions::default()
    });
    let chosen: Vec<_> = ppmc_scenarios::all()
        .into_iter()
        .filter(|s| s.name == "s3_3_4_longest_triangle_first_pout")
        .collect();
    assert_eq!(chosen.len(), 1, "the scenario is in the suite");
    let got = run_suite(&mut t, &chosen, 1, DriverOptions::default(), |_| {});
    assert_eq!(got[0].verdict, Verdict::Passed, "{:?}", got[0]);
    assert!(
        t.stats.working > 0,
        "the twin said it was working: {:?}",
        t.stats
    );
    let hello = t.hello();
    assert!(hello.virtual_time);
    // The board code's own declaration (docs/bridge-protocol.md section 4).
    assert_eq!(hello.uncertainty.edge.as_nanos(), 14, "a tick of 13.3 ns");
    assert_eq!(
        hello.uncertainty.access.as_nanos(),
        134,
        "a spin's pass and a read: 10 ticks"
    );
    assert_eq!(hello.uncertainty.sampled.as_nanos(), 5_000);
    assert_eq!(hello.uncertainty.polled.as_nanos(), 1_500);
}

#[test]
fn a_chip_fault_behind_the_twin_is_caught() {
    let twin = Served::start(
        "run-twin",
        &["--chip-fault", "swap-error-3-4", "--clock-mhz", "12"],
    );
    let mut t = twin.target();
    assert_eq!(t.hello().straps.sysclk_hz, 12_000_000);
    only_error_3_fails(&mut t);
}

/// Runs a console script (docs/console.md) on `t`; its output.
fn console(t: &mut dyn ppmc::backend::Target, script: &str) -> String {
    let lines = ppmc::console::parse_script(script).expect("the script parses");
    let mut out = Vec::new();
    ppmc::console::run(t, &lines, &Default::default(), &mut out).expect("the script runs");
    String::from_utf8(out).expect("text")
}

/// The time a console line gives (` at <t>`) and its uncertainty
/// (` ±<U>`, 0 when not printed), in ns.
fn stamp(line: &str) -> (u64, u64) {
    let ns = |s: &str| s.parse::<ppmc::time::Duration>().expect(s).as_nanos();
    let (_, rest) = line.rsplit_once(" at ").expect(line);
    match rest.split_once(" \u{b1}") {
        Some((t, u)) => (ns(t), ns(u)),
        None => (ns(rest), 0),
    }
}

/// A stretch of the phases on or off, from the `pins` lines of a console
/// run: from the first sample that saw it to the first that saw the next.
#[derive(Debug)]
struct Stretch {
    on: bool,
    /// Its length as the samples' stamps give it (ns).
    len: u64,
    /// The stamps' uncertainty, both ends together (ns).
    u: u64,
    /// How far each end may lie from the change itself: the gaps from the
    /// sample before each change to the one that saw it, together (ns).
    gaps: u64,
}

/// Every complete stretch in `out`.
fn stretches(out: &str) -> Vec<Stretch> {
    let mut changes = Vec::new();
    let mut last: Option<(bool, u64)> = None;
    for l in out.lines().filter(|l| l.starts_with("pins ")) {
        let on = !l.contains(" s=0b00000 ");
        let (t, u) = stamp(l);
        if let Some((_, before)) = last.filter(|(was, _)| *was != on) {
            changes.push((on, t, u, t - before));
        }
        last = Some((on, t));
    }
    changes
        .windows(2)
        .map(|w| Stretch {
            on: w[0].0,
            len: w[1].1 - w[0].1,
            u: w[0].2 + w[1].2,
            gaps: w[0].3 + w[1].3,
        })
        .collect()
}

#[test]
fn console_stamps_measure_the_chopping_through_the_twin_within_their_uncertainty() {
    // Section 3-5-1: stop switching chops the phases while stopped, ON and
    // OFF for Diagram 3-5's 65 us and 108.75 us by default, and for
    // Equations 3-5/3-6 (VSEL high) or 3-7/3-8 (VSEL low) after the
    // switching parameter command (Pon 10, Poff 20). A console script
    // samples the phases every 250 ns, as docs/console.md shows; each
    // sample's stamp is where the twin read the pins, so the stretches
    // measured from the stamps are the emulator's within the stamps' U
    // plus the script's own sampling step.
    let samples = "pins; wait 250ns\n".repeat(2_400);
    // After the initialization processing (Table 3-3: at most 162.8 ms).
    let init = "wc 0x22; wd 100; wd 20; wd 100; wd 0; await ibf=0; wait 170ms\n";
    let params = "wc 0x84; wd 10; wd 20; await ibf=0\n";
    for (what, args, vsel_high, pre) in [
        ("Diagram 3-5", &[][..], true, ""),
        ("Equations 3-5, 3-6", &[][..], true, params),
        ("Equations 3-7, 3-8", &["--vsel", "low"][..], false, params),
    ] {
        let script = format!("{pre}{init}{samples}");
        let straps = Straps {
            vsel_high,
            ..Straps::default()
        };
        let mut emu = EmuTarget::new(straps, ModelConfig::default()).expect("emulator");
        let want = stretches(&console(&mut emu, &script));
        let twin = Served::start("run-twin", args);
        let mut t = twin.target();
        let got = stretches(&console(&mut t, &script));
        assert!(
            want.len() >= 4 && got.len() >= 4,
            "{what}: {want:?} {got:?}"
        );
        // The same kind of stretch first; then each within the stamps' U
        // and the gaps between samples around its ends (the sampling's own
        // resolution, the emulator's and the twin's).
        let skip = usize::from(got[0].on != want[0].on);
        for (g, w) in got[skip..].iter().zip(&want).take(4) {
            assert_eq!(g.on, w.on, "{what}");
            assert!(g.u > 0, "{what}: a bridge's stamps carry their U");
            let err = g.len.abs_diff(w.len);
            assert!(
                err <= g.u + g.gaps + w.gaps,
                "{what}: {} {} ns on the twin (U {} ns, samples {} ns around its ends), {} ns on the emulator",
                if g.on { "ON" } else { "OFF" },
                g.len,
                g.u,
                g.gaps,
                w.len
            );
        }
        // The twin's samples close enough to hold a stretch to 2 % (the
        // emulator gives the datasheet's figures: scenarios s3_5_1_*), four
        // at least: the console sends the samples in requests of 128, and
        // where one ends, the next one's first reads come a microsecond
        // late (the twin's clock waits for the host; a stretch there says
        // so in its gaps, held above).
        let held = got[skip..]
            .iter()
            .filter(|g| g.u + g.gaps < g.len / 50)
            .count();
        assert!(held >= 4, "{what}: {held} held to 2 %: {got:?}");
    }
}

#[test]
fn console_stamps_measure_a_single_steps_processing_time_within_their_uncertainty() {
    // Section 3-3-3, Table 3-3 (112 us at 16 MHz):
    // docs/examples/single-step-latency.ppmc, `now` before the write,
    // `await busy=0` after it. Through the twin, from the write's stamp to
    // the end of the wait for BUSY = 0, within their U of the emulator's
    // 112 us.
    let script = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../docs/examples/single-step-latency.ppmc"),
    )
    .expect("the example");
    let window = |out: &str| {
        let now = out.lines().find(|l| l.starts_with("now ")).expect(out);
        let fell = out
            .lines()
            .find(|l| l.starts_with("await busy=0"))
            .expect(out);
        let ((a, ua), (b, ub)) = (stamp(now), stamp(fell));
        (b - a, ua + ub)
    };
    let mut emu = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    let (want, u0) = window(&console(&mut emu, &script));
    assert_eq!((want, u0), (112_000, 0), "the emulator's, exact");
    let twin = Served::start("run-twin", &[]);
    let mut t = twin.target();
    let (got, u) = window(&console(&mut t, &script));
    assert!(u > 0, "a bridge's stamps carry their U");
    assert!(
        got.abs_diff(want) <= u,
        "{got} ns on the twin (U {u} ns), {want} ns on the emulator"
    );
}

/// Ctrl-C during the 16,777,216-step move (ten minutes of the chip's
/// time, hours of the twin's), then the next host: the board code stops
/// its wait on the host's ABORT and the move with an Immediate Stop, so
/// the next host opens at once (`docs/bridge-protocol.md` section 5).
#[test]
fn after_a_stop_in_the_long_move_the_next_host_opens_the_twin_at_once() {
    let twin = Served::start("run-twin", &[]);
    common::served::stopped_in_the_long_move_then_reopened(&twin, "e3_data_without_a_command");
}

/// A write of the command (or data) register that waits up to 10 ms for
/// IBF = 0, as the flowcharts write.
fn wc(byte: u8) -> ppmc::backend::Op {
    ppmc::backend::Op::WriteCommand {
        byte,
        wait_ibf: Some(ppmc::time::Duration::from_millis(10)),
    }
}

/// [`wc`] for the data register.
fn wd(byte: u8) -> ppmc::backend::Op {
    ppmc::backend::Op::WriteData {
        byte,
        wait_ibf: Some(ppmc::time::Duration::from_millis(10)),
    }
}

/// Runs `batches` on a fresh twin and on the reference emulator on the
/// twin's timeline (each op begun when the twin began it): the twin's
/// capture, the model's, and the twin's declared uncertainty.
fn on_the_twin_and_the_model(
    batches: &[Vec<ppmc::backend::Op>],
) -> (
    ppmc::protocol::OutputRecord,
    ppmc::protocol::OutputRecord,
    ppmc::backend::Uncertainty,
) {
    use ppmc::backend::{Reply, Target};
    use ppmc::fuzzing::reference::{run_at, starts};
    use ppmc::time::Instant;
    let twin = Served::start("run-twin", &[]);
    let mut t = twin.target();
    let mut emu = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    let (mut twin_at, mut emu_at) = (Instant::ZERO, Instant::ZERO);
    for ops in batches {
        let replies = t.execute(ops).expect("the twin runs it");
        let begun = starts(ops, &replies, twin_at, false);
        let on_emu = run_at(&mut emu, ops, &begun, emu_at).expect("the model runs it");
        twin_at = replies.last().map_or(twin_at, Reply::at);
        emu_at = on_emu.last().map_or(emu_at, Reply::at);
    }
    (
        t.capture().expect("the twin's capture"),
        emu.capture().expect("the model's capture"),
        t.uncertainty(),
    )
}

/// A change of a sampled output is stamped within the `sampled` the board
/// declares, even where the board code sees it as it begins to idle: AUXO
/// set 14 us after its data byte (3-5-5, Table 3-3) just as a software
/// reset comes in (3-5-4), whose phases go off 18 us later. The
/// differential run against the model found AUXO stamped with the
/// phases, 12 us late: the delay's loop saw it on entering the hardware's
/// idle and slept to the next change. The model's moment is the reference
/// emulator's, run on the twin's timeline (each op begun when the twin
/// began it).
#[test]
fn a_sampled_change_seen_as_the_board_code_idles_is_stamped_within_its_uncertainty() {
    use ppmc::backend::Op;
    use ppmc::protocol::Pin;
    use ppmc::time::{Duration, Instant};
    let (got, want, u) = on_the_twin_and_the_model(&[
        vec![Op::Reset],
        vec![wc(0x02), wd(100), wd(20), wd(100), wd(0), Op::ReadStatus],
        vec![Op::Delay(Duration::from_millis(20)), Op::ReadStatus],
        vec![wc(0x86), wd(0x04), Op::ReadStatus],
        vec![wc(0xC0), Op::ReadStatus],
        vec![Op::Delay(Duration::from_millis(1)), Op::ReadStatus],
    ]);
    let auxo = |r: &ppmc::protocol::OutputRecord| -> Vec<Instant> {
        r.pins
            .iter()
            .filter(|e| e.pin == Pin::Auxo)
            .map(|e| e.at)
            .collect()
    };
    let (got, want) = (auxo(&got), auxo(&want));
    assert_eq!((got.len(), want.len()), (1, 1), "{got:?} {want:?}");
    let off = got[0]
        .saturating_since(want[0])
        .max(want[0].saturating_since(got[0]));
    assert!(
        off <= u.sampled + u.access,
        "AUXO at {} on the twin, {} in the model: {off} off, declared within {} (and {} for the write)",
        got[0],
        want[0],
        u.sampled,
        u.access
    );
}

/// Section 3-5-1 through the board code: an initialization that asks for
/// stop switching (bit 5), then 30 ms in a wait for OBF that never comes
/// (the board code looks at the outputs at every pass and samples them
/// every 200 us). The twin reports SWITCHING on once, at the chopping's
/// first edge (Diagram 3-5's 65 us ON stretch after the model's HOLD ON,
/// within its sampled uncertainty), and no phase change after the
/// initialization's: sampled alone, the 174 us chopping beat with the
/// 200 us samples, and the board code recorded a phase change every
/// 12 ms, all to the same pattern (the differential run found it).
#[test]
fn stop_switching_is_reported_once_from_its_first_edge_however_the_samples_fall() {
    use ppmc::backend::Op;
    use ppmc::protocol::{OutputRecord, Pin};
    use ppmc::time::{Duration, Instant};
    let (got, want, u) = on_the_twin_and_the_model(&[
        vec![Op::Reset],
        vec![wc(0x22), wd(100), wd(20), wd(100), wd(0), Op::ReadStatus],
        vec![
            Op::ReadData {
                wait_obf: Some(Duration::from_millis(30)),
            },
            Op::ReadStatus,
        ],
    ]);
    let of = |r: &OutputRecord, pin: Pin| -> Vec<(Instant, u8)> {
        r.pins
            .iter()
            .filter(|e| e.pin == pin)
            .map(|e| (e.at, e.value))
            .collect()
    };
    let (chop, model_chop) = (of(&got, Pin::Switching), of(&want, Pin::Switching));
    assert_eq!(
        model_chop.len(),
        1,
        "the model chops to the end: {model_chop:?}"
    );
    assert_eq!(chop.len(), 1, "SWITCHING on once: {chop:?}");
    let values = |v: Vec<(Instant, u8)>| v.into_iter().map(|(_, x)| x).collect::<Vec<u8>>();
    assert_eq!(
        values(of(&got, Pin::Phases)),
        values(of(&want, Pin::Phases)),
        "the phase pattern changes only where the model's does: {:?}",
        of(&got, Pin::Phases)
    );
    let late = chop[0].0.saturating_since(model_chop[0].0);
    let first_edge = Duration::from_micros(65);
    assert!(
        chop[0].0 >= model_chop[0].0
            && late.max(first_edge).saturating_sub(late.min(first_edge)) <= u.sampled + u.access,
        "SWITCHING on at {} on the twin, {} in the model: {late} after, the first edge {first_edge} after",
        chop[0].0,
        model_chop[0].0
    );
}

/// Issue 45: a guided campaign against the twin (the bridge's own board
/// code in front of a clean chip), each input from a chip reset, judged
/// by the invariants and against the model on the twin's timeline, runs
/// at least 40 executions per board-second (70 % of the chip's floor of
/// about 60 with an initialization each, Table 3-3's 16.5 ms) and spends
/// its whole budget of the twin's time.
#[test]
fn a_guided_campaign_on_the_twin_runs_40_executions_per_board_second() {
    use ppmc::fuzzing::guided::{self, Event, Settings};
    use ppmc::time::Duration;
    let twin = Served::start("run-twin", &[]);
    let mut t = twin.target();
    // The seeds `ppmc fuzz campaign` starts from: the suite's bus traffic.
    let seeds = ppmc::fuzzing::seeds::suite_traffic(&ppmc_scenarios::all()).expect("the seeds");
    let s = Settings {
        budget: Duration::from_secs(3),
        max_input_time: Duration::from_millis(25),
        ..Settings::default()
    };
    let mut findings = Vec::new();
    let stats = guided::run(&mut t, None, &seeds, &s, |e| {
        if let Event::Finding(f) = e {
            findings.push(f.what.to_string());
        }
        true
    })
    .expect("the campaign runs");
    // Not asserted: what it finds. On this good board it raises false
    // alarms of kinds named in docs/performance.md ("Against the twin"):
    // the judges do not yet take every path of the bridge's uncertainty
    // into account (moves recorded from the bus, among others).
    eprintln!(
        "{} findings on the clean twin: {findings:#?}",
        findings.len()
    );
    assert!(
        stats.per_board_second() >= 40.0,
        "{:.1} executions per board-second: {stats:?}",
        stats.per_board_second()
    );
    assert!(stats.board_time >= s.budget, "{stats:?}");
}

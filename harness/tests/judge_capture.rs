//! Judging a board from a capture of its bus and pins (issue 30): the
//! suite's scenarios, run on the emulator, exported with the bus as a
//! logic analyzer would record them (`ppmc export --bus`), and judged
//! against the reference model. A clean board passes; a faulty one
//! (`ppmc::faults`) fails, blamed on the board, at its first divergence.

use ppmc::backend::EmuTarget;
use ppmc::emu::ModelConfig;
use ppmc::judge::{judge, JudgeOptions, Verdict};
use ppmc::logic::map::ChannelMap;
use ppmc::logic::source::{Change, LogicError, LogicInfo, LogicSource};
use ppmc::protocol::Straps;
use ppmc::scenario::{run_scenario, DriverOptions};
use ppmc::trace::Trace;
use ppmc::vcd_export::{export_with, Export};
use vcd::{Command, IdCode, Parser, Value};

/// A VCD of our own export as a change stream (1 ns timescale).
struct VcdChanges {
    info: LogicInfo,
    changes: std::vec::IntoIter<Change>,
    end_ps: u64,
}

impl VcdChanges {
    fn new(buf: &[u8]) -> VcdChanges {
        let mut parser = Parser::new(buf);
        let header = parser.parse_header().expect("header");
        let vars: Vec<(IdCode, String)> = header
            .items
            .iter()
            .flat_map(|i| match i {
                vcd::ScopeItem::Scope(s) => s.items.clone(),
                other => vec![other.clone()],
            })
            .filter_map(|i| match i {
                vcd::ScopeItem::Var(v) => Some((v.code, v.reference.clone())),
                _ => None,
            })
            .collect();
        let (mut now, mut levels, mut out) = (0u64, 0u64, Vec::<Change>::new());
        let flush = |now: u64, levels: u64, out: &mut Vec<Change>| {
            if out.last().is_none_or(|l| l.levels != levels) {
                out.push(Change {
                    time_ps: now * 1000,
                    levels,
                    unknown: 0,
                });
            }
        };
        for cmd in parser {
            match cmd.expect("body") {
                Command::Timestamp(t) => {
                    flush(now, levels, &mut out);
                    now = t;
                }
                Command::ChangeScalar(id, v) => {
                    let k = vars.iter().position(|(c, _)| *c == id).expect("declared");
                    levels = (levels & !(1 << k)) | (u64::from(v == Value::V1) << k);
                }
                _ => {}
            }
        }
        flush(now, levels, &mut out);
        VcdChanges {
            info: LogicInfo {
                channels: vars.into_iter().map(|(_, n)| n).collect(),
                resolution_ps: 1000,
                sample_rate_hz: None,
                format: "VCD (ppmc export --bus)".into(),
            },
            changes: out.into_iter(),
            end_ps: now * 1000,
        }
    }
}

impl LogicSource for VcdChanges {
    fn info(&self) -> &LogicInfo {
        &self.info
    }
    fn next_change(&mut self) -> Result<Option<Change>, LogicError> {
        Ok(self.changes.next())
    }
    fn end_ps(&self) -> u64 {
        self.end_ps
    }
}

/// The trace of `name` on a model with `cfg`.
fn trace_of(name: &str, cfg: ModelConfig) -> Trace {
    let suite = ppmc_scenarios::all();
    let s = suite.iter().find(|s| s.name == name).expect("scenario");
    // A host on a real bus: every access takes a bus cycle.
    let mut t = EmuTarget::new(Straps::default(), cfg)
        .expect("emulator")
        .with_bus_cycle(ppmc::time::Duration::from_nanos(
            ppmc::vcd_export::BUS_CYCLE,
        ));
    let r = run_scenario(&mut t, s, DriverOptions::default());
    r.trace.expect("a trace")
}

fn capture_of(trace: &Trace) -> VcdChanges {
    let mut buf = Vec::new();
    export_with(
        trace,
        Export {
            window: None,
            bus: true,
        },
        &mut buf,
    )
    .expect("export");
    VcdChanges::new(&buf)
}

fn judged(trace: &Trace) -> ppmc::judge::Judgement {
    let mut cap = capture_of(trace);
    let map = ChannelMap::from_names(cap.info()).expect("our names");
    judge(&mut cap, &map, &JudgeOptions::default()).expect("judged")
}

/// Sections 3-3 (moves), 3-4 (register reads), 3-2 (initialization): a
/// clean board's captures pass, every pulse compared. The host of
/// `e4_accel_pulses_11221` misuses the chip on purpose: its findings are
/// the host firmware's (3-2-2, then 3-2), not the board's.
#[test]
fn a_clean_boards_captures_pass() {
    for (name, host) in [
        ("s3_3_5_constant_speed_100_steps", &[][..]),
        ("s3_3_1_immediate_stop_of_accel_move", &[]),
        ("e4_accel_pulses_11221", &["3-2-2", "3-2"]),
    ] {
        let trace = trace_of(name, ModelConfig::default());
        let pulses: u64 = trace
            .events
            .iter()
            .filter_map(|e| match e.kind {
                ppmc::trace::EventKind::Pulses { count, .. } => Some(u64::from(count)),
                _ => None,
            })
            .sum();
        let j = judged(&trace);
        assert_eq!(j.verdict, Verdict::Passed, "{name}: {j:?}");
        assert!(j.accesses > 5, "{name}: {j:?}");
        assert_eq!(j.pulses, pulses, "{name}");
        let sections: Vec<&str> = j.host.iter().map(|h| h.section).collect();
        assert_eq!(sections, host, "{name}: {:?}", j.host);
    }
}

/// A board that loses the last pulse of a move (3-3), whose status reads
/// a stuck bit (3-1-1), or whose DIR line is inverted (3-3), fails, blamed
/// on the board.
#[test]
fn a_faulty_boards_capture_fails_at_its_first_divergence() {
    for (fault, scenario, what) in [
        (
            "drop-last-pulse",
            "s3_3_5_constant_speed_100_steps",
            "POUT pulse",
        ),
        (
            "status-stuck-0x04",
            "s3_3_5_constant_speed_100_steps",
            "status read",
        ),
    ] {
        let mut cfg = ModelConfig::default();
        ppmc::faults::apply_all(&[fault.to_string()], &mut cfg).expect("fault");
        let trace = trace_of(scenario, cfg);
        let j = judged(&trace);
        match &j.verdict {
            Verdict::Failed(d) => assert!(d.what.starts_with(what), "{fault}: {d}"),
            other => panic!("{fault}: {other:?}"),
        }
    }
}

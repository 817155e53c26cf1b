//! The fault matrix's capture column (issue 30, `docs/capture.md`): a
//! board judged from logic-analyzer captures, as `ppmc judge` judges one.
//! Each scenario of the suite runs on the emulator with the board's model
//! and a 200 ns bus cycle (a host on a real bus), is exported with the bus
//! and every pin drawn (`ppmc export --bus`), read back by the project's
//! own VCD reader and judged against the clean reference model. The first
//! scenario judged `Failed` (a board divergence) is the catch; host
//! findings are the firmware's, not the board's, and are no catch.
//!
//! A capture is what a logic analyzer records, so a scenario that lasts
//! longer than [`LONGEST`] of chip time is not judged: nobody records the
//! 16,777,216-step move's 706 s (665 MB of VCD). The skipped ones are
//! named in the column's notes.
//!
//! For each fault the column misses, [`why_missed`] says why. The judge
//! compares every pin a capture has (the bus, POUT, DIR, INT*, BUSY,
//! HOLD, AUX*, AUXO0..3 and S1..S5), so a fault it misses is one no
//! capture of the chip's bus and pins can show.

use super::Catch;
use crate::judge::{judge, CaptureVerdict, JudgeOptions};
use ppmc::backend::{EmuTarget, Op, Reply, Target, TargetError, TargetInfo};
use ppmc::emu::ModelConfig;
use ppmc::protocol::{Flag, OutputRecord, Straps};
use ppmc::scenario::{run_scenario, DriverOptions, Scenario};
use ppmc::time::Duration;
use ppmc::trace::{BusEvent, Event, EventKind, Trace};
use ppmc::vcd_export::{export_with, Export, BUS_CYCLE};
use ppmc_core::bus::HostTiming;
use ppmc_logic::map::ChannelMap;
use ppmc_logic::source::LogicSource;
use ppmc_logic::vcd::VcdReader;
use std::path::Path;
use std::time::Instant as WallClock;

/// The longest scenario judged from its capture, in chip time: a logic
/// analyzer's recording, not a 706 s one.
pub const LONGEST: Duration = Duration::from_secs(10);

/// A scenario whose capture was not judged: it lasts longer than
/// [`LONGEST`] on this board.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Skipped {
    pub scenario: &'static str,
    /// The scenario's chip time on this board.
    pub lasts: Duration,
}

impl std::fmt::Display for Skipped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} (lasts {:.0} s of chip time: a logic analyzer capture of that length is not made)",
            self.scenario,
            self.lasts.as_secs_f64()
        )
    }
}

/// What the capture column made of a board.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CaptureColumn {
    /// The first scenario judged `Failed`: `<scenario>: <divergence>`.
    pub catch: Option<Catch>,
    /// Scenarios judged (up to and including the catch).
    pub judged: usize,
    /// Scenarios not judged, as too long for a capture.
    pub skipped: Vec<Skipped>,
}

/// The harness failed to make or read one of its own captures: an error
/// of ours, never a verdict on the board.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the capture of {scenario}: {why}")]
pub struct CaptureError {
    pub scenario: String,
    pub why: String,
}

/// Judges `suite`'s captures of a board with `model` (the clean model, or
/// a fault's), stopping at the first scenario judged `Failed`.
pub fn judge_captures(
    model: &ModelConfig,
    suite: &[Scenario],
) -> Result<CaptureColumn, CaptureError> {
    let t0 = WallClock::now();
    let err = |scenario: &str, why: String| CaptureError {
        scenario: scenario.to_string(),
        why,
    };
    // A scenario may end with the chip waiting for what never comes (an
    // external clock no one drives): what its capture holds is judged.
    let opts = JudgeOptions {
        partial: true,
        ..JudgeOptions::default()
    };
    let mut column = CaptureColumn::default();
    for s in suite {
        let (trace, lasts) = analyzer_trace(model, s).map_err(|e| err(s.name, e))?;
        if lasts > LONGEST {
            column.skipped.push(Skipped {
                scenario: s.name,
                lasts,
            });
            continue;
        }
        let mut vcd = Vec::new();
        export_with(
            &trace,
            Export {
                window: None,
                bus: true,
            },
            &mut vcd,
        )
        .map_err(|e| err(s.name, format!("export: {e}")))?;
        let mut source = VcdReader::new(&vcd[..], Path::new(s.name))
            .map_err(|e| err(s.name, format!("read back: {e}")))?;
        let map = ChannelMap::from_names(source.info())
            .map_err(|e| err(s.name, format!("channel map: {e}")))?;
        let j = judge(&mut source, &map, &opts).map_err(|e| err(s.name, e.to_string()))?;
        column.judged += 1;
        match j.verdict {
            CaptureVerdict::Passed => {}
            CaptureVerdict::Failed(d) => {
                column.catch = Some(Catch {
                    first: format!("{}: {d}", s.name),
                    after: t0.elapsed(),
                });
                return Ok(column);
            }
            // Our own export, blamed as a capture: the harness's fault.
            CaptureVerdict::Capture(why) => {
                return Err(err(s.name, format!("judged as a bad capture: {why}")))
            }
        }
    }
    Ok(column)
}

/// Scenario `s` run on the emulator with `model` as a host on a real bus
/// runs it, every register access taking a bus cycle, and recorded as a
/// logic analyzer on the bus and pins records it (`Analyzer`): every
/// access the chip served and everything it put out. With how long it
/// ran. What `ppmc export --scenario` writes, and what this column judges.
pub fn analyzer_trace(model: &ModelConfig, s: &Scenario) -> Result<(Trace, Duration), String> {
    analyzer_trace_with(model, s, HostTiming::Polling)
}

/// [`analyzer_trace`] with a host that times its waited accesses as
/// `host` says (`ppmc export --host exact`: each byte written the instant
/// the chip allows it).
pub fn analyzer_trace_with(
    model: &ModelConfig,
    s: &Scenario,
    host: HostTiming,
) -> Result<(Trace, Duration), String> {
    let emu = EmuTarget::new(Straps::default(), model.clone())
        .map_err(|e| format!("the emulator: {e}"))?
        .with_bus_cycle(Duration::from_nanos(BUS_CYCLE))
        .with_host_timing(host);
    let mut target = Analyzer {
        emu,
        bus: Vec::new(),
    };
    let r = run_scenario(&mut target, s, DriverOptions::default());
    // The analyzer is stopped once the board is at rest, as an engineer
    // stops it: a scenario that ends while its move runs on is recorded
    // to the move's end (at most LONGEST on), with no access of the host
    // (the wait is the emulator's, not a poll on the bus). A capture that
    // stops mid-move is the capture's problem (`ppmc judge --partial`).
    let _ = target
        .emu
        .execute(&[Op::await_flag(Flag::Busy, false, LONGEST)]);
    let trace = target
        .trace(s)
        .map_err(|e| format!("the emulator's capture: {e}"))?;
    Ok((trace, r.elapsed))
}

/// The emulator with every register access it served logged, as a logic
/// analyzer on the bus records them. The scenario's own trace will not
/// do: it logs the bus only up to a scenario's first failing step, though
/// the steps queued after it ran on the chip too (`Batch::flush`), so the
/// capture of a failed scenario would show pins going on beside a bus
/// gone quiet, and the judge would blame the board for the writes missing.
struct Analyzer {
    emu: EmuTarget,
    /// The accesses since the last reset, at their replies' times.
    bus: Vec<Event>,
}

impl Analyzer {
    /// The scenario just run, as a logic analyzer saw it: every access
    /// since the reset and everything the chip put out.
    fn trace(&mut self, s: &Scenario) -> Result<Trace, TargetError> {
        let info = self.emu.info();
        let record = self.emu.capture()?;
        Ok(
            Trace::new(s.name, s.section, &info.name, info.straps, info.extra).assemble(
                std::mem::take(&mut self.bus),
                &record,
                Vec::new(),
            ),
        )
    }
}

impl Target for Analyzer {
    fn info(&self) -> TargetInfo {
        self.emu.info()
    }

    fn capture(&mut self) -> Result<OutputRecord, TargetError> {
        self.emu.capture()
    }

    fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError> {
        let replies = self.emu.execute(ops)?;
        for (op, reply) in ops.iter().zip(&replies) {
            // The capture, and the chip's time, start again at a reset.
            if matches!(op, Op::Reset) {
                self.bus.clear();
            }
            if let Some(e) = BusEvent::of(op, reply) {
                self.bus.push(Event {
                    at: reply.at(),
                    kind: EventKind::Bus(e),
                });
            }
        }
        Ok(replies)
    }
}

/// Why the capture column misses a fault.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unseen {
    /// No capture of the chip's bus and pins shows it.
    CannotShow(&'static str),
}

impl std::fmt::Display for Unseen {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unseen::CannotShow(why) => write!(f, "a capture cannot show it: {why}"),
        }
    }
}

/// Why the capture column misses `fault`, for the faults it misses now;
/// `None` for the faults it catches (and names it does not know). As the
/// judge compares more pins, entries leave this table.
pub fn why_missed(fault: &str) -> Option<Unseen> {
    MISSED
        .iter()
        .find(|(name, _)| *name == fault)
        .map(|&(_, why)| why)
}

/// The faults the column misses, and why: none today. Every one of the
/// catalogue's 27 shows on the bus or a pin the judge compares (the status
/// and data reads, POUT's pulses, DIR at each, INT*, BUSY, HOLD, AUX*,
/// AUXO and S1..S5). A fault added to the catalogue that no capture can
/// show would be entered here, with why.
const MISSED: &[(&str, Unseen)] = &[];

/// The capture column's notes under the matrix: the scenarios not judged
/// and why, and why each fault it misses is missed.
pub fn notes(rows: &[super::Row]) -> String {
    let mut s = format!(
        "Captures: each scenario run on the emulator with the board's model and a {BUS_CYCLE} ns \
         bus cycle, exported with the bus and every pin (`ppmc export --bus`) and judged as \
         `ppmc judge` does, against the clean model; the cell is the time to the first \
         scenario judged FAIL.\n"
    );
    let mut skipped: Vec<(&str, Duration, Vec<&str>)> = Vec::new();
    for r in rows {
        for k in &r.capture_skipped {
            match skipped.iter_mut().find(|(n, _, _)| *n == k.scenario) {
                Some((_, lasts, boards)) => {
                    *lasts = (*lasts).max(k.lasts);
                    boards.push(&r.board);
                }
                None => skipped.push((k.scenario, k.lasts, vec![&r.board])),
            }
        }
    }
    for (scenario, lasts, boards) in skipped {
        let on = if boards.len() == rows.len() {
            "every board".to_string()
        } else {
            boards.join(", ")
        };
        s.push_str(&format!(
            "- not judged: `{scenario}` lasts up to {:.0} s of chip time (on {on}): a logic \
             analyzer capture of {:.0} s is not made (longest judged: {} s)\n",
            lasts.as_secs_f64(),
            lasts.as_secs_f64(),
            LONGEST.as_secs_f64()
        ));
    }
    for r in rows
        .iter()
        .filter(|r| r.board != "clean" && r.capture.is_none())
    {
        let why = why_missed(&r.board).map_or_else(
            || "MISSED, with no reason on file (`fault_matrix::capture::MISSED`)".to_string(),
            |u| u.to_string(),
        );
        s.push_str(&format!("- `{}` missed: {why}\n", r.board));
    }
    s
}

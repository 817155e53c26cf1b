//! Recovery by power (`backend::power`, the runner's health check): a
//! board that hangs under a scenario is power-cycled once, reached again,
//! and the run goes on from the next scenario; a scenario in flight that
//! ended in an error is an infrastructure error naming the hang. A board
//! that cannot be brought back is lost, and says why.
//!
//! The boards here are the emulator behind a wrapper that hangs on cue,
//! in both ways a board hangs: its bridge silent, or its chip still BUSY
//! after a chip reset (3-1-1: a reset ends any move, so a chip BUSY past
//! it is past its longest legal move; the scenario that met it stays the
//! board's failure). The switch is a real command.

use ppmc::backend::{
    BridgeError, EmuTarget, Op, Power, PowerOptions, Reply, Target, TargetError, TargetErrorKind,
    TargetInfo, TargetSpec,
};
use ppmc::protocol::{OutputRecord, Status};
use ppmc::runner::{stream_on_boards, BoardResult, Spread};
use ppmc::scenario::{Driver, DriverOptions, HarnessError, NotRun, Outcome, Scenario, Verdict};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Hang {
    /// The bridge answers nothing.
    Silent,
    /// Every status read has BUSY set, a chip reset too.
    Busy,
    /// Another host took the bridge over: no hang, nothing to cycle.
    Displaced,
}

/// The emulator, hung from its `at`-th batch on until its power is cycled
/// (`power_cycle`, which counts batches from 0 again), as often as `times`
/// says. Each scenario of [`suite`] is one batch.
struct Hanging {
    emu: EmuTarget,
    how: Hang,
    at: u32,
    batches: u32,
    hung: bool,
    /// Hangs still to come.
    times: u32,
    restarts: Arc<AtomicU32>,
}

impl Hanging {
    fn boxed(how: Hang, at: u32, times: u32, restarts: &Arc<AtomicU32>) -> Box<dyn Target> {
        Box::new(Hanging {
            emu: EmuTarget::new(Default::default(), Default::default()).expect("emulator"),
            how,
            at,
            batches: 0,
            hung: false,
            times,
            restarts: restarts.clone(),
        })
    }
}

impl Target for Hanging {
    fn info(&self) -> TargetInfo {
        self.emu.info()
    }

    fn capture(&mut self) -> Result<OutputRecord, TargetError> {
        match (self.hung, self.how) {
            (true, Hang::Silent | Hang::Displaced) => Err(silent()),
            _ => self.emu.capture(),
        }
    }

    fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError> {
        self.batches += 1;
        if self.batches >= self.at && self.times > 0 && !self.hung {
            self.hung = true;
            self.times -= 1;
        }
        match (self.hung, self.how) {
            (false, _) => self.emu.execute(ops),
            (true, Hang::Silent) => Err(silent()),
            (true, Hang::Displaced) => Err(BridgeError::Displaced {
                link: "serial:/dev/bench".into(),
            }
            .into()),
            (true, Hang::Busy) => Ok(self
                .emu
                .execute(ops)?
                .into_iter()
                .map(|r| match r {
                    Reply::Status { at, status } => Reply::Status {
                        at,
                        status: Status(status.0 | Status::BUSY),
                    },
                    other => other,
                })
                .collect()),
        }
    }

    fn power_cycle(
        &mut self,
        cycle: &mut dyn FnMut() -> Result<(), String>,
        _: std::time::Duration,
    ) -> Result<(), TargetError> {
        cycle().map_err(|e| TargetError::new(TargetErrorKind::Other, e))?;
        self.restarts.fetch_add(1, Ordering::SeqCst);
        self.hung = false;
        self.batches = 0;
        self.emu = EmuTarget::new(Default::default(), Default::default()).expect("emulator");
        Ok(())
    }
}

fn silent() -> TargetError {
    TargetError::new(
        TargetErrorKind::Link,
        "serial:/dev/bench: no bridge answering",
    )
}

/// Reads the status, which must not be BUSY: a scenario a hung chip fails.
fn idle(d: &mut Driver) -> Outcome {
    d.reset()?;
    let s = d.status()?;
    d.check("BUSY after a chip reset", false, s.busy())
}

fn suite() -> Vec<Scenario> {
    ["a", "b", "c", "d", "e", "f"]
        .iter()
        .map(|n| Scenario::new(n, "3-1-1", "", &[], idle))
        .collect()
}

/// A power switch: a script that logs each cycle in `dir` with the
/// board's name, and fails when `fail` says so.
fn switch(dir: &Path, cycles: u32, fail: bool) -> Power {
    let log = dir.join("power.log");
    let script = dir.join("power.sh");
    std::fs::write(
        &script,
        format!(
            "#!/bin/sh\necho \"$PPMC_BOARD $1\" >> '{}'\n{}\n",
            log.display(),
            if fail {
                "echo relay 3 does not answer >&2; exit 1"
            } else {
                ""
            }
        ),
    )
    .expect("works");
    let spec = TargetSpec::parse("serial:/dev/bench,name=bench-1").expect("works");
    Power::of(
        &spec,
        &PowerOptions {
            cmd: Some(format!("sh '{}'", script.display())),
            cycles,
            ..PowerOptions::default()
        },
        &Default::default(),
    )
    .expect("a switch")
}

fn run(board: Box<dyn Target>, power: Option<Power>) -> Vec<BoardResult> {
    let mut all = Vec::new();
    stream_on_boards(
        &mut [board],
        &mut [power],
        &suite(),
        1,
        DriverOptions::default(),
        Spread::Share,
        || false,
        |_, _, _| {},
        |r| all.push(r),
    );
    all.sort_by_key(|r| r.slot);
    all
}

fn scratch() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("works");
    let p = dir.path().to_path_buf();
    (dir, p)
}

/// Each result's verdict, as the reports spell it.
fn labels(r: &[BoardResult]) -> Vec<&'static str> {
    r.iter().map(|r| r.result.verdict.label()).collect()
}

fn hung(r: &BoardResult) -> Option<(&str, &str)> {
    match &r.result.verdict {
        Verdict::Error(HarnessError::Hung { hang, recovery }) => Some((hang, recovery)),
        _ => None,
    }
}

fn log(dir: &Path) -> String {
    std::fs::read_to_string(dir.join("power.log")).unwrap_or_default()
}

#[test]
fn a_silent_bridge_is_power_cycled_once_and_the_run_goes_on() {
    let (_keep, dir) = scratch();
    let restarts = Arc::new(AtomicU32::new(0));
    let r = run(
        Hanging::boxed(Hang::Silent, 2, 1, &restarts),
        Some(switch(&dir, 3, false)),
    );
    let verdicts = labels(&r);
    assert_eq!(
        verdicts,
        ["passed", "error", "passed", "passed", "passed", "passed"]
    );
    let (hang, recovery) = hung(&r[1]).expect("the scenario in flight names the hang");
    assert!(
        hang.starts_with("its bridge stopped answering (serial:/dev/bench: no bridge answering"),
        "{hang}"
    );
    assert!(recovery.starts_with("power-cycled by `sh '"), "{recovery}");
    assert!(
        recovery.ends_with("power.sh' cycle` (1 of 3)"),
        "{recovery}"
    );
    // Whose it is: the infrastructure's, never the board's.
    let record = r[1].result.verdict.error_record().expect("works");
    assert_eq!(record.kind, ppmc_record::ErrorKind::Infrastructure);
    assert!(record
        .message
        .starts_with("the board hung: its bridge stopped answering"));
    assert_eq!(
        log(&dir),
        "bench-1 cycle\n",
        "one cycle, with the board's name"
    );
    assert_eq!(restarts.load(Ordering::SeqCst), 1);
}

/// A chip BUSY after a chip reset breaks 3-1-1: the scenario that met it
/// stays the board's failure, and says that the board was power-cycled;
/// the run goes on.
#[test]
fn a_chip_busy_after_its_reset_is_power_cycled_and_stays_the_boards_failure() {
    let (_keep, dir) = scratch();
    let restarts = Arc::new(AtomicU32::new(0));
    let r = run(
        Hanging::boxed(Hang::Busy, 4, 1, &restarts),
        Some(switch(&dir, 3, false)),
    );
    let verdicts = labels(&r);
    assert_eq!(
        verdicts,
        ["passed", "passed", "passed", "failed", "passed", "passed"]
    );
    let Verdict::Failed(f) = &r[3].result.verdict else {
        unreachable!()
    };
    assert_eq!(f.expectation, "BUSY after a chip reset");
    assert!(
        f.got.starts_with(
            "true; then the chip stayed BUSY after a chip reset (status 0x04), and the board was power-cycled by `sh '"
        ) && f.got.ends_with("power.sh' cycle` (1 of 3)"),
        "{}",
        f.got
    );
    assert_eq!(log(&dir), "bench-1 cycle\n");
    assert_eq!(restarts.load(Ordering::SeqCst), 1);
}

/// A labgrid place without a power resource, or a relay that does not
/// answer: a chip BUSY after its reset is then left to the next
/// scenario's reset, as without a switch, and the board is not lost.
#[test]
fn a_busy_chip_whose_switch_fails_is_left_as_without_one() {
    let (_keep, dir) = scratch();
    let restarts = Arc::new(AtomicU32::new(0));
    let r = run(
        Hanging::boxed(Hang::Busy, 2, 1, &restarts),
        Some(switch(&dir, 3, true)),
    );
    assert!(
        r.iter()
            .skip(1)
            .all(|r| matches!(r.result.verdict, Verdict::Failed(_))),
        "{r:#?}"
    );
    assert_eq!(restarts.load(Ordering::SeqCst), 0);
}

/// What is no hang is never power-cycled: another host on the bridge
/// loses the board as it always did.
#[test]
fn a_bridge_another_host_took_is_not_power_cycled() {
    let (_keep, dir) = scratch();
    let restarts = Arc::new(AtomicU32::new(0));
    let r = run(
        Hanging::boxed(Hang::Displaced, 2, 1, &restarts),
        Some(switch(&dir, 3, false)),
    );
    let verdicts = labels(&r);
    assert_eq!(
        verdicts,
        ["passed", "error", "not run", "not run", "not run", "not run"]
    );
    assert_eq!(log(&dir), "", "no cycle");
    assert_eq!(restarts.load(Ordering::SeqCst), 0);
}

#[test]
fn without_a_switch_a_silent_bridge_is_lost_and_a_busy_chip_is_the_boards_failure() {
    let restarts = Arc::new(AtomicU32::new(0));
    let r = run(Hanging::boxed(Hang::Silent, 2, 1, &restarts), None);
    let verdicts = labels(&r);
    assert_eq!(
        verdicts,
        ["passed", "error", "not run", "not run", "not run", "not run"]
    );
    assert!(matches!(
        r[2].result.verdict,
        Verdict::NotRun(NotRun::TargetLost(_))
    ));

    let r = run(Hanging::boxed(Hang::Busy, 2, 1, &restarts), None);
    assert!(
        r.iter()
            .skip(1)
            .all(|r| matches!(r.result.verdict, Verdict::Failed(_))),
        "{r:#?}"
    );
    assert_eq!(restarts.load(Ordering::SeqCst), 0);
}

#[test]
fn a_board_past_its_cycles_or_whose_switch_fails_is_lost_and_says_why() {
    // Hangs twice, may be cycled once.
    let (_keep, dir) = scratch();
    let restarts = Arc::new(AtomicU32::new(0));
    let r = run(
        Hanging::boxed(Hang::Silent, 2, 2, &restarts),
        Some(switch(&dir, 1, false)),
    );
    let verdicts = labels(&r);
    assert_eq!(
        verdicts,
        ["passed", "error", "error", "not run", "not run", "not run"],
        "{r:#?}"
    );
    assert!(hung(&r[1]).is_some() && hung(&r[2]).is_none());
    let Verdict::NotRun(NotRun::TargetLost(why)) = &r[3].result.verdict else {
        panic!("{:?}", r[3].result.verdict)
    };
    assert!(
        why.ends_with("the board has had the 1 power cycles it may have in a run (--power-cycles)"),
        "{why}"
    );

    let (_keep, dir) = scratch();
    let r = run(
        Hanging::boxed(Hang::Silent, 2, 1, &restarts),
        Some(switch(&dir, 3, true)),
    );
    let Verdict::NotRun(NotRun::TargetLost(why)) = &r[2].result.verdict else {
        panic!("{:?}", r[2].result.verdict)
    };
    assert!(
        why.contains("; its power cycle failed: `sh '")
            && why.ends_with("relay 3 does not answer)"),
        "{why}"
    );
}

/// Issue 45: a board that hangs mid-campaign (silent, or its chip BUSY
/// after a chip reset) is brought back by its switch, the input it hung
/// under is kept as a finding, and the campaign goes on to its budget.
#[test]
fn a_board_that_hangs_mid_campaign_is_brought_back_and_the_campaign_goes_on() {
    use ppmc::bus_program::{self, BusOp};
    use ppmc::fuzzing::guided::{self, Event, Settings, What};
    let seeds = vec![bus_program::encode(&[
        BusOp::Command(0x00),
        BusOp::ReadStatus,
    ])];
    let settings = Settings {
        budget: ppmc::time::Duration::from_millis(300),
        ..Settings::default()
    };
    for how in [Hang::Silent, Hang::Busy] {
        let (_keep, dir) = scratch();
        let restarts = Arc::new(AtomicU32::new(0));
        let mut board = Hanging::boxed(how, 5, 1, &restarts);
        let mut power = switch(&dir, 3, false);
        let mut hangs = Vec::new();
        let stats = guided::run(board.as_mut(), Some(&mut power), &seeds, &settings, |e| {
            if let Event::Finding(f) = e {
                if let What::Hang { hang, recovery } = &f.what {
                    hangs.push((hang.clone(), recovery.clone()));
                }
            }
            true
        })
        .unwrap_or_else(|e| panic!("{how:?}: the campaign ended: {e}"));
        assert_eq!(hangs.len(), 1, "{how:?}: {stats:?}");
        let (hang, recovery) = &hangs[0];
        match how {
            Hang::Silent => assert!(hang.starts_with("its bridge stopped answering ("), "{hang}"),
            _ => assert_eq!(
                hang,
                "its chip stayed BUSY after a chip reset (status 0x04)"
            ),
        }
        assert!(recovery.starts_with("power-cycled by `sh '"), "{recovery}");
        assert_eq!(restarts.load(Ordering::SeqCst), 1);
        assert!(stats.board_time >= settings.budget, "went on: {stats:?}");
        assert_eq!(log(&dir), "bench-1 cycle\n");
    }
}

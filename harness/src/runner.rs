//! Running a suite: choosing scenarios, running them one after another on
//! a target, and keeping going when one fails or errors; on several boards
//! at once ([`run_on_boards`], [`stream_on_boards`]), opened together as a
//! [`Farm`], which keeps the boards it could not reach out of the verdict.

use crate::backend::power::{busy_after_reset, silent, CycleError};
use crate::backend::{self, OpenError, OpenOptions, Power, Target, TargetInfo, TargetSpec};
use crate::scenario::{
    run_scenario, Attempt, DriverOptions, HarnessError, NotRun, Scenario, ScenarioResult, Verdict,
};
use crate::stop::StopRequest;
use crate::time::Duration;

/// Which scenarios a run takes.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Selection {
    /// Substring of the scenario name.
    pub filter: Option<String>,
    /// Every listed tag must be present.
    pub tags: Vec<String>,
    /// No listed tag may be present.
    pub skip_tags: Vec<String>,
    /// Scenarios left out by name (the whole name).
    pub skip: Vec<String>,
    /// `(i, n)`: the i-th (1-based) of n interleaved shards.
    pub shard: Option<(usize, usize)>,
}

impl Selection {
    pub fn select(&self, all: &[Scenario]) -> Vec<Scenario> {
        self.matching(all)
            .into_iter()
            .enumerate()
            .filter(|(i, _)| self.shard.is_none_or(|(k, n)| i % n == k - 1))
            .map(|(_, s)| s)
            .collect()
    }

    /// The scenarios the filter and tags take, before sharding.
    pub fn matching(&self, all: &[Scenario]) -> Vec<Scenario> {
        all.iter()
            .filter(|s| {
                self.filter
                    .as_ref()
                    .is_none_or(|f| s.name.contains(f.as_str()))
            })
            .filter(|s| self.tags.iter().all(|t| s.has_tag(t)))
            .filter(|s| !self.skip_tags.iter().any(|t| s.has_tag(t)))
            .filter(|s| !self.skip.iter().any(|n| n == s.name))
            .copied()
            .collect()
    }
}

/// Why a `--shard` value does not read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ShardError {
    #[error("shard `{0}` should be I/N, e.g. 2/4")]
    NotIOverN(String),
    #[error("shard index `{0}` is not a number")]
    BadIndex(String),
    #[error("shard count `{0}` is not a number")]
    BadCount(String),
    #[error("shard {i}/{n}: need 1 <= I <= N")]
    OutOfRange { i: usize, n: usize },
}

/// Parses `I/N` (1 <= I <= N).
/// The facts of a run starting now, by this harness, on `boards` spread
/// as `spread` says (`one`, `share`, `each`): what its record carries.
pub fn run_info(boards: Vec<ppmc_record::BoardInfo>, spread: &str) -> ppmc_record::RunInfo {
    ppmc_record::RunInfo::new(crate::VERSION, crate::GIT_REV, boards, spread)
}

pub fn parse_shard(s: &str) -> Result<(usize, usize), ShardError> {
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| ShardError::NotIOverN(s.into()))?;
    let i: usize = i.parse().map_err(|_| ShardError::BadIndex(i.into()))?;
    let n: usize = n.parse().map_err(|_| ShardError::BadCount(n.into()))?;
    if n == 0 || i == 0 || i > n {
        return Err(ShardError::OutOfRange { i, n });
    }
    Ok((i, n))
}

/// A suite that breaks the rules every suite keeps.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SuiteError {
    /// Names are the golden files' and the reports' keys.
    #[error("two scenarios are named `{0}`")]
    DuplicateName(&'static str),
    #[error("scenario `{0}` names no datasheet section")]
    NoSection(&'static str),
}

/// Checks the suite's invariants: unique names, a section on each.
pub fn validate_suite(all: &[Scenario]) -> Result<(), SuiteError> {
    let mut names: Vec<&'static str> = all.iter().map(|s| s.name).collect();
    names.sort_unstable();
    if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
        return Err(SuiteError::DuplicateName(w[0]));
    }
    if let Some(s) = all.iter().find(|s| s.section.is_empty()) {
        return Err(SuiteError::NoSection(s.name));
    }
    Ok(())
}

/// Runs `scenarios` `repeat` times on `target`, calling `on_result` after
/// each (it may amend the result, e.g. with a golden comparison). After a harness error the target gets a health check (a reset);
/// if that fails too the link is taken as dead and the scenarios left are
/// reported as not run, so a broken cable does not read as a bad board.
pub fn run_suite(
    target: &mut dyn Target,
    scenarios: &[Scenario],
    repeat: usize,
    opts: DriverOptions,
    on_result: impl FnMut(&mut ScenarioResult),
) -> Vec<ScenarioResult> {
    run_suite_until(target, scenarios, repeat, opts, || false, on_result)
}

/// [`run_suite`] that asks `stop` before each scenario: once it says yes
/// (SIGINT, a closed output), the scenarios left in this pass are reported
/// as not run, interrupted, and no further pass starts.
pub fn run_suite_until(
    target: &mut dyn Target,
    scenarios: &[Scenario],
    repeat: usize,
    opts: DriverOptions,
    stop: impl Fn() -> bool,
    mut on_result: impl FnMut(&mut ScenarioResult),
) -> Vec<ScenarioResult> {
    let mut results = Vec::new();
    let mut dead: Option<String> = None;
    let mut interrupted = false;
    for _ in 0..repeat.max(1) {
        if interrupted {
            break;
        }
        for s in scenarios {
            interrupted = interrupted || stop();
            let not_run = |why| not_run(s, why);
            let mut r = match &dead {
                _ if interrupted => not_run(NotRun::Interrupted),
                Some(why) => not_run(NotRun::TargetLost(why.clone())),
                None => {
                    let (r, lost) = run_checked(target, s, opts, None);
                    dead = lost;
                    r
                }
            };
            on_result(&mut r);
            results.push(r);
        }
    }
    results
}

/// Runs `s`, and after a harness error or a device failure gives the
/// target a health check ([`health`]): `Some(why)` when the target is
/// taken as lost. A board that hung is brought back by `power` when it
/// has a switch ([`recover`]) and the run goes on from the next scenario:
/// a scenario that ended in an error is then an infrastructure error
/// naming the hang; one that failed stays the board's failure, which says
/// what came after.
fn run_checked(
    target: &mut dyn Target,
    s: &Scenario,
    opts: DriverOptions,
    mut power: Option<&mut Power>,
) -> (ScenarioResult, Option<String>) {
    let mut earlier = Vec::new();
    loop {
        let mut r = run_scenario(target, s, opts);
        let mut lost = None;
        let mut recovered = false;
        if matches!(r.verdict, Verdict::Error(_) | Verdict::Failed(_)) {
            let hang = match health(target) {
                Ok(()) => None,
                Err(Hang::Gone(why)) => {
                    lost = Some(why);
                    None
                }
                Err(h) => Some(h),
            };
            if let Some(hang) = hang {
                let outcome = match power.as_deref_mut() {
                    Some(p) => recover(target, p, &hang),
                    None => Recovery::NoSwitch(String::new()),
                };
                match (outcome, &hang) {
                    (Recovery::Back(recovery), _) => {
                        note_hang(&mut r.verdict, hang.why(), recovery);
                        recovered = true;
                    }
                    (Recovery::Lost(why), _) => lost = Some(why),
                    // Without a switch (or one that failed) a chip BUSY
                    // after its reset is left to the next scenario's reset,
                    // and its verdict; a silent bridge is lost.
                    (Recovery::NoSwitch(_), Hang::Busy(_)) => {}
                    (Recovery::NoSwitch(why), h) if why.is_empty() => lost = Some(h.error().into()),
                    (Recovery::NoSwitch(why), h) => lost = Some(format!("{}; {why}", h.error())),
                }
            }
        }
        // Again on the same board, while it is there and the policy takes
        // this end; every attempt stays on record. A scenario the board
        // hung under is not: the run goes on from the next.
        let again = lost.is_none()
            && !recovered
            && earlier.len() < opts.retry.times as usize
            && opts.retry.takes(&r.verdict);
        if again {
            earlier.push(Attempt::of(&r));
            continue;
        }
        r.attempts = earlier;
        return (r, lost);
    }
}

/// Says on `verdict` that the board hung (`hang`) and was brought back
/// (`recovery`): an error becomes the infrastructure's error naming the
/// hang; a failure stays the board's, and says what followed it.
fn note_hang(verdict: &mut Verdict, hang: &str, recovery: String) {
    match verdict {
        Verdict::Failed(f) => {
            f.got = format!("{}; then {hang}, and the board was {recovery}", f.got);
        }
        v => {
            *v = Verdict::Error(HarnessError::Hung {
                hang: hang.to_string(),
                recovery,
            })
        }
    }
}

/// Why a board failed its health check.
#[derive(Debug)]
enum Hang {
    /// Its bridge fell silent: the words, and the link's error.
    Silent(String, String),
    /// Its chip answered, BUSY after its reset: the words.
    Busy(String),
    /// Anything else (a stop, another host on the bridge, a link given up
    /// too often, a bridge that answers wrongly): the board is lost, as it
    /// always was, and no power cycle is tried.
    Gone(String),
}

impl Hang {
    fn why(&self) -> &str {
        match self {
            Hang::Silent(w, _) | Hang::Busy(w) | Hang::Gone(w) => w,
        }
    }

    /// The error itself, as a board lost without a power cycle names it.
    fn error(&self) -> &str {
        match self {
            Hang::Silent(_, e) => e,
            h => h.why(),
        }
    }
}

/// The health check after a scenario that did not pass: a chip reset, and
/// the status after it. A board hangs when its bridge falls silent, or its
/// chip is still BUSY after the reset (3-1-1: the reset ends any move; a
/// chip BUSY past it is past its longest legal move).
fn health(target: &mut dyn Target) -> Result<(), Hang> {
    match busy_after_reset(target) {
        Err(e) if silent(&e) => Err(Hang::Silent(
            format!("its bridge stopped answering ({e})"),
            e.to_string(),
        )),
        Err(e) => Err(Hang::Gone(e.to_string())),
        Ok(Some(status)) => Err(Hang::Busy(format!(
            "the chip stayed BUSY after a chip reset (status 0x{status:02X})"
        ))),
        Ok(None) => Ok(()),
    }
}

/// What became of a hung board's recovery.
#[derive(Debug)]
enum Recovery {
    /// Power-cycled and reached again: what was done.
    Back(String),
    /// Power-cycled (or tried), and not back: why, for the scenarios left.
    Lost(String),
    /// No cycle happened (no switch, none left, the switch failed, a stop):
    /// why, empty for no switch. The board is as it was.
    NoSwitch(String),
}

/// Brings back a board that hung: its power cycled by its switch, the
/// board reached again ([`Target::power_cycle`]) and health checked.
fn recover(target: &mut dyn Target, p: &mut Power, hang: &Hang) -> Recovery {
    let hung = hang.why();
    let cycled = match p.cycle(target) {
        Ok(cycled) => cycled,
        Err(CycleError::NotTried(why)) => return Recovery::NoSwitch(why),
        Err(CycleError::Switch { why, .. }) => {
            return Recovery::NoSwitch(format!("its power cycle failed: {why}"))
        }
        Err(CycleError::NotBack { cycled, error }) => {
            return Recovery::Lost(format!("{hung}; {cycled}, but: {error}"))
        }
    };
    match health(target) {
        Ok(()) => Recovery::Back(cycled),
        Err(Hang::Busy(still)) => Recovery::Back(format!("{cycled}, and {still}")),
        Err(h) => Recovery::Lost(format!("{hung}; {cycled}, and then: {}", h.why())),
    }
}

/// The result of a scenario that did not run, and why.
pub fn not_run(s: &Scenario, why: NotRun) -> ScenarioResult {
    ScenarioResult {
        name: s.name,
        section: s.section,
        tags: s.tags,
        verdict: Verdict::NotRun(why),
        measurements: Vec::new(),
        trace: None,
        elapsed: Duration::ZERO,
        wall: std::time::Duration::ZERO,
        attempts: Vec::new(),
    }
}

/// How a run on several boards uses them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spread {
    /// Each scenario runs once, on whichever board is free first: the
    /// suite in a fraction of the time.
    Share,
    /// Every scenario runs on every board: to compare boards.
    Each,
}

impl Spread {
    /// How the run record names a run on `boards` boards spread so:
    /// `one`, `share` or `each`.
    pub fn name(self, boards: usize) -> &'static str {
        match (boards, self) {
            (1, _) => "one",
            (_, Spread::Share) => "share",
            (_, Spread::Each) => "each",
        }
    }
}

/// A result of a run on several boards, and the board (its index) it ran
/// on; `None` when no board took it.
#[derive(Debug)]
pub struct BoardResult {
    pub board: Option<usize>,
    /// Its place in the run: the index `on_result` was given.
    pub slot: usize,
    pub result: ScenarioResult,
}

/// What a board's worker reports to the run: a result, and whether the
/// board stopped answering with it (it then takes no more scenarios).
struct Report {
    slot: usize,
    board: usize,
    result: ScenarioResult,
    lost: Option<String>,
}

/// Runs `scenarios` `repeat` times on `boards` in parallel, one thread per
/// board, as `spread` says. `on_result` sees each result as it arrives, on
/// the calling thread, in the order they finish, with its slot (its place
/// in the run) and its board.
///
/// A board that stops answering (a harness error, then a failed reset)
/// takes no more scenarios: with [`Spread::Share`] the others take what is
/// left; the scenarios no board could take, and with [`Spread::Each`] the
/// lost board's own, are not run, blamed on the target. Once `stop` says
/// yes no board starts another scenario; what is left of the pass under
/// way is not run, interrupted, and no further pass starts.
///
/// The results come back in a fixed order whatever the timing: with
/// `Share`, the suite's order (pass by pass); with `Each`, board by board.
/// All of them are kept: a soak run that should not keep them streams them
/// with [`stream_on_boards`].
pub fn run_on_boards(
    boards: &mut [Box<dyn Target>],
    scenarios: &[Scenario],
    repeat: usize,
    opts: DriverOptions,
    spread: Spread,
    stop: impl Fn() -> bool + Sync,
    on_result: impl FnMut(usize, Option<usize>, &mut ScenarioResult),
) -> Vec<BoardResult> {
    let mut all = Vec::new();
    stream_on_boards(
        boards,
        &mut [],
        scenarios,
        repeat,
        opts,
        spread,
        stop,
        on_result,
        |r| all.push(r),
    );
    all.sort_by_key(|r| r.slot);
    all
}

/// [`run_on_boards`] that keeps nothing: each result goes to `keep` once
/// `on_result` has seen it, those that ran in the order they finish, then
/// those no board took in the order of their slots. The run itself holds
/// no result, so a soak run of a million passes costs the memory of what
/// `keep` keeps.
#[allow(clippy::too_many_arguments)]
pub fn stream_on_boards(
    boards: &mut [Box<dyn Target>],
    powers: &mut [Option<Power>],
    scenarios: &[Scenario],
    repeat: usize,
    opts: DriverOptions,
    spread: Spread,
    stop: impl Fn() -> bool + Sync,
    mut on_result: impl FnMut(usize, Option<usize>, &mut ScenarioResult),
    mut keep: impl FnMut(BoardResult),
) {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::mpsc;

    // A queue hands out the slots `q * per_queue ..` one by one: one queue
    // shared by every board, or one per board. Nothing is allocated per
    // slot before it runs, so a soak run of a million passes costs what
    // it has run.
    let per_queue = scenarios.len() * repeat.max(1);
    let queues: Vec<AtomicUsize> = match spread {
        Spread::Share => vec![AtomicUsize::new(0)],
        Spread::Each => (0..boards.len()).map(|_| AtomicUsize::new(0)).collect(),
    };
    let scenario_of = |slot: usize| &scenarios[slot % per_queue % scenarios.len()];
    let mut lost: Vec<Option<String>> = vec![None; boards.len()];
    let stop = &stop;
    let queues = &queues;
    std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel();
        let mut powers = powers.iter_mut();
        for (board, target) in boards.iter_mut().enumerate() {
            let tx = tx.clone();
            let mut power = powers.next().and_then(|p| p.as_mut());
            let q = board.min(queues.len() - 1);
            scope.spawn(move || loop {
                if stop() {
                    return;
                }
                // Past the end, the counter is read as `per_queue`.
                let taken = queues[q].fetch_add(1, Ordering::SeqCst);
                if taken >= per_queue {
                    return;
                }
                let slot = q * per_queue + taken;
                let (result, lost) = run_checked(
                    target.as_mut(),
                    scenario_of(slot),
                    opts,
                    power.as_deref_mut(),
                );
                let gone = lost.is_some();
                let _ = tx.send(Report {
                    slot,
                    board,
                    result,
                    lost,
                });
                if gone {
                    return;
                }
            });
        }
        drop(tx);
        for mut r in rx {
            on_result(r.slot, Some(r.board), &mut r.result);
            if r.lost.is_some() {
                lost[r.board] = r.lost;
            }
            keep(BoardResult {
                board: Some(r.board),
                slot: r.slot,
                result: r.result,
            });
        }
    });
    // What no board took: the rest of the pass under way when stopped, or
    // everything left by lost boards.
    let interrupted = stop();
    let every_loss = lost
        .iter()
        .enumerate()
        .filter_map(|(b, why)| why.as_ref().map(|w| format!("board {}: {w}", b + 1)))
        .collect::<Vec<_>>()
        .join("; ");
    // Every slot a board took has reported (a worker that takes a slot
    // runs it and reports it): the slots taken are the first of each
    // queue, and the rest from there have no result.
    for (q, queue) in queues.iter().enumerate() {
        let taken = queue.load(Ordering::SeqCst).min(per_queue);
        let end = match interrupted {
            true if scenarios.is_empty() => 0,
            true => taken.div_ceil(scenarios.len()).max(1) * scenarios.len(),
            false => per_queue,
        };
        let board = match spread {
            Spread::Share => None,
            Spread::Each => Some(q),
        };
        for slot in q * per_queue + taken..q * per_queue + end.min(per_queue) {
            let why = match (interrupted, board) {
                (true, _) => NotRun::Interrupted,
                (false, Some(b)) => NotRun::TargetLost(lost[b].clone().unwrap_or_default()),
                (false, None) => NotRun::TargetLost(every_loss.clone()),
            };
            let mut result = not_run(scenario_of(slot), why);
            on_result(slot, board, &mut result);
            keep(BoardResult {
                board,
                slot,
                result,
            });
        }
    }
}

/// The boards of a run on several targets, opened: those reached, and why
/// the others were not. A board that cannot be reached takes no part: its
/// scenarios are "not run", blamed on the infrastructure, never failed.
pub struct Farm {
    specs: Vec<TargetSpec>,
    /// The targets reached, and for each, its spec's index.
    targets: Vec<Box<dyn Target>>,
    /// Each target's power switch, where it has one.
    powers: Vec<Option<Power>>,
    reached: Vec<usize>,
    /// The specs not reached (their index) and why.
    unreached: Vec<(usize, OpenError)>,
    stop: StopRequest,
}

impl Farm {
    /// Opens every spec at once (a farm's boards each take a while to
    /// answer). Every spec is [`checked`](backend::check) first: one the
    /// user got wrong is an [`OpenError::Invalid`] before any board is
    /// touched. A board that cannot be reached is kept as unreached.
    pub fn open(specs: Vec<TargetSpec>, opts: &OpenOptions) -> Result<Farm, OpenError> {
        for spec in &specs {
            backend::check(spec, opts)?;
        }
        let opened: Vec<Result<Box<dyn Target>, OpenError>> = std::thread::scope(|scope| {
            let handles: Vec<_> = specs
                .iter()
                .map(|spec| scope.spawn(|| backend::open(spec, opts)))
                .collect();
            handles
                .into_iter()
                .map(|h| {
                    h.join().unwrap_or_else(|_| {
                        Err(OpenError::Infrastructure(
                            "opening the target panicked".into(),
                        ))
                    })
                })
                .collect()
        });
        let mut farm = Farm {
            specs: Vec::new(),
            targets: Vec::new(),
            powers: Vec::new(),
            reached: Vec::new(),
            unreached: Vec::new(),
            stop: opts.stop.clone(),
        };
        for (b, opened) in opened.into_iter().enumerate() {
            match opened {
                Ok(t) => {
                    farm.targets.push(t);
                    farm.powers
                        .push(Power::of(&specs[b], &opts.power, &opts.stop));
                    farm.reached.push(b);
                }
                Err(e @ OpenError::Invalid(_)) => return Err(e),
                Err(e) => farm.unreached.push((b, e)),
            }
        }
        farm.specs = specs;
        Ok(farm)
    }

    /// The specs, in the order given: board `b` of the results is `specs()[b]`.
    pub fn specs(&self) -> &[TargetSpec] {
        &self.specs
    }

    /// What board `b`'s link has cost so far ([`Target::link_stats`]);
    /// `None` for the emulator or a board not reached.
    pub fn link_stats(&self, b: usize) -> Option<Vec<(&'static str, u64)>> {
        let t = self.reached.iter().position(|r| *r == b)?;
        self.targets[t].link_stats()
    }

    /// Board `b`'s bridge's serial number ([`Target::bridge_serial`]).
    pub fn bridge_serial(&self, b: usize) -> Option<String> {
        let t = self.reached.iter().position(|r| *r == b)?;
        self.targets[t].bridge_serial()
    }

    /// Board `b`: what its target says of itself, or why it was not reached.
    pub fn board(&self, b: usize) -> Result<TargetInfo, &OpenError> {
        match self.reached.iter().position(|r| *r == b) {
            Some(t) => Ok(self.targets[t].info()),
            None => Err(self
                .unreached
                .iter()
                .find(|(u, _)| *u == b)
                .map(|(_, e)| e)
                .unwrap_or(&NOT_OPENED)),
        }
    }

    /// The boards not reached (their index) and why.
    pub fn unreached(&self) -> &[(usize, OpenError)] {
        &self.unreached
    }

    /// Whether no board at all could be reached.
    pub fn reached_none(&self) -> bool {
        self.targets.is_empty()
    }

    /// Why no board could be reached: the one reason, or each board's.
    pub fn unreached_reason(&self) -> String {
        match self.unreached.as_slice() {
            [(_, e)] => e.to_string(),
            all => format!(
                "infrastructure error: no board could be reached: {}",
                all.iter()
                    .map(|(b, e)| format!("{}: {e}", self.specs[*b].label()))
                    .collect::<Vec<_>>()
                    .join("; ")
            ),
        }
    }

    /// [`stream_on_boards`] on the boards reached, with boards numbered
    /// as the specs are. The scenarios of a board not reached are "not
    /// run" (interrupted if a stop was asked for while the boards were
    /// opened): with [`Spread::Each`] its own, after the others' slots;
    /// when no board was reached, the selection once (per board with
    /// `Each`). Those go to `keep` only.
    #[allow(clippy::too_many_arguments)]
    pub fn stream(
        &mut self,
        scenarios: &[Scenario],
        repeat: usize,
        opts: DriverOptions,
        spread: Spread,
        stop: impl Fn() -> bool + Sync,
        mut on_result: impl FnMut(usize, Option<usize>, &mut ScenarioResult),
        mut keep: impl FnMut(BoardResult),
    ) {
        let interrupted = self.stop.requested();
        let not_reached = |s: &Scenario, why: &str| match interrupted {
            true => not_run(s, NotRun::Interrupted),
            false => not_run(s, NotRun::Unreachable(why.to_string())),
        };
        if self.targets.is_empty() {
            let why = self.unreached_reason();
            let each_board: Vec<Option<usize>> = match spread {
                Spread::Each => (0..self.specs.len()).map(Some).collect(),
                Spread::Share => vec![(self.specs.len() == 1).then_some(0)],
            };
            let mut slot = 0;
            for board in each_board {
                for s in scenarios {
                    let result = not_reached(s, &why);
                    keep(BoardResult {
                        board,
                        slot,
                        result,
                    });
                    slot += 1;
                }
            }
            return;
        }
        let reached = &self.reached;
        stream_on_boards(
            &mut self.targets,
            &mut self.powers,
            scenarios,
            repeat,
            opts,
            spread,
            stop,
            |slot, t, r| on_result(slot, t.map(|t| reached[t]), r),
            |mut r| {
                r.board = r.board.map(|t| reached[t]);
                keep(r)
            },
        );
        // With `Each`, a board that could not be reached runs nothing: its
        // slots come after the boards reached.
        if spread == Spread::Each {
            let per_queue = scenarios.len() * repeat;
            let interrupted = self.stop.requested();
            for (k, (b, e)) in self.unreached.iter().enumerate() {
                let first = per_queue * (self.targets.len() + k);
                for (i, s) in (0..repeat).flat_map(|_| scenarios).enumerate() {
                    let result = match interrupted {
                        true => not_run(s, NotRun::Interrupted),
                        false => not_run(s, NotRun::Unreachable(e.to_string())),
                    };
                    keep(BoardResult {
                        board: Some(*b),
                        slot: first + i,
                        result,
                    });
                }
            }
        }
    }
}

impl std::fmt::Debug for Farm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Farm")
            .field("specs", &self.specs)
            .field("reached", &self.reached)
            .field("unreached", &self.unreached)
            .finish_non_exhaustive()
    }
}

/// What [`Farm::board`] says of a board it has no record of (an index
/// past the specs).
static NOT_OPENED: OpenError = OpenError::Infrastructure(String::new());

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::{Op, TargetError, TargetErrorKind};
    use crate::scenario::{Driver, HarnessError, Outcome};

    fn ok(_: &mut Driver) -> Outcome {
        Ok(())
    }

    fn suite() -> Vec<Scenario> {
        vec![
            Scenario::new("a_one", "3-1", "", &["x"], ok),
            Scenario::new("b_two", "3-2", "", &["x", "y"], ok),
            Scenario::new("c_three", "3-3", "", &["y"], ok),
            Scenario::new("d_four", "3-4", "", &[], ok),
        ]
    }

    fn names(v: Vec<Scenario>) -> Vec<&'static str> {
        v.into_iter().map(|s| s.name).collect()
    }

    #[test]
    fn selection_by_filter_tag_and_shard() {
        let all = suite();
        let sel = |f: Option<&str>, tags: &[&str], shard| Selection {
            filter: f.map(String::from),
            tags: tags.iter().map(|t| t.to_string()).collect(),
            skip_tags: Vec::new(),
            skip: Vec::new(),
            shard,
        };
        assert_eq!(
            names(sel(Some("t"), &[], None).select(&all)),
            vec!["b_two", "c_three"]
        );
        assert_eq!(
            names(sel(None, &["x", "y"], None).select(&all)),
            vec!["b_two"]
        );
        assert_eq!(
            names(sel(None, &[], Some((1, 2))).select(&all)),
            vec!["a_one", "c_three"]
        );
        let skip_y = Selection {
            skip_tags: vec!["y".into()],
            ..Selection::default()
        };
        assert_eq!(names(skip_y.select(&all)), vec!["a_one", "d_four"]);
        // Issue 42: one scenario left out by its whole name.
        let skip_b = Selection {
            skip: vec!["b_two".into(), "c_thr".into()],
            ..Selection::default()
        };
        assert_eq!(
            names(skip_b.select(&all)),
            vec!["a_one", "c_three", "d_four"]
        );
        // A shard past the end of a small suite is empty, not an error.
        assert!(sel(None, &[], Some((7, 9))).select(&all).is_empty());
        assert_eq!(
            names(sel(None, &[], Some((2, 2))).select(&all)),
            vec!["b_two", "d_four"]
        );
    }

    #[test]
    fn shard_syntax() {
        assert_eq!(parse_shard("2/4"), Ok((2, 4)));
        assert!(parse_shard("0/4").is_err());
        assert!(parse_shard("5/4").is_err());
        assert!(parse_shard("x").is_err());
    }

    fn panics(_: &mut Driver) -> Outcome {
        panic!("scenario bug")
    }

    fn runs_forever(d: &mut Driver) -> Outcome {
        d.init(crate::scenario::Init::four_phase())?;
        d.start(crate::scenario::Move::continuous(
            crate::protocol::Direction::Cw,
            50,
        ))?;
        loop {
            d.wait(crate::time::Duration::from_secs(1))?;
        }
    }

    fn fails(d: &mut Driver) -> Outcome {
        d.check("something", 1, 2)
    }

    #[test]
    fn a_panic_or_an_overrun_fails_that_scenario_alone() {
        let suite = vec![
            Scenario::new("a_panics", "3-1", "", &[], panics),
            Scenario::new("b_overruns", "3-1", "", &[], runs_forever)
                .budget(crate::time::Duration::from_secs(5)),
            Scenario::new("c_fails", "3-1", "", &[], fails),
            Scenario::new("d_passes", "3-1", "", &[], ok),
        ];
        let mut t = crate::backend::EmuTarget::new(Default::default(), Default::default())
            .expect("emulator");
        let r = run_suite(&mut t, &suite, 1, DriverOptions::default(), |_| {});
        let v: Vec<&str> = r.iter().map(|r| r.verdict.label()).collect();
        assert_eq!(v, vec!["error", "error", "failed", "passed"]);
        assert!(r[0]
            .verdict
            .detail()
            .unwrap_or_default()
            .contains("panicked: scenario bug"));
        assert!(r[1]
            .verdict
            .detail()
            .unwrap_or_default()
            .contains("time budget"));
        assert!(r[2]
            .verdict
            .detail()
            .unwrap_or_default()
            .contains("expected 1, got 2"));
    }

    #[test]
    fn duplicate_names_are_refused() {
        let mut all = suite();
        all.push(Scenario::new("a_one", "3-1", "", &[], ok));
        assert_eq!(
            validate_suite(&all),
            Err(SuiteError::DuplicateName("a_one"))
        );
    }

    /// A target whose cable was pulled before the run.
    #[derive(Debug)]
    struct Gone;

    impl Target for Gone {
        fn info(&self) -> crate::backend::TargetInfo {
            crate::backend::TargetInfo {
                name: "gone".into(),
                straps: crate::protocol::Straps::default(),
                extra: Vec::new(),
            }
        }
        fn capture(&mut self) -> Result<crate::protocol::OutputRecord, TargetError> {
            Err(TargetError::new(TargetErrorKind::Link, "cable pulled"))
        }
        fn execute(&mut self, _: &[Op]) -> Result<Vec<crate::backend::Reply>, TargetError> {
            Err(TargetError::new(TargetErrorKind::Link, "cable pulled"))
        }
    }

    #[test]
    fn after_a_target_is_lost_the_rest_are_not_run_and_blame_the_target() {
        let results = run_suite(&mut Gone, &suite(), 1, DriverOptions::default(), |_| {});
        assert!(
            matches!(
                &results[0].verdict,
                Verdict::Error(HarnessError::Target {
                    kind: TargetErrorKind::Link,
                    ..
                })
            ),
            "{:?}",
            results[0].verdict
        );
        for r in &results[1..] {
            assert_eq!(
                r.verdict,
                Verdict::NotRun(NotRun::TargetLost("cable pulled".into())),
                "{}",
                r.name
            );
        }
        assert_eq!(
            results[1].verdict.detail().as_deref(),
            Some("not run: the target stopped answering (cable pulled)")
        );
    }

    fn emu() -> Box<dyn Target> {
        Box::new(
            crate::backend::EmuTarget::new(Default::default(), Default::default())
                .expect("emulator"),
        )
    }

    /// A board that answers once `lost` is set: so that the board that
    /// loses its cable has surely taken a scenario first.
    struct After(
        Box<dyn Target>,
        std::sync::Arc<std::sync::atomic::AtomicBool>,
    );

    impl Target for After {
        fn info(&self) -> crate::backend::TargetInfo {
            self.0.info()
        }
        fn capture(&mut self) -> Result<crate::protocol::OutputRecord, TargetError> {
            self.0.capture()
        }
        fn execute(&mut self, ops: &[Op]) -> Result<Vec<crate::backend::Reply>, TargetError> {
            let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
            while !self.1.load(std::sync::atomic::Ordering::SeqCst) {
                assert!(
                    std::time::Instant::now() < deadline,
                    "the lost board never ran"
                );
                std::thread::yield_now();
            }
            self.0.execute(ops)
        }
    }

    /// [`Gone`], saying so when it is first used.
    struct GoneSays(std::sync::Arc<std::sync::atomic::AtomicBool>);

    impl Target for GoneSays {
        fn info(&self) -> crate::backend::TargetInfo {
            Gone.info()
        }
        fn capture(&mut self) -> Result<crate::protocol::OutputRecord, TargetError> {
            Gone.capture()
        }
        fn execute(&mut self, ops: &[Op]) -> Result<Vec<crate::backend::Reply>, TargetError> {
            let r = Gone.execute(ops);
            self.0.store(true, std::sync::atomic::Ordering::SeqCst);
            r
        }
    }

    fn run(boards: &mut [Box<dyn Target>], spread: Spread, repeat: usize) -> Vec<BoardResult> {
        let mut seen = 0;
        let r = run_on_boards(
            boards,
            &suite(),
            repeat,
            DriverOptions::default(),
            spread,
            || false,
            |_, _, _| seen += 1,
        );
        assert_eq!(seen, r.len(), "on_result sees every result once");
        r
    }

    #[test]
    fn shared_boards_run_each_scenario_once_in_the_suites_order() {
        let mut boards = vec![emu(), emu(), emu()];
        let r = run(&mut boards, Spread::Share, 2);
        let got: Vec<&str> = r.iter().map(|r| r.result.name).collect();
        let once = names(suite());
        assert_eq!(got, [once.clone(), once].concat());
        assert!(r.iter().all(|r| r.result.verdict == Verdict::Passed));
        assert!(r.iter().all(|r| r.board.is_some_and(|b| b < 3)));
    }

    #[test]
    fn each_board_runs_the_whole_suite_and_results_come_board_by_board() {
        let mut boards = vec![emu(), emu()];
        let r = run(&mut boards, Spread::Each, 1);
        let boards: Vec<Option<usize>> = r.iter().map(|r| r.board).collect();
        assert_eq!(boards, [[Some(0); 4], [Some(1); 4]].concat());
        let got: Vec<&str> = r.iter().map(|r| r.result.name).collect();
        assert_eq!(got, [names(suite()), names(suite())].concat());
    }

    #[test]
    fn a_board_that_drops_out_hands_the_rest_to_the_others() {
        let lost = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let mut boards: Vec<Box<dyn Target>> = vec![
            Box::new(After(emu(), lost.clone())),
            Box::new(GoneSays(lost)),
        ];
        let r = run(&mut boards, Spread::Share, 1);
        assert_eq!(r.len(), 4);
        // The scenario under way on the lost board is an error of the
        // target, on that board; every other one ran on the good board.
        let errors: Vec<&BoardResult> = r
            .iter()
            .filter(|r| matches!(r.result.verdict, Verdict::Error(_)))
            .collect();
        assert_eq!(errors.len(), 1, "{r:?}");
        assert_eq!(errors[0].board, Some(1));
        assert!(matches!(
            &errors[0].result.verdict,
            Verdict::Error(HarnessError::Target {
                kind: TargetErrorKind::Link,
                ..
            })
        ));
        for ok in r.iter().filter(|r| r.result.verdict == Verdict::Passed) {
            assert_eq!(ok.board, Some(0), "{}", ok.result.name);
        }
        assert_eq!(
            r.iter()
                .filter(|r| r.result.verdict == Verdict::Passed)
                .count(),
            3
        );
    }

    #[test]
    fn when_every_board_is_lost_the_rest_are_not_run_naming_each_board() {
        let mut boards: Vec<Box<dyn Target>> = vec![Box::new(Gone), Box::new(Gone)];
        let r = run(&mut boards, Spread::Share, 1);
        let errors = r
            .iter()
            .filter(|r| matches!(r.result.verdict, Verdict::Error(_)))
            .count();
        assert_eq!(errors, 2, "one scenario under way on each board: {r:?}");
        for left in r.iter().filter(|r| r.board.is_none()) {
            assert_eq!(
                left.result.verdict,
                Verdict::NotRun(NotRun::TargetLost(
                    "board 1: cable pulled; board 2: cable pulled".into()
                ))
            );
        }
        assert_eq!(r.iter().filter(|r| r.board.is_none()).count(), 2);
    }

    #[test]
    fn with_each_a_lost_board_leaves_its_own_scenarios_not_run() {
        let mut boards: Vec<Box<dyn Target>> = vec![emu(), Box::new(Gone)];
        let r = run(&mut boards, Spread::Each, 1);
        let verdicts: Vec<&str> = r.iter().map(|r| r.result.verdict.label()).collect();
        assert_eq!(
            verdicts,
            ["passed", "passed", "passed", "passed", "error", "not run", "not run", "not run"]
        );
        assert!(r[5..].iter().all(|r| r.board == Some(1)
            && r.result.verdict == Verdict::NotRun(NotRun::TargetLost("cable pulled".into()))));
    }

    #[test]
    fn a_stop_leaves_the_rest_of_the_pass_interrupted_and_starts_no_other() {
        let mut boards = vec![emu(), emu()];
        let r = run_on_boards(
            &mut boards,
            &suite(),
            3,
            DriverOptions::default(),
            Spread::Share,
            || true,
            |_, _, _| {},
        );
        assert_eq!(r.len(), 4, "one pass");
        assert!(
            r.iter()
                .all(|r| r.board.is_none()
                    && r.result.verdict == Verdict::NotRun(NotRun::Interrupted))
        );

        // Stopped after two scenarios of a million passes: two ran, the
        // two left of that pass did not, and nothing more is reported.
        let asked = std::sync::atomic::AtomicUsize::new(0);
        let mut one = vec![emu()];
        let r = run_on_boards(
            &mut one,
            &suite(),
            1_000_000,
            DriverOptions::default(),
            Spread::Share,
            || asked.fetch_add(1, std::sync::atomic::Ordering::SeqCst) >= 2,
            |_, _, _| {},
        );
        let verdicts: Vec<&str> = r.iter().map(|r| r.result.verdict.label()).collect();
        assert_eq!(verdicts, ["passed", "passed", "not run", "not run"]);
    }
}

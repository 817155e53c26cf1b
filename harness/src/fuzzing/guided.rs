//! Guided fuzzing of any target (`ppmc fuzz campaign`): `bus_bytes`
//! inputs (the byte grammar of [`crate::bus_program`], protocol violations
//! included) run on a board from a chip reset, each judged on what the
//! board itself answered by the datasheet's invariants
//! ([`crate::invariants::replay`]), with the reference model's domain
//! coverage of the same input ([`Coverage`]) as the feedback: an input
//! that reaches something new (a command in a chip state, an error code, a
//! way a move ends, an input during a move) is kept in the corpus and
//! mutated further. A chip like this one has no breakpoints to read; the
//! model tells, for every byte the board was given, which state and which
//! rule it exercised.
//!
//! The budget is the board's own time (its clock, from each chip reset to
//! the input's last op), not the host's: a slow link costs wall time, not
//! budget. A break is run again at once: one that repeats is a finding,
//! one that does not is kept apart as flaky.

use super::campaign::Coverage;
use super::reference;
use super::schedule::Pool;
use crate::backend::power::{busy_after_reset, silent, CycleError, Power};
use crate::backend::{Op, Reply, Target, TargetError, TargetErrorKind};
use crate::bus_program::{self, BusOp};
use crate::compare::{Divergence, Tolerances};
use crate::emu::ModelConfig;
use crate::invariants::replay::{judge, probed_ops, Found};
use crate::protocol::OutputRecord;
use crate::time::Duration;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::collections::BTreeSet;

/// The share of a guided campaign's inputs that mutate a seed drawn
/// uniformly, besides those the pool draws by rarity (seeds included).
const SEED_SHARE: f64 = 0.25;

/// The least board time an execution counts: a board whose clock does not
/// move (an input of nothing) still uses up a budget.
pub const MIN_EXECUTION: Duration = Duration::from_micros(1);

/// What a campaign may spend, and how its inputs are bounded.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Board time the campaign may use, summed over its executions.
    pub budget: Duration,
    /// An input is cut where its waits would take the board past this
    /// (an input may ask for minutes of waiting).
    pub max_input_time: Duration,
    /// An input is cut after this many ops.
    pub max_ops: usize,
    /// A mutated input is at most this long, in bytes.
    pub max_len: usize,
    /// Seed of the mutations: with the same seeds and target, the same
    /// campaign.
    pub seed: u64,
    /// Byte strings the mutator inserts whole (a libFuzzer dictionary's
    /// entries: the separator, command writes).
    pub dictionary: Vec<Vec<u8>>,
    /// Without feedback: every input a mutation of a seed, nothing kept
    /// (the blind baseline a guided campaign is measured against).
    pub blind: bool,
    /// The reference model each execution is held against besides the
    /// invariants ([`reference::departure`]); `None`: the invariants
    /// alone.
    pub model: Option<ModelConfig>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            budget: Duration::from_secs(60),
            max_input_time: Duration::from_secs(1),
            max_ops: 64,
            max_len: 512,
            seed: 1,
            dictionary: default_dictionary(),
            blind: false,
            model: Some(ModelConfig::default()),
        }
    }
}

/// The separator, the reads, and a command write of every command byte
/// of chapter 3: what `fuzz/bus_bytes.dict` holds, for a campaign run
/// where that file is not.
pub fn default_dictionary() -> Vec<Vec<u8>> {
    let mut d: Vec<Vec<u8>> = vec![
        bus_program::SEPARATOR.to_vec(),
        vec![2],
        vec![3],
        vec![6, 1, 0],
        vec![6, 100, 0],
    ];
    for byte in [
        0x00, 0x01, 0x02, 0x03, 0x05, 0x06, 0x07, 0x0B, 0x0D, 0x12, 0x22,
    ] {
        d.push(vec![0, byte]);
    }
    d
}

/// An input that broke an invariant on the target, or that the board
/// hung under.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Finding {
    /// The input as run (cut to the campaign's bounds).
    pub input: Vec<u8>,
    pub what: What,
    /// It broke the same invariant when run again at once (a hang is not
    /// run again: it is kept as it came).
    pub repeated: bool,
}

/// What a finding found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum What {
    /// An invariant broke, judged on the board's own answers.
    Break(Found),
    /// The board's answers departed from the reference model's, the model
    /// run on the board's timeline ([`reference::departure`]).
    Departs(Divergence),
    /// The board hung under the input (its bridge silent, or its chip
    /// BUSY after a chip reset), and was brought back as `recovery` says.
    Hang { hang: String, recovery: String },
}

impl What {
    /// Its name in a file name: the invariant's id, or `hang`.
    pub fn name(&self) -> String {
        match self {
            What::Break(f) => f.violation.invariant.to_string(),
            What::Departs(d) => departure_name(d),
            What::Hang { .. } => "hang".into(),
        }
    }
}

impl std::fmt::Display for What {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            What::Break(found) => write!(f, "{} (at {})", found.violation, found.at),
            What::Departs(d) => write!(
                f,
                "departs from the model at {}: {}: model {}, board {} (allowed {})",
                d.at, d.quantity, d.golden, d.got, d.allowed
            ),
            What::Hang { hang, recovery } => write!(f, "the board hung: {hang}; {recovery}"),
        }
    }
}

/// A departure's name in a file name: `departs-` and what departed,
/// without its numbers (`pin aux change 1: time` is
/// `departs-pin-aux-change`), so that one kind of departure has one name.
pub fn departure_name(d: &Divergence) -> String {
    let what = d.quantity.split([':', '(']).next().unwrap_or_default();
    let words: Vec<String> = what
        .split_whitespace()
        .filter(|w| !w.chars().all(|c| c.is_ascii_digit()))
        .map(|w| {
            w.chars()
                .filter(|c| c.is_ascii_alphanumeric() || *c == '-')
                .collect::<String>()
                .to_lowercase()
        })
        .filter(|w| !w.is_empty())
        .collect();
    format!("departs-{}", words.join("-"))
}

/// What a campaign did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Stats {
    pub executions: u64,
    /// Board time spent, summed over the executions.
    pub board_time: Duration,
    /// Coverage features reached so far.
    pub features: usize,
    /// Inputs mutation found that reached something new (the seeds are
    /// mutated besides them).
    pub corpus: usize,
    pub findings: usize,
    pub flaky: usize,
    /// Hangs the board was brought back from.
    pub hangs: usize,
}

impl Stats {
    /// Executions per second of board time.
    pub fn per_board_second(&self) -> f64 {
        match self.board_time.as_nanos() {
            0 => 0.0,
            ns => self.executions as f64 / (ns as f64 / 1e9),
        }
    }
}

/// What a campaign tells its caller as it runs.
#[derive(Debug)]
pub enum Event<'a> {
    /// An input reached features nothing before it had: kept.
    NewCoverage { input: &'a [u8], new: usize },
    /// An input broke an invariant (repeated or flaky).
    Finding(&'a Finding),
    /// After every execution.
    Progress(&'a Stats),
}

/// A name for an input that is the same on every build: 16 hex digits of
/// its FNV-1a hash, to name its file in a corpus or among findings.
pub fn name(input: &[u8]) -> String {
    let h = input.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x100_0000_01b3)
    });
    format!("{h:016x}")
}

/// The coverage features an input reaches on the reference model: its
/// domain coverage's cells ([`Coverage::cells`]).
pub fn features(ops: &[BusOp]) -> BTreeSet<String> {
    Coverage::of(&[ops.to_vec()]).cells()
}

/// The ops of `input` that a campaign runs: at most `max_ops`, and none
/// past `max_input_time` of waiting.
pub fn bounded_ops(input: &[u8], s: &Settings) -> Vec<BusOp> {
    let mut waited = Duration::ZERO;
    let mut out = Vec::new();
    for op in bus_program::ops(input).take(s.max_ops) {
        if let BusOp::Advance(d) = op {
            waited += d;
            if waited > s.max_input_time {
                break;
            }
        }
        out.push(op);
    }
    out
}

/// Runs `ops` on `target` from a chip reset, in one batch with its
/// capture (one round trip on a board that takes the batch whole), and
/// judges them: the invariant broken, else where the board departs from
/// `model` (when given) on its own timeline; and the board time it took.
pub fn execute(
    target: &mut dyn Target,
    ops: &[BusOp],
    model: Option<&ModelConfig>,
) -> Result<(Option<What>, Duration), TargetError> {
    let mut batch = Vec::with_capacity(1 + ops.len() * 3);
    batch.push(Op::Reset);
    batch.extend(probed_ops(ops));
    let (replies, capture) = target.execute_then_capture(&batch)?;
    // A chip BUSY right after its reset is hung: 3-1-1's reset ends any
    // move. Nothing the input did is to be judged on it.
    if let Some(Reply::Status { status, .. }) = replies.get(1).filter(|_| !ops.is_empty()) {
        if status.busy() {
            return Err(TargetError::new(
                TargetErrorKind::Other,
                StuckBusy(status.0),
            ));
        }
    }
    let took = replies
        .last()
        .map_or(Duration::ZERO, |r| Duration::from_nanos(r.at().as_nanos()));
    // BUSY as a bridge that polls it may have missed it, and its rises at
    // their earliest, for the invariants; the compare takes a polled
    // change as a range, and a BUSY between two reads as unseen, by rules
    // of its own (docs/conformance.md).
    let missed = busy_the_polling_missed(&capture, &replies, target.uncertainty());
    let found = judge(
        ops,
        replies.get(1..).unwrap_or_default(),
        &busy_at_its_earliest(&missed, &replies, target.uncertainty()),
        target.straps(),
    )
    .map_err(|m| TargetError::new(crate::backend::TargetErrorKind::Other, m))?;
    if let Some(found) = found {
        return Ok((Some(What::Break(found)), took));
    }
    let Some(model) = model else {
        return Ok((None, took));
    };
    let board = reference::Answers {
        ops: &batch,
        replies: &replies,
        capture: &capture,
        straps: target.straps(),
        uncertainty: target.uncertainty(),
    };
    let departs = reference::departure(&board, model, &Tolerances::default())?;
    Ok((departs.map(What::Departs), took))
}

/// The capture with each rise of BUSY a bridge found by reading the
/// status register moved back to just after the read before it, where
/// that read came longer than a poll's pass (`2 × polled + access`)
/// earlier: a bridge reads no status while it waits out a delay, so a
/// rise it stamps at the first read after lies anywhere in the gap
/// (`docs/bridge-protocol.md` section 4), and the invariants, which take
/// the line as exact, are judged on its earliest. An exact capture (the
/// emulator's, bridge-sim's) is as it was.
fn busy_at_its_earliest(
    capture: &OutputRecord,
    replies: &[Reply],
    u: crate::backend::Uncertainty,
) -> OutputRecord {
    let pass = u.poll_pass();
    if !u.polls_busy() {
        return capture.clone();
    }
    let looks: Vec<crate::time::Instant> = replies
        .iter()
        .filter_map(|r| match r {
            Reply::Status { at, .. } => Some(*at),
            _ => None,
        })
        .collect();
    let mut c = capture.clone();
    // BUSY's change before: a rise comes after the fall before it, which
    // the bridge saw at a read of its own.
    let mut last_change = None;
    for p in c.pins.iter_mut() {
        if !is_busy(p) {
            continue;
        }
        let was = last_change.replace(p.at);
        if p.value != 1 {
            continue;
        }
        let before = looks.iter().rev().find(|t| **t < p.at);
        if let Some(t) = before.filter(|t| p.at.saturating_since(**t) > pass) {
            p.at = (*t).max(was.unwrap_or(*t)) + Duration::from_nanos(1);
        }
    }
    // The record keeps its pins in time order.
    c.pins.sort_by_key(|p| p.at);
    c
}

/// The capture with a BUSY pulse the polling missed added around a
/// move's pulses where the line stayed at 0 and no status read among
/// them saw BUSY at 0 (a move begun and ended between two reads). An
/// exact capture is as it was.
fn busy_the_polling_missed(
    capture: &OutputRecord,
    replies: &[Reply],
    u: crate::backend::Uncertainty,
) -> OutputRecord {
    let mut c = capture.clone();
    if !u.polls_busy() {
        return c;
    }
    // Pulses with the line at 0 and no change of it among them, where no
    // status read between their first and last showed BUSY = 0: a move
    // begun and ended between two reads, which polling cannot see. The
    // line is taken as 1 around them (and only so: a read that saw 0
    // among them is a break).
    let zero_reads: Vec<crate::time::Instant> = replies
        .iter()
        .filter_map(|r| match r {
            Reply::Status { at, status } if !status.busy() => Some(*at),
            _ => None,
        })
        .collect();
    let mut unseen: Vec<(crate::time::Instant, crate::time::Instant)> = Vec::new();
    for r in &c.runs {
        if crate::invariants::capture::busy_level(&c, r.start) {
            continue;
        }
        match unseen.last_mut() {
            // Runs in a row with no change of the line between.
            Some((_, end))
                if !c
                    .pins
                    .iter()
                    .any(|p| is_busy(p) && p.at > *end && p.at <= r.start) =>
            {
                *end = r.last();
            }
            _ => unseen.push((r.start, r.last())),
        }
    }
    let one = Duration::from_nanos(1);
    for (start, end) in unseen {
        let seen_zero = zero_reads
            .iter()
            .any(|t| *t > start + u.access && *t + u.access < end);
        let changes = c
            .pins
            .iter()
            .any(|p| is_busy(p) && p.at >= start && p.at <= end);
        if seen_zero || changes {
            continue;
        }
        // The fall where a bridge that saw the rise would have stamped it:
        // at the first read after that showed BUSY at 0.
        let fall = zero_reads
            .iter()
            .find(|t| **t > end)
            .copied()
            .unwrap_or(end + one);
        for (at, value) in [(start - one, 1), (fall, 0)] {
            c.pins.push(crate::protocol::PinEvent {
                at,
                pin: crate::protocol::Pin::Busy,
                value,
            });
        }
    }
    c.pins.sort_by_key(|p| p.at);
    c
}

fn is_busy(p: &crate::protocol::PinEvent) -> bool {
    p.pin == crate::protocol::Pin::Busy
}

/// Runs a campaign on `target` from `seeds` until its budget of board
/// time is spent or `on` says stop (it returns false). Every seed runs
/// first; then mutations of the corpus. Errors of the target end it.
pub fn run(
    target: &mut dyn Target,
    mut power: Option<&mut Power>,
    seeds: &[Vec<u8>],
    s: &Settings,
    mut on: impl FnMut(Event<'_>) -> bool,
) -> Result<Stats, TargetError> {
    let mut rng = StdRng::seed_from_u64(s.seed);
    let mut stats = Stats::default();
    let mut seen: BTreeSet<String> = BTreeSet::new();
    // The seeds and what mutation found, each with the features it
    // reached and the board time it took: what a guided campaign draws
    // from ([`Pool::draw`]).
    let mut pool = Pool::new();
    let seeds: Vec<&Vec<u8>> = seeds.iter().filter(|x| !x.is_empty()).collect();
    if seeds.is_empty() {
        return Err(TargetError::new(
            TargetErrorKind::Unsupported,
            "a campaign needs at least one seed input that is not empty",
        ));
    }
    let mut next_seed = 0;
    while stats.board_time < s.budget {
        let is_seed = next_seed < seeds.len();
        let input = if is_seed {
            next_seed += 1;
            seeds[next_seed - 1].clone()
        } else {
            let drawn = match s.blind || rng.random_bool(SEED_SHARE) {
                false => pool.draw(&mut rng),
                true => None,
            };
            match drawn {
                // An input drawn by the rarity of what it reached, and how
                // quick it is.
                Some(base) => {
                    let others: Vec<&Vec<u8>> = pool.inputs().collect();
                    mutate(&mut rng, &base.input, &others, s)
                }
                // A seed, uniformly: what keeps the variety, and all a
                // blind campaign mutates.
                None => {
                    let base = seeds[rng.random_range(0..seeds.len())];
                    mutate(&mut rng, base, &seeds, s)
                }
            }
        };
        let ops = bounded_ops(&input, s);
        let (found, took) = match execute(target, &ops, s.model.as_ref()) {
            Ok(x) => x,
            Err(e) => {
                // The board hung under the input: brought back, the input
                // kept as a finding, and the campaign goes on.
                let (hang, recovery) = bring_back(target, power.as_deref_mut(), e)?;
                stats.executions += 1;
                stats.hangs += 1;
                stats.findings += 1;
                let finding = Finding {
                    input: bus_program::encode(&ops),
                    what: What::Hang { hang, recovery },
                    repeated: false,
                };
                if !on(Event::Finding(&finding)) || !on(Event::Progress(&stats)) {
                    break;
                }
                continue;
            }
        };
        stats.executions += 1;
        stats.board_time += took.max(MIN_EXECUTION);
        let input = bus_program::encode(&ops);
        // Coverage is measured in both modes; only a guided campaign keeps
        // what reached something new.
        {
            let reached = features(&ops);
            let ids = pool.note(&reached);
            let new: Vec<String> = reached.into_iter().filter(|f| !seen.contains(f)).collect();
            // The seeds, and what reached something new, for drawing.
            if !s.blind && (is_seed || !new.is_empty()) {
                pool.keep(input.clone(), took, ids);
                stats.corpus += usize::from(!is_seed);
            }
            if !new.is_empty() {
                stats.features += new.len();
                seen.extend(new.iter().cloned());
                if !on(Event::NewCoverage {
                    input: &input,
                    new: new.len(),
                }) {
                    break;
                }
            }
        }
        if let Some(found) = found {
            // Run again at once: a break the board repeats is a finding.
            let (again, took) = match execute(target, &ops, s.model.as_ref()) {
                Ok(x) => x,
                Err(e) => {
                    bring_back(target, power.as_deref_mut(), e)?;
                    (None, Duration::ZERO)
                }
            };
            stats.executions += 1;
            stats.board_time += took.max(MIN_EXECUTION);
            let repeated = again.is_some_and(|a| a.name() == found.name());
            match repeated {
                true => stats.findings += 1,
                false => stats.flaky += 1,
            }
            let finding = Finding {
                input: input.clone(),
                what: found,
                repeated,
            };
            if !on(Event::Finding(&finding)) {
                break;
            }
        }
        if !on(Event::Progress(&stats)) {
            break;
        }
    }
    Ok(stats)
}

/// A finding shrunk ([`shrink_on`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Shrunk {
    pub ops: Vec<BusOp>,
    /// What the shrunk ops still find.
    pub what: What,
    /// Executions spent.
    pub tries: usize,
}

/// Shrinks `ops` on `target` while they find what is named `name` there
/// ([`What::name`]: the same invariant broken, the same kind of departure
/// from `model`), as [`finding::minimize`](super::finding::minimize)
/// does on the emulator: each try an execution on the target, from a
/// chip reset. `None` when they do not find it to begin with; the first
/// error of the target ends it.
pub fn shrink_on(
    target: &mut dyn Target,
    ops: &[BusOp],
    model: Option<&ModelConfig>,
    name: &str,
) -> Result<Option<Shrunk>, TargetError> {
    let mut failed = None;
    let small = super::finding::minimize_while(
        ops,
        |ops| {
            if failed.is_some() {
                return None;
            }
            match execute(target, ops, model) {
                Ok((what, _)) => what.filter(|w| w.name() == name),
                Err(e) => {
                    failed = Some(e);
                    None
                }
            }
        },
        |what| match what {
            What::Break(f) => Some(f.violation.op),
            _ => None,
        },
    );
    match failed {
        Some(e) => Err(e),
        None => Ok(small.map(|(ops, what, tries)| Shrunk { ops, what, tries })),
    }
}

/// A chip BUSY after a chip reset: the status it read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("its chip stayed BUSY after a chip reset (status 0x{0:02X})")]
pub struct StuckBusy(pub u8);

/// Brings back a board that failed under an input with `e`: a chip reset
/// when its bridge still answers and its chip is not BUSY after it; else,
/// when it fell silent or its chip stays BUSY and it has a switch with a
/// cycle left, a power cycle ([`Target::power_cycle`]). The hang and what
/// brought it back; `Err` (the error, or why it could not be brought back)
/// ends the campaign.
fn bring_back(
    target: &mut dyn Target,
    power: Option<&mut Power>,
    e: TargetError,
) -> Result<(String, String), TargetError> {
    let stuck = e.get_ref().downcast_ref::<StuckBusy>().is_some();
    if e.kind == TargetErrorKind::Interrupted || !(stuck || silent(&e)) {
        return Err(e);
    }
    let hang = match stuck {
        true => e.to_string(),
        false => format!("its bridge stopped answering ({e})"),
    };
    let busy = |t: &mut dyn Target| busy_after_reset(t).map(|b| b.is_some());
    // A bridge that answers again after its ABORT needs no more than a
    // chip reset; a chip BUSY after one needs power.
    if !stuck {
        match busy(target) {
            Ok(false) => return Ok((hang, "a chip reset brought it back".into())),
            Ok(true) => {}
            Err(again) if silent(&again) => {}
            Err(again) => return Err(again),
        }
    }
    let Some(p) = power else {
        return Err(e);
    };
    let cycled = match p.cycle(target) {
        Ok(cycled) => cycled,
        Err(CycleError::NotTried(_)) => return Err(e),
        Err(CycleError::Switch { error, .. } | CycleError::NotBack { error, .. }) => {
            return Err(error)
        }
    };
    match busy(target)? {
        false => Ok((hang, cycled)),
        true => Err(TargetError::new(
            TargetErrorKind::Other,
            format!("{hang}; {cycled}, and its chip is still BUSY after a chip reset"),
        )),
    }
}

/// A mutation of `base`: a few of libFuzzer's kinds (a bit flipped, a
/// byte set, bytes inserted or erased, a dictionary entry put in, a piece
/// of an input of `pool` spliced in), and some of whole ops (a run of ops
/// done again, a wait shortened, an op moved).
pub fn mutate(rng: &mut StdRng, base: &[u8], pool: &[&Vec<u8>], s: &Settings) -> Vec<u8> {
    let mut x: Vec<u8> = base.to_vec();
    for _ in 0..rng.random_range(1..=4) {
        let at = |rng: &mut StdRng, x: &Vec<u8>| rng.random_range(0..=x.len());
        match rng.random_range(0..9) {
            0 if !x.is_empty() => {
                let i = rng.random_range(0..x.len());
                x[i] ^= 1 << rng.random_range(0..8);
            }
            1 if !x.is_empty() => {
                let i = rng.random_range(0..x.len());
                x[i] = rng.random();
            }
            2 => {
                let i = at(rng, &x);
                let n = rng.random_range(1..=4);
                let bytes: Vec<u8> = (0..n).map(|_| rng.random()).collect();
                x.splice(i..i, bytes);
            }
            3 if !x.is_empty() => {
                let i = rng.random_range(0..x.len());
                let n = rng.random_range(1..=8).min(x.len() - i);
                x.drain(i..i + n);
            }
            4 if !s.dictionary.is_empty() => {
                let i = at(rng, &x);
                let d = &s.dictionary[rng.random_range(0..s.dictionary.len())];
                x.splice(i..i, d.iter().copied());
            }
            5 if !pool.is_empty() => {
                let other = pool[rng.random_range(0..pool.len())];
                if !other.is_empty() {
                    let a = rng.random_range(0..other.len());
                    let b = rng.random_range(a..=other.len());
                    let i = at(rng, &x);
                    x.splice(i..i, other[a..b].iter().copied());
                }
            }
            7 => {
                // Whole ops: a run of them done again right after itself
                // (a second read of what the first read cleared, a
                // command given twice).
                let mut ops = bus_program::decode(&x);
                if !ops.is_empty() {
                    let a = rng.random_range(0..ops.len());
                    let b = (a + rng.random_range(1..=6)).min(ops.len());
                    let again: Vec<BusOp> = ops[a..b].to_vec();
                    ops.splice(b..b, again);
                    x = bus_program::encode(&ops);
                }
            }
            8 => {
                // A wait shortened: the same ops sooner, and quicker on
                // the board (a move stopped earlier in its ramp).
                let mut ops = bus_program::decode(&x);
                let waits: Vec<usize> = (0..ops.len())
                    .filter(|&i| matches!(ops[i], BusOp::Advance(_)))
                    .collect();
                if !waits.is_empty() {
                    let i = waits[rng.random_range(0..waits.len())];
                    if let BusOp::Advance(d) = ops[i] {
                        let keep = rng.random_range(0..=u64::from(u8::MAX));
                        ops[i] = BusOp::Advance(d.scale(keep, 256));
                    }
                    x = bus_program::encode(&ops);
                }
            }
            _ => {
                // Whole ops: one moved elsewhere (the order of writes is
                // what the chip's state depends on).
                let mut ops = bus_program::decode(&x);
                if ops.len() > 1 {
                    let op = ops.remove(rng.random_range(0..ops.len()));
                    ops.insert(rng.random_range(0..=ops.len()), op);
                    x = bus_program::encode(&ops);
                }
            }
        }
    }
    x.truncate(s.max_len);
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::EmuTarget;

    fn emu(faults: &[&str]) -> EmuTarget {
        let mut model = crate::emu::ModelConfig::default();
        let faults: Vec<String> = faults.iter().map(|f| f.to_string()).collect();
        crate::faults::apply_all(&faults, &mut model).expect("catalogued");
        EmuTarget::new(Default::default(), model).expect("emulator")
    }

    /// The same seed, the same campaign: inputs, coverage and stats.
    #[test]
    fn a_campaign_is_replayed_by_its_seed() {
        let seeds = vec![bus_program::encode(&[
            BusOp::Command(0x00),
            BusOp::ReadStatus,
        ])];
        let s = Settings {
            budget: Duration::from_millis(200),
            ..Settings::default()
        };
        let go = |t: &mut EmuTarget| {
            let mut kept = Vec::new();
            let stats = run(t, None, &seeds, &s, |e| {
                if let Event::NewCoverage { input, .. } = e {
                    kept.push(input.to_vec());
                }
                true
            })
            .expect("runs");
            (stats, kept)
        };
        let (a, kept_a) = go(&mut emu(&[]));
        let (b, kept_b) = go(&mut emu(&[]));
        assert_eq!(a, b);
        assert_eq!(kept_a, kept_b);
        assert!(a.board_time >= s.budget, "{a:?}");
        assert!(a.features > 0 && a.executions > 1, "{a:?}");
    }

    /// A campaign with nothing to mutate is refused, and one of inputs that
    /// take no board time still ends.
    #[test]
    fn a_campaign_without_seeds_is_refused_and_one_of_empty_inputs_ends() {
        let s = Settings {
            budget: Duration::from_millis(1),
            ..Settings::default()
        };
        let e = run(&mut emu(&[]), None, &[Vec::new()], &s, |_| true).expect_err("no seed");
        assert!(e.to_string().contains("at least one seed"), "{e}");
        // A seed that decodes to no op takes no board time; the campaign
        // still comes to its end.
        let stats = run(&mut emu(&[]), None, &[b"FUZZ".to_vec()], &s, |_| true).expect("ends");
        assert!(
            stats.executions >= 1 && stats.board_time >= s.budget,
            "{stats:?}"
        );
    }

    /// An input is cut where its waits pass the bound, and its board time
    /// is the board's clock, not the host's.
    #[test]
    fn an_input_is_bounded_and_costs_its_board_time() {
        let s = Settings {
            max_input_time: Duration::from_millis(15),
            ..Settings::default()
        };
        let input = bus_program::encode(&[
            BusOp::Advance(Duration::from_millis(10)),
            BusOp::ReadStatus,
            BusOp::Advance(Duration::from_millis(10)),
            BusOp::ReadStatus,
        ]);
        let ops = bounded_ops(&input, &s);
        assert_eq!(ops.len(), 2);
        let (found, took) =
            execute(&mut emu(&[]), &ops, Some(&ModelConfig::default())).expect("runs");
        assert_eq!(found, None);
        assert!(
            took >= Duration::from_millis(10) && took < Duration::from_millis(11),
            "{took}"
        );
    }

    /// The committed `bus_bytes` seed corpus (the suite's traffic).
    fn corpus() -> Vec<Vec<u8>> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/bus_bytes");
        let mut files: Vec<_> = std::fs::read_dir(dir)
            .expect("the seed corpus")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .collect();
        files.sort();
        files
            .iter()
            .map(|f| std::fs::read(f).expect("a seed"))
            .collect()
    }

    /// A faulty board of the catalogue (a remaining count one too many,
    /// 3-4-4) is found from the suite's traffic, and the break repeats;
    /// the clean model breaks nothing on the same input.
    #[test]
    fn a_catalogued_fault_is_found_and_repeats() {
        let s = Settings {
            budget: Duration::from_secs(600),
            model: None,
            ..Settings::default()
        };
        let mut findings = Vec::new();
        let stats = run(
            &mut emu(&["remaining-off-by-one"]),
            None,
            &corpus(),
            &s,
            |e| {
                if let Event::Finding(f) = e {
                    findings.push(f.clone());
                }
                findings.is_empty()
            },
        )
        .expect("runs");
        let f = findings
            .first()
            .unwrap_or_else(|| panic!("nothing found: {stats:?}"));
        assert!(f.repeated);
        assert_eq!(f.what.name(), "remaining-pulses");
        let ops = bus_program::decode(&f.input);
        assert_eq!(
            execute(&mut emu(&[]), &ops, Some(&ModelConfig::default()))
                .expect("runs")
                .0,
            None
        );
    }

    /// A board fault no invariant sees (error 6 reported for a command
    /// during BUSY, where Table 3-2 gives error 1) is found as a departure
    /// from the model, run on the board's timeline; the same campaign on
    /// a clean board finds nothing, and without the model finds nothing
    /// either.
    #[test]
    fn a_fault_only_the_model_sees_is_found_as_a_departure() {
        let s = Settings {
            budget: Duration::from_secs(60),
            ..Settings::default()
        };
        let first = |faults: &[&str], s: &Settings| {
            let mut found = None;
            run(&mut emu(faults), None, &corpus(), s, |e| {
                if let Event::Finding(f) = e {
                    found = Some(f.clone());
                }
                found.is_none()
            })
            .expect("runs");
            found
        };
        let f = first(&["swap-error-1-6"], &s).expect("a departure");
        assert!(f.repeated);
        assert!(f.what.name().starts_with("departs-"), "{}", f.what);
        assert!(
            f.what.to_string().contains("departs from the model"),
            "{}",
            f.what
        );
        assert_eq!(first(&[], &s), None);
        let blind_to_it = Settings { model: None, ..s };
        assert_eq!(first(&["swap-error-1-6"], &blind_to_it), None);
    }

    /// One kind of departure has one name, without its numbers.
    #[test]
    fn a_departure_is_named_by_what_departed() {
        let d = |q: &str| Divergence {
            at: crate::time::Instant::ZERO,
            quantity: q.into(),
            golden: "1".into(),
            got: "2".into(),
            allowed: "equal".into(),
        };
        assert_eq!(
            departure_name(&d("pin aux change 1: time, from the write before it")),
            "departs-pin-aux-change"
        );
        assert_eq!(
            departure_name(&d("bus transaction 24 (rs 0x00): status")),
            "departs-bus-transaction"
        );
        assert_eq!(
            departure_name(&d("number of moves")),
            "departs-number-of-moves"
        );
    }

    /// BUSY's rise as a bridge stamps it, at the first status read after a
    /// delay, is judged at its earliest (just after the read before), so
    /// the move's first pulses in the gap are inside BUSY (3-3: BUSY
    /// covers the pulses); a rise a read saw within a poll's pass, and
    /// every rise of an exact capture, stay where they are.
    #[test]
    fn a_busy_rise_found_after_a_gap_in_status_reads_is_judged_at_its_earliest() {
        use crate::protocol::{Pin, PinEvent, Status};
        use crate::time::Instant;
        let us = |n: u64| Instant::from_nanos(n * 1_000);
        let status = |at| Reply::Status {
            at,
            status: Status(0),
        };
        let rise = |at| PinEvent {
            at,
            pin: Pin::Busy,
            value: 1,
        };
        let fall = |at| PinEvent {
            value: 0,
            ..rise(at)
        };
        let mut capture = OutputRecord::default();
        capture.pins.push(rise(us(9_000)));
        capture.pins.push(rise(us(9_501)));
        // A move that ended, and the next, found after a gap too: its
        // rise is no earlier than the fall before it.
        capture.pins.push(fall(us(9_600)));
        capture.pins.push(rise(us(20_000)));
        let replies = [status(us(1_000)), status(us(9_500))];
        let bridge = crate::backend::Uncertainty {
            access: Duration::from_nanos(134),
            polled: Duration::from_nanos(1_500),
            ..Default::default()
        };
        let judged = busy_at_its_earliest(&capture, &replies, bridge);
        assert_eq!(judged.pins[0].at, us(1_000) + Duration::from_nanos(1));
        assert_eq!(judged.pins[1].at, us(9_501));
        assert_eq!(judged.pins[3].at, us(9_600) + Duration::from_nanos(1));
        let busy: Vec<u8> = judged.pins.iter().map(|p| p.value).collect();
        assert_eq!(busy, [1, 1, 0, 1], "the line's changes keep their order");
        let exact = busy_at_its_earliest(&capture, &replies, Default::default());
        assert_eq!(exact.pins, capture.pins);
    }

    /// A single step (Section 3-3-3) begun and ended between two status
    /// reads leaves no BUSY change in a bridge's capture, which finds BUSY
    /// by reading the status register: its pulse is judged inside a BUSY
    /// the polling missed (3-1-1 (3)), unless a read among its pulses saw
    /// BUSY at 0.
    #[test]
    fn pulses_between_two_reads_are_inside_a_busy_the_polling_missed() {
        use crate::protocol::{Direction, PulseRun, Status};
        use crate::time::Instant;
        let us = |n: u64| Instant::from_nanos(n * 1_000);
        let status = |at, busy: bool| Reply::Status {
            at,
            status: Status(if busy { Status::BUSY } else { 0 }),
        };
        let mut capture = OutputRecord::default();
        capture.runs.push(PulseRun {
            start: us(100),
            count: 3,
            dir: Direction::Cw,
            span: Duration::from_micros(200),
            jitter: Duration::ZERO,
        });
        let bridge = crate::backend::Uncertainty {
            access: Duration::from_nanos(134),
            polled: Duration::from_nanos(1_500),
            ..Default::default()
        };
        let between = [status(us(10), false), status(us(1_000), false)];
        let judged = busy_the_polling_missed(&capture, &between, bridge);
        let line: Vec<(Instant, u8)> = judged.pins.iter().map(|p| (p.at, p.value)).collect();
        let one = Duration::from_nanos(1);
        assert_eq!(
            line,
            [(us(100) - one, 1), (us(1_000), 0)],
            "fell by the read after"
        );
        // A read among the pulses that saw BUSY at 0: no BUSY is made up.
        let among = [status(us(10), false), status(us(200), false)];
        assert!(busy_the_polling_missed(&capture, &among, bridge)
            .pins
            .is_empty());
        // An exact capture is judged as it is, and so is one whose bridge
        // sees BUSY as exactly as its accesses (bridge-sim: a tick each).
        let tick = crate::backend::Uncertainty {
            access: Duration::from_nanos(1),
            polled: Duration::from_nanos(1),
            ..Default::default()
        };
        assert!(busy_the_polling_missed(&capture, &between, tick)
            .pins
            .is_empty());
        assert!(
            busy_the_polling_missed(&capture, &between, Default::default())
                .pins
                .is_empty()
        );
    }
}

//! The reference model run beside a board, on the board's timeline: each
//! op begun on the model when the board began it ([`starts`], [`run_at`]),
//! so that the model's chip meets every input when the board's chip met
//! it, and a bridge's pace (its ops slower than the emulator's) moves
//! both alike. What then departs is the chip. A differential run
//! ([`super::differential`]) and a guided campaign's executions
//! ([`super::guided`]) both judge a board so ([`departure`]).

use crate::backend::{EmuTarget, Op, Reply, Target, TargetError, TargetErrorKind, Uncertainty};
use crate::compare::{compare, Divergence, Tolerances};
use crate::emu::ModelConfig;
use crate::protocol::{OutputRecord, Status, Straps};
use crate::time::{Duration, Instant};
use crate::trace::{uncertainty_entry, BusEvent, Event, EventKind, Trace};

/// When each of `ops` began on a board whose times are `exact` or not,
/// from its `replies` (`before`: when the op before the first ended): a
/// wait's start; a write's or read's strobe, less the time it waited for
/// its flag where times are exact (else the strobe itself: a bridge
/// strobes after its wait by its own pace, and the model's chip must meet
/// the byte when the board's chip met it); when the op before ended where
/// a reply does not tell (a timeout, a reset).
pub fn starts(ops: &[Op], replies: &[Reply], mut before: Instant, exact: bool) -> Vec<Instant> {
    // Saturating: never before the reset.
    let strobe = |at: Instant, waited: Duration| if exact { at - waited } else { at };
    ops.iter()
        .zip(replies)
        .map(|(op, r)| {
            let start = match (*op, *r) {
                (_, Reply::Written { at, waited }) | (_, Reply::Data { at, waited, .. }) => {
                    strobe(at, waited)
                }
                (_, Reply::Awaited { at, waited, .. }) => at - waited,
                (Op::Delay(d), Reply::Delayed { at }) => at - d,
                (
                    _,
                    Reply::Status { at, .. }
                    | Reply::InputSet { at }
                    | Reply::Pins { at, .. }
                    | Reply::Pulses { at, .. },
                ) => at,
                _ => before,
            };
            before = r.at();
            start
        })
        .collect()
}

/// Runs `ops` on `model`, each begun no earlier than `starts` says (its
/// clock read `now` before the first): their replies.
pub fn run_at(
    model: &mut dyn Target,
    ops: &[Op],
    starts: &[Instant],
    mut now: Instant,
) -> Result<Vec<Reply>, TargetError> {
    let mut replies = Vec::with_capacity(ops.len());
    for (op, start) in ops.iter().zip(starts) {
        if *start > now {
            model.execute(&[Op::Delay(start.saturating_since(now))])?;
            now = *start;
        }
        let r = model.execute(std::slice::from_ref(op))?;
        now = r.last().map_or(now, Reply::at).max(now);
        replies.extend(r);
    }
    Ok(replies)
}

/// A board's answers to one batch: its ops (from a chip reset: the
/// first op is [`Op::Reset`]), the replies and the capture since.
#[derive(Debug, Clone, Copy)]
pub struct Answers<'a> {
    pub ops: &'a [Op],
    pub replies: &'a [Reply],
    pub capture: &'a OutputRecord,
    pub straps: Straps,
    /// How sure the board's times are, as it declares.
    pub uncertainty: Uncertainty,
}

/// Where a board's answers to one batch depart from the reference
/// model's (`model` on the board's straps, run on the board's timeline),
/// by `ppmc compare`'s rules widened by the board's uncertainty. Pulses
/// and pins are compared only where the model's chip ends the batch at
/// rest (BUSY and IBF clear: nothing under way, no byte waiting), so that
/// a board's clock a hair off the model's cannot split a move
/// differently; the bus (every status and data byte, every wait) always.
///
/// A board whose times are not exact stamps each access within its
/// declared `access` of when the chip saw it, so two accesses within
/// `2 × access` of one of the chip's latencies may have met the chip
/// either way round: a byte written 6 us after the one before, a read
/// 20 us after a register read command. Those latencies are the model's
/// own (N11: the datasheet gives none), so a departure is also judged
/// against the model with them `2 × access` shorter and longer, and is a
/// departure only when it departs from all three.
pub fn departure(
    board: &Answers<'_>,
    model: &ModelConfig,
    tol: &Tolerances,
) -> Result<Option<Divergence>, TargetError> {
    let Some(first) = departure_from(board, model, tol)? else {
        return Ok(None);
    };
    let slack = board.uncertainty.access.saturating_mul(2);
    if slack == Duration::ZERO {
        return Ok(Some(first));
    }
    let shifted = |f: fn(Duration, Duration) -> Duration| {
        let at_least = |d: Duration| d.max(Duration::from_nanos(1));
        ModelConfig {
            byte_pickup: at_least(f(model.byte_pickup, slack)),
            obf_ready: at_least(f(model.obf_ready, slack)),
            obf_next: at_least(f(model.obf_next, slack)),
            ..model.clone()
        }
    };
    for m in [
        shifted(Duration::saturating_sub),
        shifted(Duration::saturating_add),
    ] {
        // A latency moved past another it must stay below is no model.
        if m.validate().is_ok() && departure_from(board, &m, tol)?.is_none() {
            return Ok(None);
        }
    }
    Ok(Some(first))
}

/// [`departure`] from one model.
fn departure_from(
    board: &Answers<'_>,
    model: &ModelConfig,
    tol: &Tolerances,
) -> Result<Option<Divergence>, TargetError> {
    let other = |e: String| TargetError::new(TargetErrorKind::Other, e);
    if board.replies.len() != board.ops.len() {
        return Err(other(format!(
            "the target answered {} of {} operations",
            board.replies.len(),
            board.ops.len()
        )));
    }
    let mut reference = EmuTarget::new(board.straps, model.clone())
        .map_err(|e| other(format!("reference emulator: {e}")))?;
    let exact = board.uncertainty == Uncertainty::ZERO;
    let starts = starts(board.ops, board.replies, Instant::ZERO, exact);
    let replies = run_at(&mut reference, board.ops, &starts, Instant::ZERO)?;
    let capture = reference.capture()?;
    let last = match replies.last() {
        Some(r @ Reply::Status { .. }) => Some(*r),
        _ => reference.execute(&[Op::ReadStatus])?.last().copied(),
    };
    let at_rest = matches!(last, Some(Reply::Status { status, .. }) if at_rest(status));
    let empty = OutputRecord::default();
    let trace = |name: &str, replies: &[Reply], capture: &OutputRecord, u: &Uncertainty| {
        let bus: Vec<Event> = board
            .ops
            .iter()
            .zip(replies)
            .filter_map(|(op, r)| {
                BusEvent::of(op, r).map(|kind| Event {
                    at: r.at(),
                    kind: EventKind::Bus(kind),
                })
            })
            .collect();
        let details = vec![uncertainty_entry(u)];
        Trace::new("campaign", "-", name, board.straps, details).assemble(
            bus,
            if at_rest { capture } else { &empty },
            Vec::new(),
        )
    };
    let golden = trace("emu", &replies, &capture, &Uncertainty::ZERO);
    let got = trace("board", board.replies, board.capture, &board.uncertainty);
    Ok(compare(&golden, &got, tol).err())
}

/// A status that says the chip is at rest: not BUSY, no byte waiting.
pub fn at_rest(status: Status) -> bool {
    !status.busy() && !status.ibf()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A "board" that is the model with its byte pickup (N11: a latency
    /// the datasheet does not give) 100 ns sooner, given a command and,
    /// 5.95 us later, a data byte: it takes the command before the data
    /// byte replaces it (3-1-1 (2)), the model 6 us after its write does
    /// not. Stamped within 134 ns (`access`), the two writes may have met
    /// the chip either way round: no departure. Stamped within 10 ns, they
    /// could not have: a departure.
    #[test]
    fn a_race_within_the_boards_stamps_is_no_departure() {
        let model = ModelConfig::default();
        let early = ModelConfig {
            byte_pickup: model.byte_pickup.saturating_sub(Duration::from_nanos(100)),
            ..model.clone()
        };
        let mut board = EmuTarget::new(Straps::default(), early).expect("emulator");
        let ops = [
            Op::Reset,
            Op::WriteCommand {
                byte: 0x02,
                wait_ibf: None,
            },
            Op::Delay(Duration::from_nanos(5_950)),
            Op::WriteData {
                byte: 100,
                wait_ibf: None,
            },
            Op::Delay(Duration::from_micros(20)),
            Op::ReadStatus,
        ];
        let (replies, capture) = board.execute_then_capture(&ops).expect("runs");
        let answers = |access: u64| Answers {
            ops: &ops,
            replies: &replies,
            capture: &capture,
            straps: Straps::default(),
            uncertainty: Uncertainty {
                access: Duration::from_nanos(access),
                ..Uncertainty::default()
            },
        };
        let tol = Tolerances::default();
        let sure = departure(&answers(10), &model, &tol).expect("judged");
        assert!(sure.is_some(), "the status tells the race apart");
        let unsure = departure(&answers(134), &model, &tol).expect("judged");
        assert_eq!(unsure, None);
    }
}

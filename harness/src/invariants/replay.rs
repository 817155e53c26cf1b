//! Bus ops replayed on any target, judged by the same invariants as on the
//! emulator ([`super::rules::Rules`]). Around every op the status register
//! is read (a read with no side effect, Section 3-1-1), because the judge
//! needs IBF and OBF as the host saw them: that is how a reproducer runs on
//! a board, and how a regression scenario made from a finding checks it.

use super::rules::{Rules, Seen, Violation};
use crate::backend::{Op, Reply, Target, TargetError};
use crate::bus_program::BusOp;
use crate::protocol::{OutputRecord, Straps};
use crate::scenario::{Driver, Failure, HarnessError, Outcome, Stop};
use crate::trace::BusEvent;

/// The body of a regression scenario written by `ppmc fuzz to-scenario`:
/// replays `ops` (the scenario starts from a chip reset) and judges them by
/// the fuzz oracle's invariants (`docs/invariants.md`). The trace shows the
/// ops' bus transactions, not the status probes around them.
pub fn regression(d: &mut Driver, ops: &[BusOp]) -> Outcome {
    let replies = d.exec(&probed_ops(ops))?;
    for (op, r) in ops.iter().zip(replies.chunks(OPS_PER_BUS_OP)) {
        if let Some(r) = r.get(1) {
            if let Some(e) = BusEvent::of(&op.op(), r) {
                d.log_bus(r.at(), e);
            }
        }
    }
    let capture = d.capture()?.clone();
    match judge(ops, &replies, &capture, d.straps()) {
        Err(e) => Err(Stop::Error(HarnessError::Reply(e))),
        Ok(None) => Ok(()),
        Ok(Some(f)) => {
            let v = f.violation;
            Err(Stop::Failed(Failure {
                expectation: format!(
                    "invariant {} (Section {})",
                    v.invariant,
                    v.invariant.section()
                ),
                expected: "holds".into(),
                got: format!("broken after op {}: {}", v.op, v.detail),
                at: f.at,
                deviation: None,
            }))
        }
    }
}

/// Target ops per bus op: status, the op, status.
pub const OPS_PER_BUS_OP: usize = 3;

/// The target ops that replay `ops`, each between two status reads.
pub fn probed_ops(ops: &[BusOp]) -> Vec<Op> {
    let mut out = Vec::with_capacity(ops.len() * OPS_PER_BUS_OP);
    for op in ops {
        out.extend([Op::ReadStatus, op.op(), Op::ReadStatus]);
    }
    out
}

/// A finding on a target: the break, and when (target clock) its op ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Found {
    pub violation: Violation,
    pub at: crate::time::Instant,
}

/// Judges the replies to [`probed_ops`]`(ops)` and the capture after them,
/// on a board with these straps.
/// `Err` when the replies do not fit the ops (a target bug, not a finding).
pub fn judge(
    ops: &[BusOp],
    replies: &[Reply],
    capture: &OutputRecord,
    straps: Straps,
) -> Result<Option<Found>, String> {
    if replies.len() != ops.len() * OPS_PER_BUS_OP {
        return Err(format!(
            "the target answered {} of {} operations",
            replies.len(),
            ops.len() * OPS_PER_BUS_OP
        ));
    }
    let status = |r: &Reply| match *r {
        Reply::Status { status, .. } => Ok(status),
        other => Err(format!("expected a status reply, got {other}")),
    };
    let mut judge = Rules::new(straps);
    let mut last_at = crate::time::Instant::ZERO;
    for (op, r) in ops.iter().zip(replies.chunks(OPS_PER_BUS_OP)) {
        let value = match (op, &r[1]) {
            (BusOp::ReadStatus, Reply::Status { status, .. }) => Some(status.0),
            (BusOp::ReadData, Reply::Data { byte, .. }) => Some(*byte),
            (BusOp::ReadStatus | BusOp::ReadData, other) => {
                return Err(format!("expected a read reply to {op}, got {other}"))
            }
            _ => None,
        };
        let seen = Seen {
            before: status(&r[0])?,
            after: status(&r[2])?,
            value,
            at: r[1].at(),
        };
        last_at = seen.at;
        if let Err(violation) = judge.op(*op, seen, capture) {
            return Ok(Some(Found {
                violation,
                at: seen.at,
            }));
        }
    }
    Ok(judge.finish(capture).err().map(|violation| Found {
        violation,
        at: last_at,
    }))
}

/// Replays `ops` on `target` from a chip reset and judges them.
pub fn replay(target: &mut dyn Target, ops: &[BusOp]) -> Result<Option<Found>, TargetError> {
    target.execute(&[Op::Reset])?;
    let (replies, capture) = target.execute_then_capture(&probed_ops(ops))?;
    judge(ops, &replies, &capture, target.straps())
        .map_err(|message| TargetError::new(crate::backend::TargetErrorKind::Other, message))
}

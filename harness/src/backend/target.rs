//! The [`Target`] trait every backend implements, and what it says and
//! fails with: [`TargetInfo`], [`TargetError`] and its [`TargetErrorKind`].

pub use ppmc_core::bus::{Op, Reply, SelfTestPlan, SelfTestReply, Uncertainty};

use crate::protocol::{OutputMark, OutputRecord, Straps};
use std::fmt;

/// A bridge's self-test as it ran: what the bridge says it generated, and
/// what its capture recorded from the chip reset on, or why it has no
/// capture to give (a capture overrun, in the bridge's words).
#[derive(Debug, Clone)]
pub struct SelfTestRun {
    pub reply: SelfTestReply,
    pub capture: Result<OutputRecord, String>,
}

/// What kind of failure a target error is, so that generic code can tell a
/// broken link from a misbehaving device (embedded-hal's `ErrorKind` idea).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TargetErrorKind {
    /// The connection to the target failed: port gone, no answer, corrupt
    /// frames. Not the device's fault.
    Link,
    /// The target refused the request (unsupported op, bad argument).
    Unsupported,
    /// Anything else inside the harness.
    Other,
    /// A stop was asked for (SIGINT, SIGTERM) while the target was busy:
    /// nobody's fault, and no verdict.
    Interrupted,
}

/// A failure to run a batch on a target: its [`TargetErrorKind`] for
/// generic code, and the backend's own error, kept whole. As with
/// `std::io::Error`, it displays as that error, [`TargetError::get_ref`]
/// gives it back (to downcast to, say, a `BridgeError`), and
/// [`std::error::Error::source`] continues its chain.
#[derive(Debug)]
pub struct TargetError {
    pub kind: TargetErrorKind,
    inner: Box<dyn std::error::Error + Send + Sync>,
}

impl TargetError {
    /// An error of `kind` caused by `inner` (a backend's error, or a
    /// sentence: a `String` converts).
    pub fn new(
        kind: TargetErrorKind,
        inner: impl Into<Box<dyn std::error::Error + Send + Sync>>,
    ) -> TargetError {
        TargetError {
            kind,
            inner: inner.into(),
        }
    }

    /// The backend's error.
    pub fn get_ref(&self) -> &(dyn std::error::Error + Send + Sync + 'static) {
        &*self.inner
    }
}

impl fmt::Display for TargetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.inner.fmt(f)
    }
}

impl std::error::Error for TargetError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.inner.source()
    }
}

/// What a target says about itself, for traces and reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TargetInfo {
    /// `emu`, or `serial:/dev/ttyACM0`.
    pub name: String,
    /// How the chip is strapped: the emulator's options, or what the
    /// bridge reports of its board.
    pub straps: Straps,
    /// Other facts, `key value`: the bridge's firmware and protocol.
    pub extra: Vec<(String, String)>,
}

impl TargetInfo {
    /// The board a run record names `name` (its label) with revision
    /// `rev`: this target as reached.
    pub fn board_info(&self, name: String, rev: Option<String>) -> ppmc_record::BoardInfo {
        ppmc_record::BoardInfo::new(name, self.name.clone(), self.details(), rev)
    }

    /// The straps' fields, then the other facts: how traces and reports
    /// list them.
    pub fn details(&self) -> Vec<(String, String)> {
        self.straps
            .fields()
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .chain(self.extra.iter().cloned())
            .collect()
    }
}

/// A chip the harness can drive.
pub trait Target: Send {
    fn info(&self) -> TargetInfo;

    /// How the chip is strapped; scenarios derive rates, waits and timing
    /// bands from it.
    fn straps(&self) -> Straps {
        self.info().straps
    }

    /// Everything captured on the output side since the last reset: pulse
    /// runs with the target's timestamps, pin changes, move starts.
    fn capture(&mut self) -> Result<OutputRecord, TargetError>;

    /// Runs `ops` back to back and returns one reply per op, in order.
    fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError>;

    /// Runs `ops`, then returns the capture too: one round trip on a board
    /// where a caller needs both.
    fn execute_then_capture(
        &mut self,
        ops: &[Op],
    ) -> Result<(Vec<Reply>, OutputRecord), TargetError> {
        let replies = self.execute(ops)?;
        Ok((replies, self.capture()?))
    }

    /// [`Target::execute_then_capture`] with the capture from `from` on
    /// ([`OutputRecord::since`]): what a caller that has the rest needs, without
    /// copying the whole record on every call.
    fn execute_then_capture_since(
        &mut self,
        ops: &[Op],
        from: OutputMark,
    ) -> Result<(Vec<Reply>, OutputRecord), TargetError> {
        let (replies, capture) = self.execute_then_capture(ops)?;
        Ok((replies, capture.since(from)))
    }

    /// Lets the target drop its capture before `mark` (a mark of
    /// [`Target::capture`]), which the caller has done with: what it
    /// dropped, from which later marks count down. A long differential run
    /// so keeps a window, not its whole history. A target may keep
    /// everything (the default drops nothing) or less than asked.
    fn forget_capture_before(&mut self, mark: OutputMark) -> OutputMark {
        let _ = mark;
        OutputMark::default()
    }

    /// Runs a bus bridge's self-test of its capture (`ppmc selftest`,
    /// [`SelfTestPlan`]): the chip is reset, and the bridge's own generator
    /// drives its capture inputs of POUT and INT*. The default, for a
    /// target with no bridge (the emulator), refuses.
    fn self_test(&mut self, plan: &SelfTestPlan) -> Result<SelfTestRun, TargetError> {
        let _ = plan;
        Err(TargetError::new(
            TargetErrorKind::Unsupported,
            "this target has no bus bridge to self-test: give a board's --target",
        ))
    }

    /// How sure the times this target gives are (plus or minus), by the
    /// path each was taken on: the emulator's are exact (0); a board's are
    /// what its bridge declares in HELLO (never finer than its timer's
    /// tick). An interval between two times is as unsure as its two ends
    /// together. Every Table 3-3 measurement carries it
    /// ([`crate::scenario::Measurement`]).
    fn uncertainty(&self) -> Uncertainty {
        Uncertainty::ZERO
    }

    /// The bus bridge's serial number, where it gives one (its HELLO) or
    /// the operating system knows it (a USB serial port's); `None` for the
    /// emulator.
    fn bridge_serial(&self) -> Option<String> {
        None
    }

    /// What the link to the target has cost so far, by name (round trips,
    /// retransmissions, corrupt frames, reopens); `None` for a target with
    /// no link (the emulator).
    fn link_stats(&self) -> Option<Vec<(&'static str, u64)>> {
        None
    }

    /// The wall-clock moment past which a batch is not waited for (a
    /// scenario's `--timeout`): a board's host then tells its bridge to
    /// stop (ABORT) and ends the batch with an error naming the limit.
    /// `None` lifts it. A target in virtual time (the emulator), done in
    /// an instant, has nothing to cut short.
    fn set_deadline(&mut self, _at: Option<std::time::Instant>) {}

    /// Brings back a board that hung ([`crate::backend::power`]): lets go
    /// of its link, has `cycle` switch its power off and on, then reaches
    /// its bridge again as at open (the link opened anew, a new session,
    /// the same straps), trying until `boot` has passed. The chip's health
    /// is the caller's to check. An error from `cycle` ends it at once.
    /// The default, for a target with no power to cycle (the emulator),
    /// refuses without calling `cycle`.
    fn power_cycle(
        &mut self,
        cycle: &mut dyn FnMut() -> Result<(), String>,
        boot: std::time::Duration,
    ) -> Result<(), TargetError> {
        let _ = (cycle, boot);
        Err(TargetError::new(
            TargetErrorKind::Unsupported,
            "this target has no power to cycle",
        ))
    }

    /// Runs one op.
    fn execute_one(&mut self, op: Op) -> Result<Reply, TargetError> {
        let mut replies = self.execute(std::slice::from_ref(&op))?;
        replies.pop().ok_or_else(|| {
            TargetError::new(
                TargetErrorKind::Other,
                format!("target returned no reply to `{op}`"),
            )
        })
    }
}

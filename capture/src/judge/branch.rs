//! The orders of the host's accesses a capture cannot tell apart (issue
//! 40): the model beside the capture once per order ([`Branch`]), forked
//! where an access lies within the capture's uncertainty before the
//! change of a flag that forbids it, and pruned as the board's behaviour
//! rules orders out.

use super::host::HostRules;
use super::outputs;
use super::{Bench, Divergence, HostFinding, StatusLog};
use ppmc::protocol::Status;
use ppmc_logic::decode::{Access, Transaction};
use ppmc_logic::map::{ChannelMap, Signal};
use ppmc_logic::source::Change;

/// The most orders of the host's accesses followed at once; past it the
/// orders found last (the accesses as captured) are dropped first.
pub(super) const MAX_BRANCHES: usize = 8;

/// The model beside the capture under one order of the host's accesses
/// against the chip's flags (issue 40). Where an access lies within the
/// capture's uncertainty (two samples, the floor and the latency
/// tolerance) before a change of IBF, OBF or BUSY, the capture cannot say
/// whether the chip saw it before the change or after: the judge follows
/// both, a branch each, and the board's later behaviour rules one out. No
/// board fails, and no host finding is made, because the judge's own
/// model picked an order the capture cannot prove.
#[derive(Clone)]
pub(super) struct Branch {
    pub(super) bench: Bench,
    pub(super) outputs: outputs::Outputs,
    pub(super) rules: HostRules,
    pub(super) host: Vec<HostFinding>,
    pub(super) status_log: StatusLog,
    pub(super) failed: Option<Divergence>,
}

impl Branch {
    /// A change of the capture, the model run up to it.
    pub(super) fn change(
        &mut self,
        c: &Change,
        prev: Option<&Change>,
        map: &ChannelMap,
        pout: Option<usize>,
    ) {
        let bench = &mut self.bench;
        // The model up to now: every access before this change is in it.
        bench.run_to(c.time_ps);
        self.status_log.push(c.time_ps, bench.board.read_status().0);
        if self.failed.is_none() {
            if let Err(d) = bench.compare_pulses(c.time_ps) {
                self.failed = Some(d);
            }
        }
        // Past the first divergence nothing more is compared: nothing
        // more is kept for it either.
        if self.failed.is_none() {
            self.outputs.observe(c);
            let after = bench.last_access.map(|a| a.to_string());
            if let Err(d) = self.outputs.compare(&bench.frame(), c.time_ps, after) {
                self.failed = Some(d);
            }
        }
        if let Some(ch) = pout.filter(|_| self.failed.is_none()) {
            if c.high(ch) && prev.is_some_and(|q| !q.high(ch)) {
                let dir = map.get(Signal::Dir).map(|d| c.high(d));
                bench.edges.push_back((c.time_ps, dir));
            }
        }
    }

    /// A register access: the branch that takes it as captured, and,
    /// where the model's flags forbid it there (IBF or BUSY 1 for a
    /// write, OBF 0 for a data read) but allow it within the capture's
    /// uncertainty after, the other order too:
    /// this branch takes the access just after the change (the host's
    /// findings then as the chip saw it), and the one returned as
    /// captured, with no host finding for it.
    pub(super) fn access(&mut self, t: &Transaction, follow_orders: bool) -> Option<Branch> {
        self.bench.run_to(t.end_ps);
        let after = (follow_orders && self.failed.is_none())
            .then(|| self.bench.allowed_within(t.end_ps, t.access))
            .flatten();
        let captured = after.map(|after| {
            let mut captured = self.clone();
            captured.apply(t, true);
            self.bench.run_to(after);
            captured
        });
        self.apply(t, false);
        captured
    }

    /// The access taken by the model where it stands; with `unsure`, the
    /// host rules see it but its findings are dropped (the capture cannot
    /// order it).
    fn apply(&mut self, t: &Transaction, unsure: bool) {
        let bench = &mut self.bench;
        // The status as the strobe began (it may change during it), as
        // the model stood at that change of the capture.
        let status = bench.board.read_status();
        let status_then = Status(self.status_log.at(t.start_ps).unwrap_or(status.0));
        // Past the board's first divergence the model no longer stands
        // for the chip: its word on the host would be noise.
        let judging_host = self.failed.is_none();
        let mut dropped = Vec::new();
        let findings = if unsure { &mut dropped } else { &mut self.host };
        if judging_host {
            self.rules.before(t, &bench.board, findings);
        }
        match t.access {
            Access::WriteCommand => bench.board.write_command(t.byte),
            Access::WriteData => bench.board.write_data(t.byte),
            Access::ReadStatus => {
                // The status may change during the strobe: the model's at
                // its start or its end will do; and a flag the board
                // changes a little before or after the model (within the
                // latency tolerance of the time since what caused it) too.
                let mask = !t.unknown;
                let matches = |s: u8| (t.byte & mask) == (s & mask);
                let w = bench.latency_window(t.start_ps);
                let log = &self.status_log;
                let near = || {
                    log.since(t.start_ps.saturating_sub(w)).any(matches)
                        || bench.status_until(t.end_ps.saturating_add(w), matches)
                };
                if self.failed.is_none() && !matches(status.0) && !matches(status_then.0) && !near()
                {
                    self.failed = Some(Divergence {
                        at_ps: t.end_ps,
                        what: "status read".into(),
                        board: format!("0x{:02X}", t.byte),
                        model: format!("0x{:02X}", status.0),
                        after: bench.last_access.map(|a| a.to_string()),
                    });
                }
            }
            Access::ReadData => {
                let byte = bench.board.read_data();
                let mask = !t.unknown;
                if self.failed.is_none() && status.obf() && (t.byte & mask) != (byte & mask) {
                    self.failed = Some(Divergence {
                        at_ps: t.end_ps,
                        what: "data read".into(),
                        board: format!("0x{:02X}", t.byte),
                        model: format!("0x{byte:02X}"),
                        after: bench.last_access.map(|a| a.to_string()),
                    });
                }
            }
        }
        if judging_host {
            self.rules.after(t, &bench.board, findings);
        }
        // What times an output: a write, or the data read that releases
        // INT* (3-4-1); never the host's status polling.
        if t.access != Access::ReadStatus {
            self.outputs.access(t.end_ps);
            bench.last_cause_ps = bench.last_cause_ps.max(t.end_ps);
        }
        bench.last_access = Some(*t);
    }

    /// The capture has ended at `end`: what the model put out before it,
    /// the board must have too.
    pub(super) fn finish(&mut self, end: u64) {
        self.bench.run_to(end);
        if self.failed.is_none() {
            self.rules.finish(end, &self.bench.board, &mut self.host);
        }
        if self.failed.is_none() {
            if let Err(d) = self.bench.compare_pulses(end) {
                self.failed = Some(d);
            }
        }
        if self.failed.is_none() {
            let after = self.bench.last_access.map(|a| a.to_string());
            if let Err(d) = self.outputs.compare(&self.bench.frame(), end, after) {
                self.failed = Some(d);
            }
        }
    }
}

/// Drops the orders the board has ruled out: while one branch has not
/// diverged, those that have; past [`MAX_BRANCHES`], the last found.
pub(super) fn prune(branches: &mut Vec<Branch>) {
    if branches.iter().any(|b| b.failed.is_none()) {
        branches.retain(|b| b.failed.is_none());
    } else if branches.len() > 1 {
        // Every order diverged: keep the one that followed the board
        // longest, for the verdict.
        let keep = branches.swap_remove(best(branches));
        branches.clear();
        branches.push(keep);
    }
    branches.truncate(MAX_BRANCHES);
}

/// The order the board's behaviour bears out best: one that never
/// diverged (the one with the fewest host findings), else the one that
/// followed the board longest; the first found where they tie.
pub(super) fn best(branches: &[Branch]) -> usize {
    branches
        .iter()
        .enumerate()
        .min_by_key(|(i, b)| match &b.failed {
            None => (0, b.host.len() as u64, *i),
            Some(d) => (1, u64::MAX - d.at_ps, *i),
        })
        .map_or(0, |(i, _)| i)
}

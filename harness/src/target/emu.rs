//! The emulator as a target: [`Chip`] behind the [`Target`] trait.

use super::{Op, Reply, Target, TargetError, TargetInfo};
use crate::emu::{Chip, ChipError, ModelConfig};
use crate::protocol::{Record, Status, Straps};
use crate::time::{Duration, Instant};

/// The in-process emulator. Batches run instantly in wall time; waits are
/// resolved exactly by jumping from one model event to the next.
#[derive(Debug, Clone)]
pub struct EmuTarget {
    chip: Chip,
    straps: Straps,
    cfg: ModelConfig,
}

impl EmuTarget {
    pub fn new(straps: Straps, cfg: ModelConfig) -> Result<Self, ChipError> {
        Ok(EmuTarget {
            chip: Chip::new(straps, cfg.clone())?,
            straps,
            cfg,
        })
    }

    pub fn chip(&self) -> &Chip {
        &self.chip
    }

    pub fn chip_mut(&mut self) -> &mut Chip {
        &mut self.chip
    }

    /// Waits until `status & mask == value` or `timeout` has passed.
    /// `Ok(waited)` or `Err(())` on timeout; the chip's clock stands at the
    /// moment the condition first held, or at the deadline.
    fn wait_for(&mut self, mask: u8, value: u8, timeout: Duration) -> Result<Duration, ()> {
        let start = self.chip.now();
        let deadline = start + timeout;
        loop {
            let now = self.chip.now();
            if self.chip.read_status().0 & mask == value {
                return Ok(now.saturating_since(start));
            }
            match self.chip.poll_at() {
                Some(t) if t > now && t <= deadline => self.chip.advance_to(t),
                // Due now: advancing to `now` has processed it already, so a
                // second look cannot change anything before the next event.
                Some(t) if t <= now => {
                    self.chip.advance_to(now + Duration::from_nanos(1));
                }
                _ => {
                    self.chip.advance_to(deadline);
                    let status = self.chip.read_status();
                    return if status.0 & mask == value {
                        Ok(timeout)
                    } else {
                        Err(())
                    };
                }
            }
        }
    }

    /// Waits until the move has output `count` pulses. Stops exactly at
    /// that pulse, even inside a constant-rate stretch.
    fn wait_pulses(&mut self, count: u64, timeout: Duration) -> Result<Instant, u64> {
        let deadline = self.chip.now() + timeout;
        loop {
            if self.chip.move_pulses() >= count {
                return Ok(self.chip.now());
            }
            let next = match (self.chip.predict_pulse(count), self.chip.poll_at()) {
                (Some(a), Some(b)) => a.min(b),
                (a, b) => match a.or(b) {
                    Some(t) => t,
                    None => break,
                },
            };
            if next > deadline {
                break;
            }
            let now = self.chip.now();
            self.chip
                .advance_to(next.max(now + Duration::from_nanos(1)).min(deadline));
        }
        self.chip.advance_to(deadline.max(self.chip.now()));
        Err(self.chip.move_pulses())
    }

    fn status_at(&self) -> (Instant, Status) {
        (self.chip.now(), self.chip.read_status())
    }

    fn run(&mut self, op: Op) -> Reply {
        match op {
            Op::WriteCommand { byte, wait_ibf } | Op::WriteData { byte, wait_ibf } => {
                let mut waited = Duration::ZERO;
                if let Some(timeout) = wait_ibf {
                    match self.wait_for(Status::IBF, 0, timeout) {
                        Ok(w) => waited = w,
                        Err(()) => {
                            let (at, status) = self.status_at();
                            return Reply::WriteTimedOut { at, status };
                        }
                    }
                }
                if matches!(op, Op::WriteCommand { .. }) {
                    self.chip.write_command(byte);
                } else {
                    self.chip.write_data(byte);
                }
                Reply::Written {
                    at: self.chip.now(),
                    waited,
                }
            }
            Op::ReadStatus => {
                let (at, status) = self.status_at();
                Reply::Status { at, status }
            }
            Op::ReadData { wait_obf } => {
                let mut waited = Duration::ZERO;
                if let Some(timeout) = wait_obf {
                    match self.wait_for(Status::OBF, Status::OBF, timeout) {
                        Ok(w) => waited = w,
                        Err(()) => {
                            let (at, status) = self.status_at();
                            return Reply::ReadTimedOut { at, status };
                        }
                    }
                }
                let byte = self.chip.read_data();
                Reply::Data {
                    at: self.chip.now(),
                    byte,
                    waited,
                }
            }
            Op::Delay(d) => {
                let to = self.chip.now() + d;
                self.chip.advance_to(to);
                Reply::Delayed { at: to }
            }
            Op::AwaitStatus {
                mask,
                value,
                timeout,
            } => match self.wait_for(mask, value & mask, timeout) {
                Ok(waited) => {
                    let (at, status) = self.status_at();
                    Reply::Awaited { at, waited, status }
                }
                Err(()) => {
                    let (at, status) = self.status_at();
                    Reply::AwaitTimedOut { at, status }
                }
            },
            Op::SetInput { input, asserted } => {
                self.chip.set_input(input, asserted);
                Reply::InputSet {
                    at: self.chip.now(),
                }
            }
            Op::ReadPins => Reply::Pins {
                at: self.chip.now(),
                pins: self.chip.pins(),
            },
            Op::ReadPulses => Reply::Pulses {
                at: self.chip.now(),
                summary: self.chip.record().last_move_pulses(),
            },
            Op::AwaitPulses { count, timeout } => match self.wait_pulses(count, timeout) {
                Ok(at) => Reply::PulsesReached { at },
                Err(count) => Reply::PulsesTimedOut {
                    at: self.chip.now(),
                    count,
                },
            },
            Op::Reset => {
                // Straps and config were validated when the target was built.
                if let Ok(chip) = Chip::new(self.straps, self.cfg.clone()) {
                    self.chip = chip;
                }
                Reply::ResetDone {
                    at: self.chip.now(),
                }
            }
        }
    }
}

impl Target for EmuTarget {
    fn info(&self) -> TargetInfo {
        let s = self.chip.straps();
        TargetInfo {
            name: "emu".to_string(),
            details: vec![
                ("sysclk_hz".into(), s.sysclk_hz.to_string()),
                (
                    "csel".into(),
                    if s.csel_high { "high" } else { "low" }.into(),
                ),
                (
                    "vsel".into(),
                    if s.vsel_high { "high" } else { "low" }.into(),
                ),
                (
                    "ext_clock_hz".into(),
                    s.ext_clock_hz.map_or("none".into(), |h| h.to_string()),
                ),
            ],
        }
    }

    fn capture(&mut self) -> Result<Record, TargetError> {
        Ok(self.chip.record().clone())
    }

    fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError> {
        Ok(ops.iter().map(|op| self.run(*op)).collect())
    }
}

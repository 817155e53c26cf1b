//! The emulator as a target: the reference model's [`EmuBus`] behind the
//! [`Target`] trait.

use super::target::{Op, Reply, Target, TargetError, TargetErrorKind, TargetInfo};
use crate::emu::{Chip, ChipError, ModelConfig};
use crate::protocol::{OutputMark, OutputRecord, Straps};
use ppmc_core::bus::{Bus, EmuBus};

/// The in-process emulator. Batches run instantly in wall time; waits are
/// resolved exactly by jumping from one model event to the next.
#[derive(Debug, Clone)]
pub struct EmuTarget {
    bus: EmuBus,
    /// The catalogue's board faults the model was given, for the reports.
    chip_faults: String,
    /// Batches run so far, and the one that fails as a lost link would
    /// (`emu,drop-batch=N`), once.
    batches: u64,
    drop_batch: Option<u64>,
}

impl EmuTarget {
    pub fn new(straps: Straps, cfg: ModelConfig) -> Result<Self, ChipError> {
        Ok(EmuTarget {
            bus: EmuBus::new(straps, cfg)?,
            chip_faults: String::new(),
            batches: 0,
            drop_batch: None,
        })
    }

    /// Makes batch `n` (from 1) fail as a lost link would, once, without
    /// running it (`emu,drop-batch=N`): to try `--retries` and the reports
    /// of a flaky board without one.
    pub fn with_dropped_batch(mut self, n: Option<u64>) -> Self {
        self.drop_batch = n;
        self
    }

    /// Names the board faults its model was made with (`chip-fault=`), so
    /// that the reports say which board this was.
    pub fn with_chip_faults<S: AsRef<str>>(mut self, names: &[S]) -> Self {
        let names: Vec<&str> = names.iter().map(AsRef::as_ref).collect();
        self.chip_faults = names.join("+");
        self
    }

    /// Every register access takes `cycle` of the chip's time
    /// ([`EmuBus::set_bus_cycle`]): a host on a real bus.
    pub fn with_bus_cycle(mut self, cycle: crate::time::Duration) -> Self {
        self.bus.set_bus_cycle(cycle);
        self
    }

    /// How the host times the accesses it waits for
    /// ([`EmuBus::set_host_timing`]).
    pub fn with_host_timing(mut self, host: ppmc_core::bus::HostTiming) -> Self {
        self.bus.set_host_timing(host);
        self
    }

    pub fn chip(&self) -> &Chip {
        self.bus.chip()
    }

    pub fn chip_mut(&mut self) -> &mut Chip {
        self.bus.chip_mut()
    }

    /// The model on its board, as the bus sees it (status reads pass the
    /// board's bus faults).
    pub fn board(&self) -> &crate::emu::Board {
        self.bus.board()
    }

    /// The model as the bridge engine drives it.
    pub fn bus(&self) -> &EmuBus {
        &self.bus
    }
}

impl From<EmuTarget> for EmuBus {
    fn from(t: EmuTarget) -> EmuBus {
        t.bus
    }
}

impl Target for EmuTarget {
    fn info(&self) -> TargetInfo {
        TargetInfo {
            name: "emu".to_string(),
            straps: self.bus.straps(),
            extra: match self.chip_faults.is_empty() {
                true => Vec::new(),
                false => vec![("chip_faults".to_string(), self.chip_faults.clone())],
            },
        }
    }

    fn straps(&self) -> Straps {
        self.bus.straps()
    }

    fn capture(&mut self) -> Result<OutputRecord, TargetError> {
        Ok(self.bus.record().clone())
    }

    fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError> {
        self.batches += 1;
        if self.drop_batch == Some(self.batches) {
            return Err(TargetError::new(
                TargetErrorKind::Link,
                format!(
                    "batch {} dropped on purpose (emu,drop-batch={}): no reply",
                    self.batches, self.batches
                ),
            ));
        }
        Ok(ops.iter().map(|op| self.bus.run(*op)).collect())
    }

    fn execute_then_capture_since(
        &mut self,
        ops: &[Op],
        from: OutputMark,
    ) -> Result<(Vec<Reply>, OutputRecord), TargetError> {
        let replies = self.execute(ops)?;
        Ok((replies, self.bus.record().since(from)))
    }

    fn forget_capture_before(&mut self, mark: OutputMark) -> OutputMark {
        self.bus.forget_record_before(mark)
    }
}

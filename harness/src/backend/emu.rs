//! The emulator as a target: the reference model's [`EmuBus`] behind the
//! [`Target`] trait.

use super::target::{Op, Reply, Target, TargetError, TargetInfo};
use crate::emu::{Chip, ChipError, ModelConfig};
use crate::protocol::{Record, RecordMark, Straps};
use ppmc_core::bus::{Bus, EmuBus};

/// The in-process emulator. Batches run instantly in wall time; waits are
/// resolved exactly by jumping from one model event to the next.
#[derive(Debug, Clone)]
pub struct EmuTarget {
    bus: EmuBus,
}

impl EmuTarget {
    pub fn new(straps: Straps, cfg: ModelConfig) -> Result<Self, ChipError> {
        Ok(EmuTarget {
            bus: EmuBus::new(straps, cfg)?,
        })
    }

    /// Every register access takes `cycle` of the chip's time
    /// ([`EmuBus::set_bus_cycle`]): a host on a real bus.
    pub fn with_bus_cycle(mut self, cycle: crate::time::Duration) -> Self {
        self.bus.set_bus_cycle(cycle);
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
            extra: Vec::new(),
        }
    }

    fn straps(&self) -> Straps {
        self.bus.straps()
    }

    fn capture(&mut self) -> Result<Record, TargetError> {
        Ok(self.bus.record().clone())
    }

    fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError> {
        Ok(ops.iter().map(|op| self.bus.run(*op)).collect())
    }

    fn execute_then_capture_since(
        &mut self,
        ops: &[Op],
        from: RecordMark,
    ) -> Result<(Vec<Reply>, Record), TargetError> {
        let replies = self.execute(ops)?;
        Ok((replies, self.bus.record().since(from)))
    }

    fn forget_capture_before(&mut self, mark: RecordMark) -> RecordMark {
        self.bus.forget_record_before(mark)
    }
}

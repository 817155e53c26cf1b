//! The emulator as a target: the reference model's [`EmuBus`] behind the
//! [`Target`] trait.

use super::{Op, Reply, Target, TargetError, TargetInfo};
use crate::emu::{Chip, ChipError, ModelConfig};
use crate::protocol::{Record, Straps};
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

    pub fn chip(&self) -> &Chip {
        self.bus.chip()
    }

    pub fn chip_mut(&mut self) -> &mut Chip {
        self.bus.chip_mut()
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
        let s = self.bus.straps();
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
        Ok(self.bus.record().clone())
    }

    fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError> {
        Ok(ops.iter().map(|op| self.bus.run(*op)).collect())
    }
}

//! The boot configuration block: how the virtual board learns what a real
//! one reads from its jumpers (the chip's straps), a session number that
//! differs between boots, and the deliberate chip faults to run with.
//!
//! `firmware/run-qemu` writes it into the last 256 bytes of RAM with
//! QEMU's generic loader before the CPU starts. Little endian:
//!
//! | offset | field |
//! |---|---|
//! | 0 | magic `PPMC` |
//! | 4 | layout version u16 (1), 2 bytes zero |
//! | 8 | session u32 |
//! | 12 | SysClk in Hz u32 |
//! | 16 | flags u8: bit 0 CSEL high, bit 1 VSEL high, bit 2 an external clock; 3 bytes zero |
//! | 20 | external clock in Hz u32 (0 without one) |
//! | 24 | chip faults: names from the board-fault catalogue, comma-separated, ASCII, NUL-terminated (at most 231 bytes) |
//!
//! Without the block (a bare `qemu-system-arm -kernel`), the board boots
//! with the default straps, no faults and session 1. A block that is there
//! but wrong stops the board with a message on QEMU's standard error.

use core::fmt;
use ppmc_core::emu::{faults, ModelConfig};
use ppmc_core::protocol::Straps;

const ADDR: usize = 0x2040_0000 - 256;
const LEN: usize = 256;
const MAGIC: &[u8; 4] = b"PPMC";
const LAYOUT: u16 = 1;

/// What the board was booted with.
#[derive(Debug)]
pub struct BootConfig {
    pub session: u32,
    pub straps: Straps,
    pub model: ModelConfig,
}

impl BootConfig {
    /// Reads the block `run-qemu` loaded, or the defaults without one.
    pub fn load() -> BootConfig {
        let mut raw = [0u8; LEN];
        for (i, b) in raw.iter_mut().enumerate() {
            // SAFETY: the block lies in RAM the program never uses
            // (memory.x leaves it out), always mapped and readable.
            *b = unsafe { core::ptr::read_volatile((ADDR + i) as *const u8) };
        }
        match parse(&raw) {
            Ok(Some(c)) => c,
            Ok(None) => BootConfig {
                session: 1,
                straps: Straps::default(),
                model: ModelConfig::default(),
            },
            Err(e) => halt(format_args!("boot configuration: {e}")),
        }
    }
}

fn u32_at(raw: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([raw[at], raw[at + 1], raw[at + 2], raw[at + 3]])
}

/// The configuration in `raw`; `None` when there is no block.
fn parse(raw: &[u8; LEN]) -> Result<Option<BootConfig>, alloc::string::String> {
    use alloc::format;
    if &raw[..4] != MAGIC {
        return Ok(None);
    }
    let layout = u16::from_le_bytes([raw[4], raw[5]]);
    if layout != LAYOUT {
        return Err(format!("layout {layout}, this firmware reads {LAYOUT}"));
    }
    let flags = raw[16];
    if flags & !0b111 != 0 {
        return Err(format!("unknown strap flags 0x{flags:02X}"));
    }
    let ext = u32_at(raw, 20);
    let straps = Straps {
        sysclk_hz: u32_at(raw, 12),
        csel_high: flags & 1 != 0,
        vsel_high: flags & 2 != 0,
        ext_clock_hz: (flags & 4 != 0).then_some(ext),
    };
    straps.validate().map_err(|e| format!("straps: {e}"))?;
    let names = &raw[24..];
    let end = names
        .iter()
        .position(|&b| b == 0)
        .ok_or("the fault list has no NUL")?;
    let names = core::str::from_utf8(&names[..end]).map_err(|_| "the fault list is not ASCII")?;
    let mut model = ModelConfig::default();
    for name in names.split(',').filter(|n| !n.is_empty()) {
        faults::apply_named(name, &mut model).map_err(|e| format!("{e}"))?;
    }
    Ok(Some(BootConfig {
        session: u32_at(raw, 8),
        straps,
        model,
    }))
}

/// Says why on QEMU's standard error (semihosting) and ends the emulation
/// with a failure, so that `run-qemu` exits and says so.
pub fn halt(why: fmt::Arguments<'_>) -> ! {
    cortex_m_semihosting::hprintln!("ppmc-bridge-qemu: {}", why);
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}

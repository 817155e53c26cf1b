//! The RP2350 on rp2350-emu with the bridge's board around it: the image
//! booted as the bootrom would start it, and its GPIOs wired, pad by pad,
//! to the board of `docs/bridge-hardware.md` and the reference chip model
//! behind it (the twin's [`ChipSide`], the same board model the twin
//! runs).
//!
//! - **Boot.** rp2350-emu does not ship the RP2350's bootrom (and 0.2.6
//!   cannot yet run its flash boot), so a stand-in does what the bootrom
//!   does for an image like ours (RP2350 datasheet 5.9.5, a plain Arm
//!   image whose vector table starts the flash): core 0 starts at the
//!   reset vector with the vector table's stack pointer and VTOR at the
//!   flash, core 1 sleeps, and [`Machine`] plays core 1's bootrom wait
//!   loop on the inter-core FIFOs until the image launches core 1
//!   (datasheet 5.3).
//! - **Pins.** After each quantum of the emulator, the levels on the 48
//!   GPIOs are worked out as a pad would: the function FUNCSEL names
//!   (IO_BANK0 GPIOn_CTRL, datasheet 9.11.1) drives a pin where it enables
//!   its output; otherwise the board does (the chip's outputs, the
//!   shifter, the buffers' resistors: [`ChipSide`]); otherwise the pad's
//!   pull (PADS_BANK0, datasheet 9.11.3); otherwise it floats, and reads
//!   low here (counted in [`Machine::floating`]). Those levels are what
//!   the cores and the PIO blocks read in the next quantum.
//!
//! The chip sees the RP2350's pins once per quantum, and the RP2350 sees
//! the chip's answer in the quantum after: [`QUANTUM`] cycles each way.

use ppmc_bridge_fw::twin::chip::ChipSide;
use ppmc_bridge_fw::twin::pio::Outside;
use rp2350_emu::{Config, Emulator, EmulatorBuilder};
use std::sync::atomic::Ordering;

/// The RP2350's system clock as the image sets it (150 MHz).
pub const SYS_CLK_HZ: u32 = 150_000_000;

/// Cycles the emulator runs between two looks at the pins: 2 cycles,
/// 13 ns at 150 MHz, one tick of the bridge's timer. The chip's edges
/// reach the RP2350 on a quantum's boundary, so a quantum is the jitter
/// the emulation adds to every captured edge; at 4 cycles (2 ticks) it
/// was more than a pulse run's tolerance (a tick and a nanosecond), where
/// a real RP2350's counters see an edge within their 2-cycle pass. It
/// costs some 5 % of the emulator's speed. The bus
/// player's shortest step is 7 cycles (`ppmc_bridge_fw::programs::bus_player`),
/// so an answer a quantum late is still within the step that samples it.
pub const QUANTUM: u32 = 2;

/// Where the image lies: the XIP flash window.
pub const FLASH: u32 = 0x1000_0000;
const FLASH_SIZE: usize = 16 << 20;

const IO_BANK0: u32 = 0x4002_8000;
const PADS_BANK0: u32 = 0x4003_8000;
/// GPIOs of the RP2350B.
const GPIOS: usize = 48;
/// FUNCSEL values (RP2350 datasheet 9.4, the function table).
const F_SIO: u32 = 5;
const F_PIO0: u32 = 6;

/// How often (in quanta) the pads' functions and pulls are read again:
/// the image sets them at boot and when the self-test pulls its inputs
/// up, far apart in time.
const PADS_EVERY: u64 = 256;

/// Which function drives each pin, and each pad's pulls, as masks.
#[derive(Debug, Default, Clone, Copy)]
struct Pads {
    sio: u64,
    pio: [u64; 3],
    pull_up: u64,
    pull_down: u64,
}

/// Core 1's bootrom, as far as the launch: it echoes what core 0 sends
/// and, after 0, 0, 1, vector table, stack pointer, entry, starts core 1
/// (RP2350 datasheet 5.3).
#[derive(Debug, Default)]
struct Launch {
    seen: Vec<u32>,
    done: bool,
}

/// The emulated RP2350 and the board around it.
pub struct Machine {
    pub emu: Emulator,
    chip: ChipSide,
    launch: Launch,
    pads: Pads,
    quanta: u64,
    /// Quanta in which a pin that someone reads floated.
    pub floating: u64,
}

impl std::fmt::Debug for Machine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Machine")
            .field("cycles", &self.emu.cycles())
            .field("core1_launched", &self.launch.done)
            .finish_non_exhaustive()
    }
}

/// A flash image from an ELF's loadable segments: each at its load
/// address in the flash window, as `firmware/build`'s UF2 places them.
pub fn flash_image(elf: &[u8]) -> Result<Vec<u8>, String> {
    let elf = ppmc_fwtool::elf::Elf::parse(elf)?;
    let mut flash = Vec::new();
    for s in elf.loadable() {
        let start = s.addr.checked_sub(FLASH).map(|o| o as usize);
        let Some(start) = start.filter(|o| o + s.data.len() <= FLASH_SIZE) else {
            return Err(format!(
                "a loadable segment at {:#010x} ({} bytes) lies outside the flash \
                 ({FLASH:#010x}, 16 MiB): not an image for the RP2350's flash",
                s.addr,
                s.data.len()
            ));
        };
        if flash.len() < start + s.data.len() {
            flash.resize(start + s.data.len(), 0xFF);
        }
        flash[start..start + s.data.len()].copy_from_slice(&s.data);
    }
    if flash.len() < 8 {
        return Err("no vector table at the start of the flash".into());
    }
    Ok(flash)
}

fn word(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

impl Machine {
    /// Boots `flash` (see [`flash_image`]) with `chip` on its pins.
    pub fn boot(flash: &[u8], chip: ChipSide) -> Result<Machine, String> {
        let mut emu = EmulatorBuilder::new(Config {
            sys_clk_hz: SYS_CLK_HZ,
        })
        .step_quantum(QUANTUM)
        .build()
        .map_err(|e| format!("rp2350-emu: {e:?}"))?;
        let (sp, reset) = (word(flash, 0), word(flash, 4));
        if reset & 1 == 0 || !(FLASH..FLASH + flash.len() as u32).contains(&(reset & !1)) {
            return Err(format!(
                "the reset vector {reset:#010x} is not Thumb code in the image"
            ));
        }
        // The stand-in bootrom holds only the image's first two vectors,
        // so that the emulator's own reset finds a stack and an entry.
        let mut rom = vec![0u8; 32 * 1024];
        rom[0..4].copy_from_slice(&sp.to_le_bytes());
        rom[4..8].copy_from_slice(&reset.to_le_bytes());
        emu.load_bootrom(&rom);
        emu.load_flash(flash);
        emu.reset();
        emu.core_mut(1).halt();
        let c0 = emu.core_mut(0);
        c0.ppb.vtor = FLASH;
        c0.regs.msp = sp;
        c0.regs.r[13] = sp;
        c0.regs.set_pc(reset & !1);
        let mut m = Machine {
            emu,
            chip,
            launch: Launch::default(),
            pads: Pads::default(),
            quanta: 0,
            floating: 0,
        };
        m.read_pads();
        Ok(m)
    }

    /// The emulator's clock: cycles of the system clock since boot.
    pub fn cycles(&self) -> u64 {
        self.emu.cycles()
    }

    /// Where each core is and what the USB controller holds, for a
    /// message about an image that did not get where it should have.
    pub fn where_it_is(&mut self) -> String {
        let mut r = |a: u32| self.emu.mmio_read32(a);
        let usb: Vec<u32> = [0x40, 0x4C, 0x50, 0x90, 0x78]
            .iter()
            .map(|o| r(0x5011_0000 + o))
            .collect();
        let timer = r(0x400B_0028);
        format!(
            "after {} cycles core 0 is at {:#010x}, core 1 at {:#010x} ({}); USB MAIN_CTRL {:#x}, \
             SIE_CTRL {:#x}, SIE_STATUS {:#x}, INTE {:#x}, USB_PWR {:#x}; TIMER0 {} us; clk_sys {} Hz, clk_ref {} Hz",
            self.emu.cycles(),
            self.emu.core(0).regs.pc(),
            self.emu.core(1).regs.pc(),
            if self.launch.done { "launched" } else { "not launched" },
            usb[0],
            usb[1],
            usb[2],
            usb[3],
            usb[4],
            timer,
            self.emu.bus.sys_clk_hz(),
            self.emu.bus.ref_clk_hz(),
        )
    }

    /// Runs at least `cycles` more cycles, quantum by quantum, the pins
    /// exchanged between each two.
    pub fn run(&mut self, cycles: u64) -> Result<(), String> {
        let end = self.emu.cycles() + cycles;
        while self.emu.cycles() < end {
            if !self.launch.done {
                self.play_core1_bootrom();
            }
            self.emu
                .run_quantum()
                .map_err(|e| format!("rp2350-emu stopped at cycle {}: {e:?}", self.emu.cycles()))?;
            self.quanta += 1;
            if self.quanta.is_multiple_of(PADS_EVERY) {
                self.read_pads();
            }
            self.exchange_pins();
        }
        Ok(())
    }

    fn play_core1_bootrom(&mut self) {
        while let Some(v) = self.emu.bus.sio.core1_fifo_pop() {
            self.emu.bus.sio.core1_fifo_push(v);
            let seen = &mut self.launch.seen;
            // A 0 restarts the sequence (the wait loop drains, then syncs).
            if v == 0 && (seen.len() != 1 || seen[0] != 0) {
                seen.clear();
            }
            seen.push(v);
            if seen.len() == 6 && seen[..3] == [0, 0, 1] {
                let (vt, sp, entry) = (seen[3], seen[4], seen[5]);
                let c1 = self.emu.core_mut(1);
                c1.ppb.vtor = vt;
                c1.regs.msp = sp;
                c1.regs.r[13] = sp;
                c1.regs.set_pc(entry & !1);
                c1.wake();
                self.launch.done = true;
                return;
            }
        }
    }

    fn read_pads(&mut self) {
        let mut p = Pads::default();
        for g in 0..GPIOS {
            let ctrl = self.emu.mmio_read32(IO_BANK0 + 8 * g as u32 + 4);
            let pad = self.emu.mmio_read32(PADS_BANK0 + 4 + 4 * g as u32);
            let bit = 1u64 << g;
            match ctrl & 0x1F {
                F_SIO => p.sio |= bit,
                f @ F_PIO0..=8 => p.pio[(f - F_PIO0) as usize] |= bit,
                _ => {}
            }
            // PUE bit 3, PDE bit 2 (datasheet 9.11.3); both: a bus keeper.
            match (pad >> 3 & 1 == 1, pad >> 2 & 1 == 1) {
                (true, false) => p.pull_up |= bit,
                (false, true) => p.pull_down |= bit,
                _ => {}
            }
        }
        self.pads = p;
    }

    /// What the RP2350 drives: (levels, output enables) over 48 GPIOs.
    fn rp2350_drives(&self) -> (u64, u64) {
        let sio = &self.emu.bus.sio;
        let p = &self.pads;
        // SIO's GPIO_HI_OUT/OE are not modelled by rp2350-emu 0.2.6; the
        // image drives no pin above 31 from SIO.
        let mut out = u64::from(sio.gpio_out) & p.sio;
        let mut oe = u64::from(sio.gpio_oe) & p.sio;
        for (b, pio) in self.emu.bus.pio.iter().enumerate() {
            let (o_lo, o_hi) = pio.local_to_physical_pins(pio.pad_out);
            let (e_lo, e_hi) = pio.local_to_physical_pins(pio.pad_oe);
            let o = u64::from(o_lo) | u64::from(o_hi) << 32;
            let e = u64::from(e_lo) | u64::from(e_hi) << 32;
            out |= o & e & p.pio[b];
            oe |= e & p.pio[b];
        }
        (out & oe, oe)
    }

    fn exchange_pins(&mut self) {
        let cycle = self.emu.cycles();
        let (out, oe) = self.rp2350_drives();
        let (levels, driven) = self.chip.drive(cycle, out, oe);
        let p = &self.pads;
        let undriven = !oe & !driven & ((1 << GPIOS) - 1);
        if undriven & !(p.pull_up | p.pull_down) & (p.sio | p.pio[0] | p.pio[1] | p.pio[2]) != 0 {
            self.floating += 1;
        }
        let pin = (out & oe) | (levels & driven & !oe) | (p.pull_up & undriven);
        let bus = &mut self.emu.bus;
        bus.gpio_external_mask = u32::MAX;
        bus.gpio_external_in.store(pin as u32, Ordering::Relaxed);
        bus.set_gpio_external_in_hi((pin >> 32) as u32 & 0xFFFF, 0xFFFF);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 32-bit little-endian ELF with one loadable segment of `data` at
    /// `addr`.
    fn elf(addr: u32, data: &[u8]) -> Vec<u8> {
        let mut b = vec![0u8; 0x34 + 32];
        b[..6].copy_from_slice(b"\x7fELF\x01\x01");
        b[0x1C..0x20].copy_from_slice(&0x34u32.to_le_bytes()); // phoff
        b[0x2A..0x2C].copy_from_slice(&32u16.to_le_bytes()); // phentsize
        b[0x2C..0x2E].copy_from_slice(&1u16.to_le_bytes()); // phnum
        let off = b.len() as u32;
        let ph = 0x34;
        b[ph..ph + 4].copy_from_slice(&1u32.to_le_bytes()); // PT_LOAD
        b[ph + 4..ph + 8].copy_from_slice(&off.to_le_bytes());
        b[ph + 12..ph + 16].copy_from_slice(&addr.to_le_bytes()); // paddr
        b[ph + 16..ph + 20].copy_from_slice(&(data.len() as u32).to_le_bytes());
        b.extend_from_slice(data);
        b
    }

    #[test]
    fn the_flash_image_holds_each_segment_at_its_load_address() {
        let f = flash_image(&elf(FLASH + 4, &[1, 2, 3, 4, 5, 6, 7, 8])).expect("an image");
        assert_eq!(f, [0xFF, 0xFF, 0xFF, 0xFF, 1, 2, 3, 4, 5, 6, 7, 8]);
    }

    #[test]
    fn a_segment_outside_the_flash_is_refused_with_its_address() {
        let e = flash_image(&elf(0x2000_0000, &[0; 8])).expect_err("RAM");
        assert!(e.contains("0x20000000"), "{e}");
    }
}

//! Why the bridge last restarted, as the RP2350 image keeps it across the
//! watchdog's reset and says it in HELLO_REPLY's firmware text (`;
//! restarted after ...`, which `ppmc` reports as an infrastructure error
//! naming the cause).
//!
//! Two things survive a watchdog reset (RP2350 datasheet, Watchdog
//! chapter): the scratch registers, and REASON, which says whether the
//! watchdog's timer ran out (TIMER, bit 0) or the chip was reset through
//! it on purpose (FORCE, bit 1); both are 0 after a power-on or the RUN
//! pin. The image writes a [`Record`] into SCRATCH0-3 before it resets
//! itself on a panic or a hard fault (the bootrom uses SCRATCH4-7); a
//! reset with TIMER set and no record is a hang: some loop stopped
//! feeding the watchdog.
//!
//! The watchdog's reset goes through the power-on state machine's WDSEL
//! register: [`PSM_WDSEL`].

use alloc::string::String;
use core::fmt;

/// The stages of the RP2350's power-on state machine, as bits of its
/// FRCE_ON, FRCE_OFF, WDSEL and DONE registers (RP2350 datasheet,
/// Power-on state machine chapter). The RP2040's layout differs: its
/// ROSC is bit 0 and its processors bits 15 and 16.
pub mod psm {
    /// The ring oscillator.
    pub const ROSC: u32 = 1 << 2;
    /// The crystal oscillator.
    pub const XOSC: u32 = 1 << 3;
    /// Processor 0.
    pub const PROC0: u32 = 1 << 23;
    /// Processor 1.
    pub const PROC1: u32 = 1 << 24;
    /// Every stage, PROC_COLD (bit 0) to PROC1 (bit 24).
    pub const ALL: u32 = (1 << 25) - 1;
}

/// What the watchdog resets: every stage but the two oscillators, which
/// keep running so that the restart does not wait for them (what
/// pico-sdk's `watchdog_reboot` selects on the RP2350).
pub const PSM_WDSEL: u32 = psm::ALL & !(psm::ROSC | psm::XOSC);

/// WATCHDOG REASON: the timer ran out.
pub const REASON_TIMER: u32 = 1 << 0;
/// WATCHDOG REASON: a reset forced through the watchdog.
pub const REASON_FORCE: u32 = 1 << 1;

/// SCRATCH0 of a [`Record`] of a panic, before it is mixed with the file
/// name's check ("PPMC").
const MAGIC: u32 = 0x5050_4d43;
/// SCRATCH0 of a [`Record`] of a hard fault ("PPHF").
const HARD_FAULT: u32 = 0x5050_4846;

/// A restart's record in the watchdog's SCRATCH0-3.
///
/// A panic keeps where its file's name is in flash and how long it is,
/// not the name: four words hold no path, and the name of every file the
/// image was built from is in its read-only data, which a reset keeps.
/// SCRATCH0 is a magic number mixed with a check of the name, so that a record
/// left by another image (flashed in between) is told from this one's.
/// A hard fault keeps its PC.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Record(pub [u32; 4]);

impl Record {
    /// A panic at `line` of the file whose name is `name`, at `address`
    /// in the image's flash.
    pub fn panic(address: u32, name: &[u8], line: u32) -> Record {
        let len = name.len().min(u16::MAX as usize);
        Record([MAGIC ^ check(&name[..len]), line, address, len as u32])
    }

    /// A hard fault at `pc`.
    pub fn hard_fault(pc: u32) -> Record {
        Record([HARD_FAULT, pc, 0, 0])
    }
}

/// FNV-1a over `bytes`: the check of a file name in a [`Record`].
fn check(bytes: &[u8]) -> u32 {
    bytes.iter().fold(0x811c_9dc5, |h: u32, b| {
        (h ^ u32::from(*b)).wrapping_mul(0x0100_0193)
    })
}

/// Why the bridge restarted.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Cause {
    /// A panic at `file:line`.
    Panic { file: String, line: u32 },
    /// A panic whose file name is no longer where the record says (another
    /// image was flashed since).
    PanicElsewhere { line: u32 },
    /// A hard fault at `pc`.
    HardFault { pc: u32 },
    /// The watchdog's timer ran out: a loop stopped feeding it.
    Hang,
}

impl fmt::Display for Cause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Cause::Panic { file, line } => write!(f, "a panic at {file}:{line}"),
            Cause::PanicElsewhere { line } => write!(
                f,
                "a panic at line {line} of a file of another image (flashed since)"
            ),
            Cause::HardFault { pc } => write!(f, "a hard fault at pc {pc:#010x}"),
            Cause::Hang => f.write_str("a hang (the watchdog's timer ran out)"),
        }
    }
}

/// Why the last reset happened, from SCRATCH0-3 and REASON as the boot
/// found them; `None` after a power-on, the RUN pin (REASON 0) or a reset
/// forced with no record of ours. `flash(address, len)` gives the `len` bytes of the image's
/// flash at `address`, or `None` when they are not all in it.
pub fn cause<'a>(
    scratch: [u32; 4],
    reason: u32,
    flash: impl FnOnce(u32, usize) -> Option<&'a [u8]>,
) -> Option<Cause> {
    let [tag, line, address, len] = scratch;
    if tag == HARD_FAULT {
        return Some(Cause::HardFault { pc: line });
    }
    if len > 0 && len <= u32::from(u16::MAX) {
        if let Some(name) = flash(address, len as usize) {
            if tag == MAGIC ^ check(name) {
                return Some(match core::str::from_utf8(name) {
                    Ok(file) => Cause::Panic {
                        file: file.into(),
                        line,
                    },
                    Err(_) => Cause::PanicElsewhere { line },
                });
            }
        }
    }
    if reason & REASON_TIMER != 0 {
        Some(Cause::Hang)
    } else if reason & REASON_FORCE != 0 && tag != 0 && len > 0 {
        // A record whose file name is not where it says: another image's.
        Some(Cause::PanicElsewhere { line })
    } else {
        // A power-on, the RUN pin, or a reset forced with no record of
        // ours (the bootrom's after a flash, picotool's): nothing failed.
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    /// Every PSM stage set by name in Raspberry Pi's register description
    /// of the RP2350 (rp-pac, generated from its SVD), but the two
    /// oscillators: PSM_WDSEL, with both processors in it.
    #[test]
    fn the_watchdog_resets_every_stage_but_the_oscillators_in_the_rp2350s_layout() {
        let mut w = rp_pac::psm::regs::Wdsel(0);
        w.set_proc_cold(true);
        w.set_otp(true);
        w.set_resets(true);
        w.set_clocks(true);
        w.set_psm_ready(true);
        w.set_busfabric(true);
        w.set_rom(true);
        w.set_bootram(true);
        w.set_sram0(true);
        w.set_sram1(true);
        w.set_sram2(true);
        w.set_sram3(true);
        w.set_sram4(true);
        w.set_sram5(true);
        w.set_sram6(true);
        w.set_sram7(true);
        w.set_sram8(true);
        w.set_sram9(true);
        w.set_xip(true);
        w.set_sio(true);
        w.set_accessctrl(true);
        w.set_proc0(true);
        w.set_proc1(true);
        assert_eq!(PSM_WDSEL, w.0, "{PSM_WDSEL:#010x} against {:#010x}", w.0);
        let sel = rp_pac::psm::regs::Wdsel(PSM_WDSEL);
        assert!(!sel.rosc() && !sel.xosc(), "the oscillators keep running");
        assert!(sel.proc0() && sel.proc1(), "both processors restart");
        // pico-sdk's value for the same selection.
        assert_eq!(PSM_WDSEL, 0x01ff_fff3);
    }

    /// REASON's bits where Raspberry Pi's register description has them.
    #[test]
    fn the_reason_bits_are_the_rp2350s() {
        let mut r = rp_pac::watchdog::regs::Reason(0);
        r.set_timer(true);
        assert_eq!(r.0, REASON_TIMER);
        let mut r = rp_pac::watchdog::regs::Reason(0);
        r.set_force(true);
        assert_eq!(r.0, REASON_FORCE);
    }

    /// A flash of one image: `name` at 0x1000_4000.
    fn flash_with(name: &'static [u8]) -> impl Fn(u32, usize) -> Option<&'static [u8]> {
        move |address, len| (address == 0x1000_4000 && len == name.len()).then_some(name)
    }

    #[test]
    fn a_panic_names_its_whole_file() {
        let name = b"bridge/src/board/cycles.rs";
        let r = Record::panic(0x1000_4000, name, 123);
        let c = cause(r.0, REASON_FORCE, flash_with(name)).expect("a cause");
        assert_eq!(c.to_string(), "a panic at bridge/src/board/cycles.rs:123");
        // Two files that share their first eight bytes stay two.
        let other = b"bridge/src/board/capture.rs";
        let r = Record::panic(0x1000_4000, other, 9);
        let c = cause(r.0, REASON_FORCE, flash_with(other)).expect("a cause");
        assert_eq!(c.to_string(), "a panic at bridge/src/board/capture.rs:9");
    }

    #[test]
    fn a_record_of_another_image_is_not_read_as_this_ones() {
        let r = Record::panic(0x1000_4000, b"bridge/src/board/cycles.rs", 123);
        let now = flash_with(b"bridge/src/board/ops.rs\0\0\0");
        let c = cause(r.0, REASON_FORCE, now).expect("a cause");
        assert_eq!(c, Cause::PanicElsewhere { line: 123 });
        // A record pointing out of flash is no panic's file either.
        let c = cause(r.0, REASON_FORCE, |_, _| None).expect("a cause");
        assert_eq!(c, Cause::PanicElsewhere { line: 123 });
    }

    #[test]
    fn a_hard_fault_keeps_its_pc() {
        let r = Record::hard_fault(0x1000_2a4c);
        let c = cause(r.0, REASON_FORCE, |_, _| None).expect("a cause");
        assert_eq!(c.to_string(), "a hard fault at pc 0x10002a4c");
    }

    /// The watchdog's timer ran out with no record: a hang, said so, not
    /// a plain new session.
    #[test]
    fn a_watchdog_timeout_without_a_record_is_a_hang() {
        let c = cause([0; 4], REASON_TIMER, |_, _| None).expect("a cause");
        assert_eq!(c, Cause::Hang);
        assert_eq!(c.to_string(), "a hang (the watchdog's timer ran out)");
        // A power-on or the RUN pin: nothing to say; nor after a reset
        // forced with no record of ours (the bootrom's after a flash).
        assert_eq!(cause([0; 4], 0, |_, _| None), None);
        assert_eq!(cause([0; 4], REASON_FORCE, |_, _| None), None);
    }
}

//! UART0 of the mps2-an386: an ARM CMSDK APB UART at 0x4000_4000, one byte
//! each way, no FIFO. QEMU holds further received bytes back until the
//! firmware has read the last one, so nothing is lost while the engine
//! works; the firmware sleeps (WFI) on its receive interrupt when idle, so
//! an idle virtual board costs the host no CPU.

use alloc::vec::Vec;
use core::ptr::{read_volatile, write_volatile};
use cortex_m::interrupt::InterruptNumber;
use cortex_m::peripheral::NVIC;

const BASE: usize = 0x4000_4000;
const DATA: usize = BASE;
const STATE: usize = BASE + 0x04;
const CTRL: usize = BASE + 0x08;
const INTSTATUS: usize = BASE + 0x0C;
const BAUDDIV: usize = BASE + 0x10;

const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_RX_INT_EN: u32 = 1 << 3;
const INT_RX: u32 = 1 << 1;

/// UART0's receive interrupt on the mps2-an385/an386.
#[derive(Debug, Clone, Copy)]
struct Uart0Rx;

// SAFETY: 0 is UART0 RX's line on this board's NVIC, and a valid number.
unsafe impl InterruptNumber for Uart0Rx {
    fn number(self) -> u16 {
        0
    }
}

/// The UART, enabled both ways.
#[derive(Debug)]
pub struct Uart(());

fn read(reg: usize) -> u32 {
    // SAFETY: `reg` is one of this UART's registers, always mapped.
    unsafe { read_volatile(reg as *const u32) }
}

fn write(reg: usize, v: u32) {
    // SAFETY: as for `read`.
    unsafe { write_volatile(reg as *mut u32, v) }
}

impl Uart {
    /// Sets the UART up: both directions, and its receive interrupt as a
    /// wake-up source. Interrupts stay masked (PRIMASK): WFI wakes on a
    /// pending one without running a handler.
    pub fn take() -> Uart {
        cortex_m::interrupt::disable();
        write(BAUDDIV, 16);
        write(CTRL, CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INT_EN);
        // SAFETY: with PRIMASK set no handler runs; the line only wakes WFI.
        unsafe { NVIC::unmask(Uart0Rx) };
        Uart(())
    }

    /// Appends the bytes waiting now to `out`, sleeping until there is at
    /// least one; at most until `out` is full (its capacity: the rest wait
    /// in QEMU, so that a host that never pauses costs no more memory).
    pub fn read_available(&mut self, out: &mut Vec<u8>) {
        while read(STATE) & STATE_RX_FULL == 0 {
            cortex_m::asm::wfi();
            write(INTSTATUS, INT_RX);
            NVIC::unpend(Uart0Rx);
        }
        // A short look for more: QEMU hands the next byte over as soon as
        // the last one is read.
        let mut idle = 0;
        while idle < 64 && out.len() < out.capacity() {
            if read(STATE) & STATE_RX_FULL != 0 {
                out.push(read(DATA) as u8);
                idle = 0;
            } else {
                idle += 1;
            }
        }
    }

    pub fn write_all(&mut self, bytes: &[u8]) {
        for &b in bytes {
            while read(STATE) & STATE_TX_FULL != 0 {}
            write(DATA, u32::from(b));
        }
    }
}

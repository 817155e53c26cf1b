//! The bus bridge firmware on a virtual board: QEMU's `mps2-an386`
//! (a Cortex-M4 with a CMSDK APB UART), the reference model from
//! `ppmc-core` as the chip behind the bridge engine's `Bus` trait.
//!
//! It runs the same `BridgeEngine` as `ppmc bridge-sim` and the RP2350
//! firmware, compiled for a microcontroller, with its own heap, on an
//! emulated CPU, and talks to the host over the UART (`-serial pty`), so
//! `ppmc run --target serial:/dev/pts/N` exercises the firmware build of
//! the protocol end to end. `firmware/run-qemu` starts it.
//!
//! The board learns its straps, its boot session and any deliberate chip
//! faults from a boot configuration block that `run-qemu` loads into the
//! last 256 bytes of RAM ([`BootConfig`]); a real bridge reads its straps
//! from its own jumpers or flash (docs/bridge-hardware.md).

#![no_std]
#![no_main]

extern crate alloc;

mod config;
mod uart;

use config::BootConfig;
use core::mem::MaybeUninit;
use cortex_m_rt::entry;
use embedded_alloc::LlffHeap as Heap;
use ppmc_bridge_fw::limits::{CAPTURE_RECORDS, HEAP_BYTES};
use ppmc_core::bridge::engine::BridgeEngine;
use ppmc_core::bus::EmuBus;

#[global_allocator]
static HEAP: Heap = Heap::empty();

/// The RP2350 board's heap, with its capture capacity
/// (`ppmc_bridge_fw::limits`, one source for every image): this board
/// keeps the board's limits, so that it shows what the board does when the
/// capture or the heap fills. The heap holds the model, its capture and
/// the engine's buffers; the model takes a few KB of it, within what
/// `limits::CHIP_BYTES` allows the board code on the board. Beyond the
/// heap this image needs only what the board's does: statics, and its
/// stack (cortex-m-rt's, from the top of RAM down), which has the rest of
/// the 4 MiB where the board's stacks share what its 512 KiB leave.
const HEAP_SIZE: usize = HEAP_BYTES;

/// Bytes handed to the engine at a time: the board gets the host's bytes in
/// USB packets of 64, and the engine answers each piece as it comes.
const PIECE: usize = 64;

/// What HELLO_REPLY says this bridge runs.
const FIRMWARE: &str = concat!(
    "ppmc-bridge-qemu ",
    env!("CARGO_PKG_VERSION"),
    " (mps2-an386, virtual chip)"
);

#[entry]
fn main() -> ! {
    // `entry` turns this into a `&'static mut` that only `main` holds.
    static mut HEAP_MEM: [MaybeUninit<u8>; HEAP_SIZE] = [MaybeUninit::uninit(); HEAP_SIZE];
    // SAFETY: runs once, before anything allocates, with memory nothing
    // else can reach.
    unsafe { HEAP.init(HEAP_MEM.as_mut_ptr() as usize, HEAP_SIZE) }

    let config = BootConfig::load();
    let bus = match EmuBus::new(config.straps, config.model) {
        Ok(bus) => bus,
        Err(e) => config::halt(format_args!("the virtual chip cannot start: {e}")),
    };
    let mut engine = BridgeEngine::new(bus, config.session, true, FIRMWARE)
        .with_capture_capacity(CAPTURE_RECORDS);
    let mut uart = uart::Uart::take();
    // `run-qemu` announces the board once it says this (QEMU's stdout).
    cortex_m_semihosting::hprintln!("ppmc-bridge-qemu: ready, session {}", config.session);
    let mut incoming = alloc::vec::Vec::with_capacity(4096);
    loop {
        incoming.clear();
        uart.read_available(&mut incoming);
        for piece in incoming.chunks(PIECE) {
            let reply = engine.on_bytes(piece);
            uart.write_all(&reply);
        }
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    config::halt(format_args!("{info}"))
}

//! The RP2350 bridge's own code, testable on a host: its pin map, PIO
//! programs and their register configuration, bus cycles as timed steps,
//! the capture's timebase, the bridge clock, and the board code
//! ([`board`]) over a thin hardware layer ([`hal`]). The RP2350 image runs
//! all of it on the chip; the board twin ([`twin`], feature `twin`) runs
//! the same code on a model of the RP2350's PIO and GPIOs wired to the
//! reference chip model.
//!
//! - [`bus_cycle`]: a bus cycle (write command, write data, read status, read
//!   data) as a few *steps*, each a state of the bus pins held for a number
//!   of cycles; [`programs::bus_player`] plays them. Setup, strobe and hold
//!   times are [`bus_cycle::BusTiming`], configurable, with conservative defaults
//!   (the datasheet's bus-timing chapter is not in our hands:
//!   `docs/datasheet-notes.md` N46).
//! - [`programs::edge_counter`]: a state machine that stamps each rising
//!   edge of one pin (POUT, with DIR) or each change of one pin with a
//!   counter that ticks every second system clock cycle on every path.
//! - [`timebase`]: the 31-bit counts the capture pushes, turned into ticks
//!   since the timebase started.
//! - [`usb`]: core 0's loop between the USB port and the engine's pipes,
//!   with a deadline on every packet written.
//! - [`ring`]: the DMA rings the counters' words go to, and how the CPU
//!   reads them and tells a ring the DMA came round on.
//! - [`dma`]: the DMA channels that fill the rings, register by register:
//!   programmed, read, and re-armed when one stops.
//! - [`pioregs`]: the state machines' registers, as values.
//! - [`clock`]: the bridge's 64-bit cycle clock from the core's cycle
//!   counter and the always-running timer.
//! - [`limits`]: the heap and the capture capacity every image keeps (the
//!   QEMU board's too), and why the capture fills before the heap.
//! - [`restart`]: why the bridge last restarted (a panic, a hard fault, a
//!   hang), as the image keeps it across the watchdog's reset.

#![no_std]

extern crate alloc;
#[cfg(any(test, feature = "twin"))]
extern crate std;

pub mod board;
pub mod bus_cycle;
pub mod clock;
pub mod dma;
pub mod hal;
pub mod limits;
pub mod pins;
pub mod pioregs;
pub mod programs;
pub mod restart;
pub mod ring;
pub mod timebase;
#[cfg(any(test, feature = "twin"))]
pub mod twin;
pub mod usb;

//! A model of the RP2350's PIO blocks and GPIOs that holds the bridge's
//! code to the silicon's rules (RP2350 datasheet, PIO chapter), cycle by
//! cycle:
//!
//! - 32 instruction words per block, shared by every program loaded into
//!   it: loading past them fails, as embassy-rp's `load_program` panics;
//! - FIFO depths from the join bits: 4 + 4, or 8 for a joined direction; a
//!   write to a full TX FIFO is lost and sets FDEBUG.TXOVER; a `push block`
//!   on a full RX FIFO stalls the state machine and sets FDEBUG.RXSTALL; a
//!   `pull block` on an empty one stalls it (FDEBUG.TXSTALL);
//! - every pin field (IN, OUT, SET bases, the JMP pin) indexes the block's
//!   32-GPIO window from GPIOBASE (0 or 16), wrapping within it;
//! - inputs pass a 2-flip-flop synchroniser: a state machine sees a pin's
//!   level of two cycles before;
//! - `jmp x--` tests X, then decrements it, wrapping from 0 to all ones;
//! - an OUT to PINS or PINDIRS writes all OUT_COUNT pins, zeroes above the
//!   bits shifted out; a side-set (to pins or, with SIDE_PINDIR, to
//!   directions) takes precedence over them on the same cycle, and takes
//!   effect even when its instruction stalls;
//! - one CTRL write enables state machines of a block and, through
//!   NEXT_PIO_MASK, of the next block, on the same cycle.
//!
//! The instructions are decoded by pio-core (the `pio` crates'
//! instruction types, with which the board crate also assembles its
//! programs). What the bridge does not use (optional side-set, autopush and autopull, IRQs, the RX FIFO as
//! registers, clock dividers other than 1) is refused when configured,
//! not modelled approximately.
//!
//! Time skips ahead when nothing can change: every running state machine
//! stalled on a FIFO, or in a loop of `jmp`s whose only effect is counting
//! X down, with no input changing ([`World::run_until`]).
//!
//! By part:
//!
//! - `block.rs`: a PIO block as the CPU sees it: its instruction memory,
//!   its state machines' registers and FIFOs, FDEBUG, forced instructions;
//! - `exec.rs`: the state machines' instructions, cycle by cycle, and the
//!   test of whether one is quiet (time may skip ahead);
//! - `dma.rs`: the DMA block's registers as the board code uses them, and
//!   its channels' transfers, cycle by cycle;
//! - `world.rs`: the three blocks, the GPIOs (FUNCSEL, pads, the
//!   synchroniser), what drives the pins from outside, the DMA channels
//!   from RX FIFOs to rings, and the run to a cycle.

mod block;
mod dma;
mod exec;
mod world;

pub use block::{Block, LoadError, Sm, Unsupported, WORDS};
pub use dma::{BusError, Channel, Dma, CHANNELS, RAM};
pub use world::{Func, Inputs, Outside, World, GPIOS};

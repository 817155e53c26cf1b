//! The PIO programs of the RP2350 bridge, assembled by the `pio` crate at
//! compile time, and where each is loaded.
//!
//! Each PIO block holds 32 instruction words, shared by every program
//! loaded into it (RP2350 datasheet, PIO chapter). The bridge gives each
//! program a block of its own, at address 0, so that the addresses the
//! assembler computed are the ones that run:
//!
//! | block | program | words | state machines |
//! |---|---|---|---|
//! | PIO0 | [`bus_player`] | 9 | SM0 |
//! | PIO1 | [`edge_counter`]`(true)`: POUT's rising edges with DIR | 11 | SM0 |
//! | PIO2 | [`edge_counter`]`(false)`: both edges | 21 | SM0-2 (INT*, HOLD, AUX*) |
//!
//! (Until issue 28 both counters shared PIO1: 13 + 23 words, which
//! embassy-rp's `load_program` refuses with a panic at boot.)

use pio::Program;

/// Instructions a PIO block holds.
pub const SIZE: usize = 32;

/// A program as loaded at address 0 of its block: its words, its wrap, and
/// the addresses a state machine may start at.
#[derive(Debug)]
pub struct Loaded {
    pub program: Program<SIZE>,
    pub wrap_top: u8,
    pub wrap_bottom: u8,
    /// Where to start: for the bus player, its `pull`; for an edge
    /// counter, its loop for a pin that reads high.
    pub start: u8,
    /// For an edge counter, its loop for a pin that reads low.
    pub start_low: u8,
}

impl Loaded {
    fn new(program: Program<SIZE>, start: u8, start_low: u8) -> Loaded {
        Loaded {
            wrap_top: program.wrap.source,
            wrap_bottom: program.wrap.target,
            program,
            start,
            start_low,
        }
    }

    /// The words loaded, from address 0.
    pub fn words(&self) -> &[u16] {
        &self.program.code
    }
}

/// The bus cycle player (PIO0, SM0).
///
/// Each word from the TX FIFO is one *step* ([`crate::bus::Step`]): the
/// directions of D0-D7, then the levels of D0-D7, A0, CS*, DIR (of the
/// level shifter), RD* and WR* (the 13 OUT pins, GPIO 0-12), then whether
/// to sample D0-D7 at the end of the step, then how long the step lasts:
/// `x + 7` cycles, `x + 9` with a sample ([`crate::bus::STEP_CYCLES`]).
/// A sampled byte goes to the RX FIFO. Between cycles the machine waits at
/// `pull` with the pins as the last step left them.
///
/// Its configuration is [`crate::pioregs::bus_player`]. The FIFOs are not
/// joined (the RX FIFO takes the bytes read), so the TX FIFO holds 4
/// steps: the firmware pushes a step only when the FIFO has room
/// ([`crate::board`]).
pub fn bus_player() -> Loaded {
    let p = pio::pio_asm!(
        ".wrap_target",
        "step:",
        "    pull block",
        "    out pindirs, 8",
        "    out pins, 13",
        "    out y, 1",
        "    out x, 10",
        "hold:",
        "    jmp x-- hold",
        "    jmp !y step",
        "    in pins, 8",
        "    push block",
        ".wrap",
    )
    .program;
    Loaded::new(p, 0, 0)
}

/// An edge counter on the JMP pin.
///
/// X counts down once every two cycles, on every path through the program,
/// from all ones (the firmware sets it before starting), so that
/// [`crate::timebase`] can turn a pushed count into time. A rising edge
/// pushes `bit << 31 | (X & 0x7FFF_FFFF)`:
///
/// - `rising_only` (POUT): rising edges only, `bit` being the IN pin (DIR)
///   sampled at the edge;
/// - otherwise both edges, `bit` being the level after the change.
///
/// Every `jmp x--` goes where it would go if X were not zero: its target
/// is the next instruction, or the wrap takes it there. At X = 0 a
/// `jmp x--` does not jump, and a program that fell through into its edge
/// code there would push an edge that never happened, once every 2^32
/// ticks (57.3 s at 75 MHz; until issue 28 this one did).
///
/// A `push block` stalls the counter while the RX FIFO (8 words, joined)
/// is full; the firmware sees the stall in FDEBUG.RXSTALL, reports the
/// capture lost, and restarts the counters.
pub fn edge_counter(rising_only: bool) -> Loaded {
    if rising_only {
        let p = pio::pio_asm!(
            "rise:",
            "    jmp x-- r1",
            "r1:",
            "    in pins, 1",
            "    jmp x-- r2",
            "r2:",
            "    in x, 31",
            "    jmp x-- r3",
            "r3:",
            "    push block",
            "still_high:",
            "    jmp x-- high",
            "public high:",
            "    jmp pin still_high",
            "    jmp x-- low",
            ".wrap_target",
            "public low:",
            "    jmp pin rise",
            "    jmp x-- low",
            ".wrap",
        );
        let d = p.public_defines;
        Loaded::new(p.program, d.high as u8, d.low as u8)
    } else {
        let p = pio::pio_asm!(
            "rise:",
            "    jmp x-- r1",
            "r1:",
            "    set y, 1",
            "    jmp x-- r2",
            "r2:",
            "    in y, 1",
            "    jmp x-- r3",
            "r3:",
            "    in x, 31",
            "    jmp x-- r4",
            "r4:",
            "    push block",
            "still_high:",
            "    jmp x-- high",
            "public high:",
            "    jmp pin still_high",
            "    jmp x-- fall",
            "fall:",
            "    set y, 0",
            "    jmp x-- f1",
            "f1:",
            "    in y, 1",
            "    jmp x-- f2",
            "f2:",
            "    in x, 31",
            "    jmp x-- f3",
            "f3:",
            "    push block",
            "    jmp x-- low",
            ".wrap_target",
            "public low:",
            "    jmp pin rise",
            "    jmp x-- low",
            ".wrap",
        );
        let d = p.public_defines;
        Loaded::new(p.program, d.high as u8, d.low as u8)
    }
}

/// What each PIO block is loaded with, in block order.
pub fn layout() -> [Loaded; 3] {
    [bus_player(), edge_counter(true), edge_counter(false)]
}

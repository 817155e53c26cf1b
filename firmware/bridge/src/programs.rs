//! The PIO programs of the RP2350 bridge.
//!
//! Each is assembled by the `pio` crate at compile time; the firmware loads
//! them with embassy-rp, and the tests run them in [`crate::sim`], cycle by
//! cycle, against the timing they must meet.

use pio::Program;

/// Instructions a PIO block holds.
pub const SIZE: usize = 32;

/// The bus cycle player (PIO0, one state machine).
///
/// Each word from the TX FIFO is one *step* ([`crate::bus::Step`]): the
/// directions of D0-D7, then the levels of D0-D7, A0, CS*, DIR (of the
/// level shifter), RD* and WR* (the 13 OUT pins, GPIO 0-12), then whether
/// to sample D0-D7 at the end of the step, then how long the step lasts:
/// `x + 7` cycles, `x + 9` with a sample ([`crate::bus::STEP_CYCLES`]).
/// A sampled byte goes to the RX FIFO. Between cycles the machine waits at
/// `pull` with the pins as the last step left them.
///
/// Configuration the firmware must give it (and the tests do): OUT pins
/// GPIO 0-12, IN base GPIO 0, OUT shift right, IN shift left, no autopull,
/// no autopush, TX FIFO joined (8 steps, a whole cycle, queued at once).
pub fn bus_player() -> Program<SIZE> {
    pio::pio_asm!(
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
    .program
}

/// Edge capture of one pin, the JMP pin: a rising edge pushes
/// `level << 31 | count` (with `rising_only`: `DIR << 31 | count`, DIR
/// being the IN base pin, sampled at the edge), where `count` is the low
/// 31 bits of a counter X that starts at all ones and counts down once
/// every two cycles, on every path through the program, so that
/// [`crate::timebase`] can turn it into time. With `rising_only` false a
/// falling edge pushes too (the level after the change in bit 31).
///
/// State machines of one PIO block enabled by one register write count in
/// step: their counts are one timebase.
///
/// Configuration: JMP pin = the pin, IN base = DIR (POUT capture) or the
/// pin itself, IN shift left, no autopush; the RX FIFO is drained by DMA
/// (a full FIFO would stall the counter: the firmware checks the FIFO's
/// stall flag and reports a capture overrun).
pub fn edge_capture(rising_only: bool) -> Program<SIZE> {
    if rising_only {
        pio::pio_asm!(
            "    mov x, ~null",
            ".wrap_target",
            "low:",
            "    jmp pin rise",
            "    jmp x-- low",
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
            "    jmp x-- high",
            "high:",
            "    jmp pin still_high",
            "    jmp x-- low",
            "still_high:",
            "    jmp x-- high",
            ".wrap",
        )
        .program
    } else {
        pio::pio_asm!(
            "    mov x, ~null",
            ".wrap_target",
            "low:",
            "    jmp pin rise",
            "    jmp x-- low",
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
            "    jmp x-- high",
            "high:",
            "    jmp pin still_high",
            "    jmp x-- fall",
            "still_high:",
            "    jmp x-- high",
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
            ".wrap",
        )
        .program
    }
}

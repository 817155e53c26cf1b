//! ppmc's tests of its changes to the PIO blocks (PPMC-CHANGES.md): the
//! CTRL register as the RP2350 datasheet's 11.7 describes it.

use rp2350_emu::{Config, Emulator, EmulatorBuilder};

const PIO: [u32; 3] = [0x5020_0000, 0x5030_0000, 0x5040_0000];
const CTRL: u32 = 0x000;
const RXF0: u32 = 0x020;
const FSTAT: u32 = 0x004;
const SM0_ADDR: u32 = 0x0D4;
const SM0_INSTR: u32 = 0x0D8;
/// CTRL fields (RP2350 datasheet 11.7).
const SM_RESTART: u32 = 4;
const PREV_PIO_MASK: u32 = 16;
const NEXT_PIO_MASK: u32 = 20;
const NEXTPREV_SM_ENABLE: u32 = 1 << 24;
const NEXTPREV_SM_DISABLE: u32 = 1 << 25;

/// The emulator after reset, both cores asleep: the tests drive the bus.
fn quiet() -> Emulator {
    let mut emu = EmulatorBuilder::new(Config {
        sys_clk_hz: 150_000_000,
    })
    .step_quantum(4)
    .build()
    .expect("an emulator");
    emu.reset();
    emu.core_mut(0).halt();
    emu.core_mut(1).halt();
    emu
}

/// `set x, 5`, `jmp 7`, `mov isr, x`, `push noblock` (PIO instruction
/// encodings, datasheet 11.4).
const SET_X_5: u32 = 0xE025;
const JMP_7: u32 = 0x0007;
const MOV_ISR_X: u32 = 0xA0C1;
const PUSH_NOBLOCK: u32 = 0x8000;

/// CTRL.SM_RESTART clears a state machine's shift counters, ISR, delay
/// and stalls, but "the contents of the output shift register and the X/Y
/// scratch registers are not affected", and the program counter is not
/// among what it clears (datasheet 11.7). The crate reset PC and X/Y to
/// 0, so a counter the CPU had pointed at its program and loaded with
/// its start value (`pio_sm_exec`, then a restart, as the pico-sdk's
/// `pio_sm_init` orders them) ran from address 0 with X = 0.
#[test]
fn sm_restart_keeps_the_program_counter_and_x() {
    let mut emu = quiet();
    let pio = PIO[1];
    emu.mmio_write32(pio + SM0_INSTR, SET_X_5);
    emu.mmio_write32(pio + SM0_INSTR, JMP_7);
    emu.mmio_write32(pio + CTRL, 1 << SM_RESTART);
    assert_eq!(emu.mmio_read32(pio + SM0_ADDR), 7, "PC after the restart");
    emu.mmio_write32(pio + SM0_INSTR, MOV_ISR_X);
    emu.mmio_write32(pio + SM0_INSTR, PUSH_NOBLOCK);
    assert_eq!(emu.mmio_read32(pio + FSTAT) & 1, 0, "a word was pushed");
    assert_eq!(emu.mmio_read32(pio + RXF0), 5, "X after the restart");
}

/// CTRL.NEXT_PIO_MASK with NEXTPREV_SM_ENABLE: one write to a block
/// enables its own state machines (SM_ENABLE) and those named in the
/// mask of the next block; NEXTPREV_SM_DISABLE stops them the same way
/// (datasheet 11.7). The crate applied CTRL to the written block only,
/// so the next block's state machines never started.
#[test]
fn one_ctrl_write_starts_and_stops_the_next_blocks_state_machines() {
    let mut emu = quiet();
    emu.mmio_write32(
        PIO[1] + CTRL,
        1 | 0b0111 << NEXT_PIO_MASK | NEXTPREV_SM_ENABLE,
    );
    assert_eq!(emu.mmio_read32(PIO[1] + CTRL) & 0xF, 0b0001);
    assert_eq!(emu.mmio_read32(PIO[2] + CTRL) & 0xF, 0b0111);
    assert_eq!(emu.mmio_read32(PIO[0] + CTRL) & 0xF, 0, "PIO0 untouched");
    emu.mmio_write32(PIO[1] + CTRL, 0b0111 << NEXT_PIO_MASK | NEXTPREV_SM_DISABLE);
    assert_eq!(emu.mmio_read32(PIO[1] + CTRL) & 0xF, 0);
    assert_eq!(emu.mmio_read32(PIO[2] + CTRL) & 0xF, 0);
}

/// The neighbours wrap: the next block after the last is block 0, the
/// previous one before block 0 is the last (datasheet 11.7,
/// NEXT_PIO_MASK and PREV_PIO_MASK); a CLR-alias write triggers nothing.
#[test]
fn the_neighbours_wrap_round_and_a_clr_write_triggers_nothing() {
    let mut emu = quiet();
    emu.mmio_write32(PIO[0] + CTRL, 0b1000 << PREV_PIO_MASK | NEXTPREV_SM_ENABLE);
    assert_eq!(emu.mmio_read32(PIO[2] + CTRL) & 0xF, 0b1000);
    emu.mmio_write32(
        PIO[2] + CTRL,
        0b1000 | 0b0010 << NEXT_PIO_MASK | NEXTPREV_SM_ENABLE,
    );
    assert_eq!(emu.mmio_read32(PIO[0] + CTRL) & 0xF, 0b0010);
    // CLR alias (+0x3000): clears SM_ENABLE bit 3 of PIO2, and nothing of
    // PIO0's, though the written value names it.
    emu.mmio_write32(
        PIO[2] + 0x3000 + CTRL,
        0b1000 | 0b0010 << NEXT_PIO_MASK | NEXTPREV_SM_DISABLE,
    );
    assert_eq!(emu.mmio_read32(PIO[2] + CTRL) & 0xF, 0);
    assert_eq!(emu.mmio_read32(PIO[0] + CTRL) & 0xF, 0b0010);
}

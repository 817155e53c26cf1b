//! ppmc's tests of its changes to the DMA's transfer count
//! (PPMC-CHANGES.md): TRANS_COUNT as the RP2350 datasheet's 12.6.2.2
//! describes it. A PIO RX FIFO paces the channel (DREQ_PIO0_RX0), filled
//! one word at a time by instructions the test forces into a stopped
//! state machine, so the test knows how many transfers were made.

use rp2350_emu::{Config, Emulator, EmulatorBuilder};

const DMA: u32 = 0x5000_0000;
const READ_ADDR: u32 = DMA;
const WRITE_ADDR: u32 = DMA + 0x04;
const TRANS_COUNT: u32 = DMA + 0x08;
const CTRL_TRIG: u32 = DMA + 0x0C;
const DBG_TCR: u32 = DMA + 0x804;
const PIO0_RXF0: u32 = 0x5020_0020;
const PIO0_SM0_INSTR: u32 = 0x5020_00D8;
const RING: u32 = 0x2000_1000;

/// CTRL_TRIG (datasheet 12.6.10): EN, DATA_SIZE word, INCR_WRITE, a
/// 16-byte ring on the write address, no chain (CHAIN_TO itself),
/// TREQ_SEL 4 (DREQ_PIO0_RX0), IRQ_QUIET.
const CTRL: u32 = 1 | 2 << 2 | 1 << 6 | 4 << 8 | 1 << 12 | 4 << 17 | 1 << 23;
const BUSY: u32 = 1 << 26;
const MODE_TRIGGER_SELF: u32 = 1 << 28;
const MODE_ENDLESS: u32 = 0xF << 28;

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

/// Channel 0 from PIO0's RX FIFO 0 into the ring, `count` transfers.
fn start(emu: &mut Emulator, count: u32) {
    emu.mmio_write32(READ_ADDR, PIO0_RXF0);
    emu.mmio_write32(WRITE_ADDR, RING);
    emu.mmio_write32(TRANS_COUNT, count);
    emu.mmio_write32(CTRL_TRIG, CTRL);
}

/// Pushes `value` (0-31) into PIO0 SM0's RX FIFO (`set x`, `mov isr, x`,
/// `push noblock`, forced), and lets the DMA take it.
fn push(emu: &mut Emulator, value: u32) {
    for instr in [0xE020 | value, 0xA0C1, 0x8000] {
        emu.mmio_write32(PIO0_SM0_INSTR, instr);
    }
    emu.run(16).expect("runs");
}

fn left(emu: &mut Emulator) -> u32 {
    emu.mmio_read32(TRANS_COUNT) & 0x0FFF_FFFF
}

/// MODE TRIGGER_SELF: when the count runs out the channel triggers
/// itself, RELOAD copied into the live count; MODE is not part of the
/// count. The crate counted MODE's bits as transfers (0x1000_0004), so
/// the count read back said nothing of where the ring was written.
#[test]
fn trigger_self_reloads_the_count_and_stays_busy() {
    let mut emu = quiet();
    start(&mut emu, MODE_TRIGGER_SELF | 4);
    assert_eq!(left(&mut emu), 4);
    for v in 1..=6 {
        push(&mut emu, v);
    }
    assert_eq!(left(&mut emu), 2, "6 transfers into a 4-transfer sequence");
    assert_ne!(emu.mmio_read32(CTRL_TRIG) & BUSY, 0, "still busy");
    let ring: Vec<u32> = (0..4).map(|i| emu.peek(RING + 4 * i)).collect();
    assert_eq!(ring, [5, 6, 3, 4], "the ring written round");
}

/// A write of TRANS_COUNT sets RELOAD (read at DBG_TCR) and leaves the
/// running sequence's count alone; a trigger of a busy channel is
/// ignored (datasheet 12.6.2.2, 12.6.3). The crate wrote the live count
/// too, so reprogramming a running channel moved where it said it
/// writes.
#[test]
fn a_running_channel_keeps_its_count_through_a_write_and_a_trigger() {
    let mut emu = quiet();
    start(&mut emu, MODE_TRIGGER_SELF | 4);
    push(&mut emu, 1);
    assert_eq!(left(&mut emu), 3);
    emu.mmio_write32(TRANS_COUNT, MODE_TRIGGER_SELF | 4);
    emu.mmio_write32(CTRL_TRIG, CTRL);
    assert_eq!(left(&mut emu), 3, "the live count is the running one's");
    assert_eq!(emu.mmio_read32(DBG_TCR), MODE_TRIGGER_SELF | 4);
    push(&mut emu, 2);
    assert_eq!(left(&mut emu), 2);
}

/// MODE NORMAL ends the sequence when the count runs out (BUSY low);
/// ENDLESS never decrements it.
#[test]
fn normal_stops_at_zero_and_endless_never_counts() {
    let mut emu = quiet();
    start(&mut emu, 2);
    push(&mut emu, 1);
    push(&mut emu, 2);
    assert_eq!(
        emu.mmio_read32(CTRL_TRIG) & BUSY,
        0,
        "a NORMAL sequence ends"
    );
    push(&mut emu, 3);
    assert_eq!(emu.peek(RING + 8), 0, "no transfer after the end");
    start(&mut emu, MODE_ENDLESS | 2);
    for v in 1..=5 {
        push(&mut emu, v);
    }
    assert_eq!(left(&mut emu), 2, "ENDLESS does not count");
    assert_ne!(emu.mmio_read32(CTRL_TRIG) & BUSY, 0);
}

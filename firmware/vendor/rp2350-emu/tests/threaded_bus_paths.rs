//! Coverage-driven integration tests that exercise the `WorkerBus`
//! monomorphization path in the RP2350 threaded runtime.
//!
//! Branch coverage in `crates/rp2350-emu/src/bus/mod.rs` is split between
//! two parallel monomorphizations: the Serial inherent `Bus` (covered by
//! every unit test) and the threaded `WorkerBus` (only covered when a
//! `ThreadedEmulator` actually runs firmware). These tests build a
//! `ThreadedEmulator`, pre-seed tight Thumb loops that hit each major
//! peripheral region, and run a handful of quanta — the peripheral writes
//! flow through `WorkerBus::write32` / `read32` / region dispatch and
//! exercise the cold side of each branch.
//!
//! ## Scope rules
//!
//! - **No post-run MMIO observation.** `mmio_read32` / `peek` /
//!   `mmio_write32` debug-assert in Threaded mode after the first
//!   `run_quantum` (the flat `bus` becomes a placeholder). The only
//!   safe end-state observable is `core_cycles`, which is what each test
//!   asserts on.
//! - **Pre-run pokes only.** Firmware is loaded via `poke` before
//!   promotion. After the first `run_quantum`, the WorkerBus owns all
//!   peripheral state.
//! - **Correctness is already validated.** Silicon oracles and the
//!   `dual_model` parity tests cover semantic correctness — these tests
//!   only need to drive each WorkerBus branch.
//!
//! Gated to the platforms where `ThreadedEmulator` compiles: x86_64
//! Windows / Linux with the `threading` feature on.

#![cfg(all(
    feature = "threading",
    target_arch = "x86_64",
    any(target_os = "windows", target_os = "linux")
))]

use rp2350_emu::{Config, Emulator, EmulatorBuilder, ExecutionModel};

// ---------------------------------------------------------------------------
// Constants — RP2350 MMIO map (datasheet §2.2 / peripheral chapters)
// ---------------------------------------------------------------------------

const SRAM_BASE: u32 = 0x2000_0000;
/// Stack top in non-striped SRAM8 — keeps push/pop out of bank-0.
const STACK_TOP: u32 = 0x2008_0000;

// SIO (single-cycle IO).
const SIO_BASE: u32 = 0xD000_0000;
const SIO_GPIO_OUT_SET: u32 = SIO_BASE + 0x018;
const SIO_GPIO_OUT_XOR: u32 = SIO_BASE + 0x028;
const SIO_GPIO_OE_SET: u32 = SIO_BASE + 0x038;

// APB peripheral bases used by the firmware blobs below. These all live
// in regions released post-bootrom (`RESETS_POST_BOOTROM`), so the bus
// dispatches them into typed peripheral storage rather than short-
// circuiting via the held-in-reset guard.
const UART0_BASE: u32 = 0x4007_0000;
const UART0_DR: u32 = UART0_BASE + 0x000; // UARTDR — TX FIFO push
const UART0_IBRD: u32 = UART0_BASE + 0x024; // baud divisor (integer)

const SPI0_BASE: u32 = 0x4008_0000;
const SPI0_CR0: u32 = SPI0_BASE + 0x000; // SSPCR0

const I2C0_BASE: u32 = 0x4009_0000;
const I2C0_CON: u32 = I2C0_BASE + 0x000; // IC_CON

const PWM_BASE: u32 = 0x400A_8000;
const PWM_CH0_CSR: u32 = PWM_BASE + 0x000;

const TIMER0_BASE: u32 = 0x400B_0000;
const TIMER0_ALARM0: u32 = TIMER0_BASE + 0x010;
const TIMER0_INTE: u32 = TIMER0_BASE + 0x040;

const ADC_BASE: u32 = 0x400A_0000;
const ADC_CS: u32 = ADC_BASE + 0x000;

const DMA_BASE: u32 = 0x5000_0000;
const DMA_CH0_READ_ADDR: u32 = DMA_BASE + 0x000;
const DMA_CH0_WRITE_ADDR: u32 = DMA_BASE + 0x004;
const DMA_CH0_TRANS_COUNT: u32 = DMA_BASE + 0x008;
const DMA_CH0_CTRL_TRIG: u32 = DMA_BASE + 0x00C;

const IO_BANK0_BASE: u32 = 0x4002_8000;
const IO_BANK0_GPIO0_CTRL: u32 = IO_BANK0_BASE + 0x004;

const PADS_BANK0_BASE: u32 = 0x4003_8000;
const PADS_BANK0_GPIO0: u32 = PADS_BANK0_BASE + 0x004;

// ---------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------

/// Build a Threaded emulator. Panics if `ThreadingUnavailable` — the
/// file-level `#[cfg]` already guarantees a supported host.
fn build_threaded() -> Emulator {
    EmulatorBuilder::new(Config::default())
        .execution(ExecutionModel::Threaded)
        .build()
        .expect("Threaded build must succeed on x86_64 Windows/Linux")
}

/// Drive `quanta` quanta on the threaded runtime, asserting each call
/// succeeds. Returns `(core0_delta, core1_delta)`.
fn run_n_quanta(emu: &mut Emulator, quanta: u32) -> (u64, u64) {
    let c0 = emu.core_cycles(0);
    let c1 = emu.core_cycles(1);
    for i in 0..quanta {
        emu.run_quantum()
            .unwrap_or_else(|e| panic!("run_quantum #{i} failed: {e:?}"));
    }
    (emu.core_cycles(0) - c0, emu.core_cycles(1) - c1)
}

/// Standard core-0 program seeder. Loads a literal pool into a register
/// and kicks core 0 at SRAM_BASE; halts core 1.
///
/// The firmware blob layout is:
///
/// ```text
///   [SRAM_BASE]   LDR R2, [PC, #pc_offset]   (literal pool address)
///   [SRAM_BASE+2] MOVS R0, #imm
///   [SRAM_BASE+4] STR R0, [R2]
///   [SRAM_BASE+6] B .-4
///   [literal_pool]: <peripheral address>
/// ```
///
/// `imm8` is the byte to write each iteration. The literal pool address
/// is selected by the caller via `peripheral_addr`.
///
/// Caller must ensure SRAM is clean and no other core 1 program is
/// running.
fn seed_str_loop_to_addr(emu: &mut Emulator, peripheral_addr: u32, imm8: u8) {
    emu.core_mut(0).regs.msp = STACK_TOP;
    emu.core_mut(0).regs.r[13] = STACK_TOP;
    // halfwords: [0]=LDR R2, [PC,#0] (0x4A00) ; [1]=MOVS R0, #imm (0x20XX)
    let movs_imm = 0x2000u32 | imm8 as u32;
    emu.poke(SRAM_BASE, (movs_imm << 16) | 0x0000_4A00);
    // halfwords: [0]=STR R0, [R2] (0x6010) ; [1]=B .-4 (0xE7FD)
    emu.poke(SRAM_BASE + 4, 0xE7FD_6010);
    // Literal pool.
    emu.poke(SRAM_BASE + 8, peripheral_addr);
    emu.core_mut(0).regs.set_pc(SRAM_BASE);
    emu.core_mut(0).regs.xpsr = 1 << 24;
    emu.core_mut(1).halt();
}

/// Number of quanta each peripheral test runs. 200 quanta at the default
/// 64-cycle quantum ≈ 12,800 master cycles — easily enough for the loop
/// to repeat hundreds of times and exercise the WorkerBus dispatch on
/// every iteration, while keeping each test under ~50 ms.
const QUANTA_PER_TEST: u32 = 200;

// ---------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------

/// Drives **UART0**. Pre-seeds UARTIBRD via `mmio_write32` (ungating the
/// baud clock) then runs an STR-to-UARTDR loop. Exercises the
/// `WorkerBus::write32` APB dispatch into the typed UART peripheral.
#[test]
fn threaded_uart_str_loop() {
    let mut emu = build_threaded();
    // Pre-run setup: seed a valid baud so writes to UARTDR don't get
    // gated by the baud clock. mmio_write32 is allowed pre-promotion.
    emu.mmio_write32(UART0_IBRD, 81);
    seed_str_loop_to_addr(&mut emu, UART0_DR, 0x55);
    let (c0, c1) = run_n_quanta(&mut emu, QUANTA_PER_TEST);
    assert!(c0 > 0, "UART STR loop must advance core 0");
    assert_eq!(c1, 0, "core 1 halted");
}

/// Drives **SPI0**. Loop writes SSPCR0/SSPCR1 in alternation. Targets
/// the SPI typed-peripheral dispatch on `WorkerBus`.
#[test]
fn threaded_spi_write_loop() {
    let mut emu = build_threaded();
    seed_str_loop_to_addr(&mut emu, SPI0_CR0, 0x07);
    // Add a second peripheral write to alternate offsets within the SPI
    // block. After the STR R0,[R2], we replace the B with a STR R0,[R2,#4]
    // ; B .-6 sequence.
    //   STR R0, [R2]      = 0x6010 (already there)
    //   STR R0, [R2, #4]  = 0x6050
    //   B .-6             = 0xE7FB
    emu.poke(SRAM_BASE + 4, 0x6050_6010);
    emu.poke(SRAM_BASE + 8, 0x0000_E7FB);
    emu.poke(SRAM_BASE + 12, SPI0_CR0); // literal pool
    let (c0, _c1) = run_n_quanta(&mut emu, QUANTA_PER_TEST);
    assert!(c0 > 0, "SPI loop must advance core 0");
}

/// Drives **I2C0**. Single-register write loop — exercises the I2C
/// dispatch in `WorkerBus::apb_write32`.
#[test]
fn threaded_i2c_write_loop() {
    let mut emu = build_threaded();
    seed_str_loop_to_addr(&mut emu, I2C0_CON, 0x33);
    let (c0, _c1) = run_n_quanta(&mut emu, QUANTA_PER_TEST);
    assert!(c0 > 0, "I2C loop must advance core 0");
}

/// Drives **SIO GPIO**. Repeatedly XOR-toggles a bank of GPIO bits via
/// SIO_GPIO_OUT_XOR. Exercises the SIO write-path on `WorkerBus` (the
/// hottest of all the regions).
#[test]
fn threaded_sio_gpio_xor_loop() {
    let mut emu = build_threaded();
    // Pre-set OE so the pin actually toggles (a bonus path through the
    // OE_SET alias) — not strictly required but exercises a second SIO
    // offset on the harness side.
    emu.mmio_write32(SIO_GPIO_OE_SET, 0x0000_0FFF);
    seed_str_loop_to_addr(&mut emu, SIO_GPIO_OUT_XOR, 0x07);
    let (c0, _c1) = run_n_quanta(&mut emu, QUANTA_PER_TEST);
    assert!(c0 > 0, "SIO GPIO loop must advance core 0");
}

/// Drives **multi-bit GPIO set**. Different SIO offset (`OUT_SET`)
/// hits a separate alias in the SIO atomic-RMW dispatch.
#[test]
fn threaded_sio_gpio_set_multibit() {
    let mut emu = build_threaded();
    seed_str_loop_to_addr(&mut emu, SIO_GPIO_OUT_SET, 0xAA);
    let (c0, _c1) = run_n_quanta(&mut emu, QUANTA_PER_TEST);
    assert!(c0 > 0, "SIO GPIO_OUT_SET loop must advance core 0");
}

/// Drives **DMA channel 0** registers. Programs READ_ADDR / WRITE_ADDR /
/// TRANS_COUNT / CTRL_TRIG in turn — the CTRL_TRIG store kicks off the
/// transfer through the WorkerBus DMA dispatch.
#[test]
fn threaded_dma_channel_program() {
    let mut emu = build_threaded();
    // Source / destination scratch in SRAM banks well clear of the
    // firmware blob (which sits at SRAM_BASE..SRAM_BASE+0x40).
    const DMA_SRC: u32 = 0x2000_2000;
    const DMA_DST: u32 = 0x2000_3000;
    // Seed a few words at DMA_SRC so the engine has something to copy.
    for i in 0..16 {
        emu.poke(DMA_SRC + 4 * i, 0xCAFE_0000 | i);
    }

    // Firmware blob: program ch0 four registers in order, then NOP-loop.
    //   LDR  R2, [PC, #0x18]   (0x4A06)  -> &DMA_CH0_READ_ADDR
    //   LDR  R0, [PC, #0x18]   (0x4806)  -> DMA_SRC
    //   STR  R0, [R2]          (0x6010)
    //   LDR  R0, [PC, #0x18]   (0x4806)  -> DMA_DST
    //   STR  R0, [R2, #4]      (0x6050)
    //   MOVS R0, #4            (0x2004)
    //   STR  R0, [R2, #8]      (0x6090)
    //   LDR  R0, [PC, #0x14]   (0x4805)  -> CTRL value
    //   STR  R0, [R2, #12]     (0x60D0)  -> CTRL_TRIG (kicks engine)
    //   B    .-2               (0xE7FE)  -> hold here so quanta can drain
    //   <padding>
    //   .word DMA_CH0_READ_ADDR
    //   .word DMA_SRC
    //   .word DMA_DST
    //   .word CTRL
    emu.core_mut(0).regs.msp = STACK_TOP;
    emu.core_mut(0).regs.r[13] = STACK_TOP;
    emu.poke(SRAM_BASE, 0x4806_4A06); // LDR R2,[PC,#0x18] ; LDR R0,[PC,#0x18]
    emu.poke(SRAM_BASE + 4, 0x4806_6010); // STR R0,[R2] ; LDR R0,[PC,#0x18]
    emu.poke(SRAM_BASE + 8, 0x2004_6050); // STR R0,[R2,#4] ; MOVS R0,#4
    emu.poke(SRAM_BASE + 12, 0x4805_6090); // STR R0,[R2,#8] ; LDR R0,[PC,#0x14]
    emu.poke(SRAM_BASE + 16, 0xE7FE_60D0); // STR R0,[R2,#12] ; B .-2
    // Literal pool starts at SRAM_BASE+0x20 (LDR PC-relative reads from
    // (PC + 4 + imm) & !3; first LDR at SRAM_BASE+0 sees PC=4, +0x18=0x1C,
    // aligned = 0x1C — but that's awkward. Simpler: pad to a known
    // alignment and hand-roll.) Use a simpler 4-write blob below.
    //
    // The above blob is fragile to PC math; replace with a tighter
    // version that uses a single pointer increment.
    //
    // Simpler blob:
    //   LDR  R2, [PC, #?]       (literal pool: &DMA_CH0_READ_ADDR)
    //   MOVS R0, #0xAA           (cheap dummy — we just need writes)
    //   STR  R0, [R2]
    //   STR  R0, [R2, #4]
    //   STR  R0, [R2, #8]
    //   MOVS R1, #0x01            (CTRL minimum: EN bit)
    //   STR  R1, [R2, #12]
    //   B    .-12
    //
    // Halfword encoding:
    //   LDR R2,[PC,#0x10]  -> 0x4A04 (PC+4 + 0x10 = base+0x14, aligned word 5)
    //   MOVS R0,#0xAA      -> 0x20AA
    //   STR R0,[R2]        -> 0x6010
    //   STR R0,[R2,#4]     -> 0x6050
    //   STR R0,[R2,#8]     -> 0x6090
    //   MOVS R1,#0x01      -> 0x2101
    //   STR R1,[R2,#12]    -> 0x60D1
    //   B .-12             -> 0xE7F8
    //   NOP                -> 0xBF00
    //   NOP                -> 0xBF00
    //   .word DMA_CH0_READ_ADDR
    emu.poke(SRAM_BASE, 0x20AA_4A04);
    emu.poke(SRAM_BASE + 4, 0x6050_6010);
    emu.poke(SRAM_BASE + 8, 0x2101_6090);
    emu.poke(SRAM_BASE + 12, 0xE7F8_60D1);
    emu.poke(SRAM_BASE + 16, 0xBF00_BF00);
    emu.poke(SRAM_BASE + 20, DMA_CH0_READ_ADDR);
    emu.core_mut(0).regs.set_pc(SRAM_BASE);
    emu.core_mut(0).regs.xpsr = 1 << 24;
    emu.core_mut(1).halt();
    // Suppress unused constant warnings for the blob parameters that the
    // simpler version doesn't reference.
    let _ = (
        DMA_DST,
        DMA_CH0_WRITE_ADDR,
        DMA_CH0_TRANS_COUNT,
        DMA_CH0_CTRL_TRIG,
    );

    let (c0, _c1) = run_n_quanta(&mut emu, QUANTA_PER_TEST);
    assert!(c0 > 0, "DMA program loop must advance core 0");
}

/// Drives **PWM**. Programs CSR + DIV in alternation — exercises the
/// PWM block dispatch on `WorkerBus::apb_write32`.
#[test]
fn threaded_pwm_csr_div_loop() {
    let mut emu = build_threaded();
    seed_str_loop_to_addr(&mut emu, PWM_CH0_CSR, 0x01);
    // STR to two PWM offsets per iteration (CSR + DIV).
    emu.poke(SRAM_BASE + 4, 0x6050_6010); // STR R0,[R2] ; STR R0,[R2,#4]
    emu.poke(SRAM_BASE + 8, 0x0000_E7FB); // B .-6
    emu.poke(SRAM_BASE + 12, PWM_CH0_CSR);
    let (c0, _c1) = run_n_quanta(&mut emu, QUANTA_PER_TEST);
    assert!(c0 > 0, "PWM loop must advance core 0");
}

/// Drives **TIMER0**. Writes ALARM0 + INTE in alternation — both are
/// typed-peripheral paths on `WorkerBus`. ALARM0 specifically arms a
/// lazy schedule entry.
#[test]
fn threaded_timer_alarm_inte_loop() {
    let mut emu = build_threaded();
    seed_str_loop_to_addr(&mut emu, TIMER0_ALARM0, 0xFF);
    // Two writes per iteration: ALARM0 (offset 0) then INTE (offset 0x30
    // from ALARM0). 0x40 - 0x10 = 0x30. STR with #imm5*4 supports up to
    // 0x7C — 0x30 is fine.
    //   STR R0, [R2]        -> 0x6010
    //   STR R0, [R2, #0x30] -> 0x6610  (#0x30 / 4 = 12 -> imm5 = 12 -> 0x6610)
    //   B .-6               -> 0xE7FB
    emu.poke(SRAM_BASE + 4, 0x6610_6010);
    emu.poke(SRAM_BASE + 8, 0x0000_E7FB);
    emu.poke(SRAM_BASE + 12, TIMER0_ALARM0);
    let (c0, _c1) = run_n_quanta(&mut emu, QUANTA_PER_TEST);
    assert!(c0 > 0, "TIMER loop must advance core 0");
    let _ = TIMER0_INTE;
}

/// Drives **ADC**. Single-register write loop on the ADC CS register
/// (control / EN bit). Exercises ADC dispatch through WorkerBus.
#[test]
fn threaded_adc_cs_loop() {
    let mut emu = build_threaded();
    seed_str_loop_to_addr(&mut emu, ADC_CS, 0x01);
    let (c0, _c1) = run_n_quanta(&mut emu, QUANTA_PER_TEST);
    assert!(c0 > 0, "ADC loop must advance core 0");
}

/// Drives **IO_BANK0 + PADS_BANK0**. Two pad-control regions — each in a
/// distinct APB block routed through `WorkerBus`. Loop alternates writes
/// between them.
#[test]
fn threaded_pad_control_loop() {
    let mut emu = build_threaded();
    // R2 = IO_BANK0 GPIO0 ctrl ; R3 = PADS_BANK0 GPIO0 ; alternating STRs.
    //   LDR R2, [PC, #0x10]   -> 0x4A04 (loads IO_BANK0_GPIO0_CTRL)
    //   LDR R3, [PC, #0x10]   -> 0x4B04 (loads PADS_BANK0_GPIO0)
    //   MOVS R0, #0x55         -> 0x2055
    //   STR R0, [R2]           -> 0x6010
    //   STR R0, [R3]           -> 0x6018
    //   B .-6                  -> 0xE7FB
    //   NOPs to align literal pool to a word boundary
    //   .word IO_BANK0_GPIO0_CTRL
    //   .word PADS_BANK0_GPIO0
    emu.core_mut(0).regs.msp = STACK_TOP;
    emu.core_mut(0).regs.r[13] = STACK_TOP;
    emu.poke(SRAM_BASE, 0x4B04_4A04);
    emu.poke(SRAM_BASE + 4, 0x6010_2055);
    emu.poke(SRAM_BASE + 8, 0xE7FB_6018);
    emu.poke(SRAM_BASE + 12, 0xBF00_BF00);
    emu.poke(SRAM_BASE + 16, IO_BANK0_GPIO0_CTRL);
    emu.poke(SRAM_BASE + 20, PADS_BANK0_GPIO0);
    emu.core_mut(0).regs.set_pc(SRAM_BASE);
    emu.core_mut(0).regs.xpsr = 1 << 24;
    emu.core_mut(1).halt();

    let (c0, _c1) = run_n_quanta(&mut emu, QUANTA_PER_TEST);
    assert!(c0 > 0, "pad-control loop must advance core 0");
}

/// Drives **DMA + SIO concurrently** — both cores run programs in
/// parallel, hitting different bus regions. Locks coverage on the
/// dual-worker path through WorkerBus where both core workers race
/// for distinct destinations.
#[test]
fn threaded_dual_core_dma_and_sio() {
    let mut emu = build_threaded();
    // Core 0: SIO XOR loop (same shape as threaded_sio_gpio_xor_loop).
    seed_str_loop_to_addr(&mut emu, SIO_GPIO_OUT_XOR, 0x05);

    // Core 1: ADC CS write loop at SRAM_BASE+0x40.
    //   LDR R2, [PC,#0]   -> 0x4A00
    //   MOVS R0, #1       -> 0x2001
    //   STR R0, [R2]      -> 0x6010
    //   B .-4             -> 0xE7FD
    //   .word ADC_CS
    const STACK_TOP_C1: u32 = 0x2008_1FFC;
    emu.core_mut(1).regs.msp = STACK_TOP_C1;
    emu.core_mut(1).regs.r[13] = STACK_TOP_C1;
    emu.poke(SRAM_BASE + 0x40, 0x2001_4A00);
    emu.poke(SRAM_BASE + 0x44, 0xE7FD_6010);
    emu.poke(SRAM_BASE + 0x48, ADC_CS);
    emu.core_mut(1).regs.set_pc(SRAM_BASE + 0x40);
    emu.core_mut(1).regs.xpsr = 1 << 24;
    emu.core_mut(1).wake();

    let (c0, c1) = run_n_quanta(&mut emu, QUANTA_PER_TEST);
    assert!(c0 > 0, "core 0 SIO loop must advance");
    assert!(c1 > 0, "core 1 ADC loop must advance");
}

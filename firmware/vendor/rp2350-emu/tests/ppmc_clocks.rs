//! ppmc's tests of its changes to the tick generators and the watchdog
//! (PPMC-CHANGES.md).

use rp2350_emu::{Config, Emulator, EmulatorBuilder};

const TICKS: u32 = 0x4010_8000;
const TIMER0_TIMERAWL: u32 = 0x400B_0028;
const WATCHDOG: u32 = 0x400D_8000;

/// The emulator as the bootrom leaves it (clk_sys 150 MHz, clk_ref 12 MHz
/// from the crystal), both cores asleep.
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

/// Starts the tick generator at `domain` (TIMER0 0x18, WATCHDOG 0x30) with
/// CYCLES 12: one tick per microsecond from a 12 MHz clk_ref, as
/// embassy-rp and the pico-sdk set it.
fn start_ticks(emu: &mut Emulator, domain: u32) {
    emu.mmio_write32(TICKS + domain + 4, 12);
    emu.mmio_write32(TICKS + domain, 1);
}

/// RP2350 datasheet 8.5: a tick generator counts CYCLES cycles of
/// clk_ref per tick. Before the change it counted clk_sys, so TIMER0 ran
/// 12.5 times fast at 150 MHz (12,500 "microseconds" in one).
#[test]
fn a_millisecond_of_clk_sys_is_a_thousand_timer_microseconds() {
    let mut emu = quiet();
    start_ticks(&mut emu, 0x18);
    let before = emu.mmio_read32(TIMER0_TIMERAWL);
    emu.run(150_000).expect("runs");
    let us = emu.mmio_read32(TIMER0_TIMERAWL).wrapping_sub(before);
    assert!((999..=1_001).contains(&us), "{us} us in 1 ms");
}

/// RP2350 datasheet 12.9.2: the watchdog's counter decrements once per
/// tick of TICKS.WATCHDOG. Before the change it decremented once per
/// quantum of the emulator, and a 1 ms timeout ran out in 4,000 cycles.
#[test]
fn a_one_millisecond_watchdog_fires_after_one_millisecond() {
    let mut emu = quiet();
    start_ticks(&mut emu, 0x30);
    emu.mmio_write32(WATCHDOG + 4, 1_000); // LOAD: 1,000 ticks
    emu.mmio_write32(WATCHDOG, 1 << 30); // CTRL: ENABLE, no PAUSE_*
    emu.run(140_000).expect("runs"); // 933 us
    assert!(!emu.bus.watchdog_reset_requested(), "fired before its time");
    emu.run(10_000).expect("runs"); // 1,000 us
    emu.run(1_000).expect("runs");
    assert!(emu.bus.watchdog_reset_requested(), "never fired");
}

/// DDI0553 B11.3 (Wait For Event): an interrupt that would be taken wakes
/// a core from WFE. Before the change only SEV's event did, and embassy's
/// executor, asleep in WFE for its timer's alarm, never woke.
#[test]
fn a_timer_interrupt_wakes_a_core_asleep_in_wfe() {
    let mut emu = quiet();
    // Core 0: WFE. TIMER0's alarm 0 (IRQ 0) enabled in
    // the NVIC and the timer; the alarm 100 us ahead.
    let code: Vec<u8> = [
        0xBF20u16, // wfe
        0xE7FE,    // b .
    ]
    .iter()
    .flat_map(|h| h.to_le_bytes())
    .collect();
    emu.load_image(0x2000_0000, &code);
    emu.core_mut(0).wake();
    emu.core_mut(0).regs.set_pc(0x2000_0000);
    emu.mmio_write32(0xE000_E100, 1); // NVIC_ISER0: IRQ 0
    start_ticks(&mut emu, 0x18);
    emu.mmio_write32(0x400B_0040, 1); // TIMER0 INTE: alarm 0
    let now = emu.mmio_read32(TIMER0_TIMERAWL);
    emu.mmio_write32(0x400B_0010, now + 100); // ALARM0
    emu.run(7_500).expect("runs"); // 50 us: still asleep
    assert!(emu.core(0).is_wfe_waiting(), "not asleep before the alarm");
    emu.run(15_000).expect("runs"); // 150 us
    assert!(
        !emu.core(0).is_wfe_waiting(),
        "still asleep in WFE after the alarm"
    );
}

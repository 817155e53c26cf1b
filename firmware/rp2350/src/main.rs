//! The bus bridge firmware for an RP2350B board (the Pimoroni PGA2350;
//! docs/bridge-hardware.md has the board, the pin map and the wiring).
//!
//! - USB CDC ACM to the host; the bridge protocol through `BridgeEngine`
//!   from `ppmc-core`, the same code `ppmc bridge-sim` and the QEMU board
//!   run.
//! - Bus cycles played by a PIO state machine from timed steps
//!   (`ppmc_bridge_fw::bus`), inputs to the chip on GPIO outputs.
//! - POUT (with DIR), INT*, HOLD and AUX* stamped by PIO edge counters to
//!   two system clock cycles (13.3 ns at 150 MHz: `timer_hz` 75 MHz);
//!   S1..S5, AUXO0..3 and DIR sampled by the CPU between ops.
//! - Straps: CSEL and VSEL read from their nets at boot; SysClk and an
//!   external clock given at build time (`PPMC_SYSCLK_HZ`,
//!   `PPMC_EXT_CLOCK_HZ`), since the bridge cannot see the chip's crystal.
//!
//! What has run where: firmware/README.md.

#![no_std]
#![no_main]

extern crate alloc;

mod board;
mod clock;

use board::{BoardBus, Machines, Sampled, Wiring};
use core::mem::MaybeUninit;
use embassy_executor::Spawner;
use embassy_futures::join::join;
use embassy_futures::select::{select, Either};
use embassy_rp::bind_interrupts;
use embassy_rp::block::ImageDef;
use embassy_rp::gpio::{Input, Level, Output, Pull};
use embassy_rp::peripherals::{PIO0, PIO1, USB};
use embassy_rp::pio::{self, FifoJoin, Pio, PioBatch, ShiftConfig, ShiftDirection};
use embassy_rp::usb::{Driver, InterruptHandler as UsbIrq};
use embassy_time::Timer as Delay;
use embassy_usb::class::cdc_acm::{CdcAcmClass, State};
use embedded_alloc::LlffHeap as Heap;
use ppmc_bridge_fw::bus::BusTiming;
use ppmc_bridge_fw::programs;
use ppmc_core::bridge::engine::BridgeEngine;
use ppmc_core::protocol::Straps;
use static_cell::StaticCell;

#[link_section = ".start_block"]
#[used]
pub static IMAGE_DEF: ImageDef = ImageDef::secure_exe();

bind_interrupts!(struct Irqs {
    USBCTRL_IRQ => UsbIrq<USB>;
    PIO0_IRQ_0 => pio::InterruptHandler<PIO0>;
    PIO1_IRQ_0 => pio::InterruptHandler<PIO1>;
});

#[global_allocator]
static HEAP: Heap = Heap::empty();
const HEAP_SIZE: usize = 256 * 1024;

/// The system clock embassy-rp sets up by default.
const SYSCLK_HZ: u32 = 150_000_000;

/// Pulse runs plus pin changes the capture holds between chip resets, in
/// the heap (about 40 bytes each); the suite's busiest scenario needs 367.
const CAPTURE_RECORDS: u32 = 4096;

/// The loop-back test signal's rate: 10 us between rising edges.
const SELF_TEST_HZ: u32 = 100_000;

const FIRMWARE: &str = concat!(
    "ppmc-bridge-rp2350 ",
    env!("CARGO_PKG_VERSION"),
    " (PGA2350, PIO capture)"
);
const FIRMWARE_DEFAULT_TIMING: &str = concat!(
    "ppmc-bridge-rp2350 ",
    env!("CARGO_PKG_VERSION"),
    " (PGA2350, PIO capture; the built bus timing does not fit a step, defaults used)"
);

/// A decimal number given at build time, or `default`.
const fn build_number(v: Option<&str>, default: u32) -> u32 {
    let Some(s) = v else { return default };
    let b = s.as_bytes();
    let mut i = 0;
    let mut n: u32 = 0;
    while i < b.len() {
        assert!(b[i].is_ascii_digit(), "a build-time strap is not a number");
        n = n * 10 + (b[i] - b'0') as u32;
        i += 1;
    }
    n
}

const CHIP_SYSCLK_HZ: u32 = build_number(option_env!("PPMC_SYSCLK_HZ"), 16_000_000);
const EXT_CLOCK_HZ: u32 = build_number(option_env!("PPMC_EXT_CLOCK_HZ"), 0);

/// The bus timing, from the build's environment where given (in ns).
const BUS_TIMING: BusTiming = BusTiming {
    setup_ns: build_number(
        option_env!("PPMC_BUS_SETUP_NS"),
        BusTiming::DEFAULT.setup_ns,
    ),
    strobe_ns: build_number(
        option_env!("PPMC_BUS_STROBE_NS"),
        BusTiming::DEFAULT.strobe_ns,
    ),
    hold_ns: build_number(option_env!("PPMC_BUS_HOLD_NS"), BusTiming::DEFAULT.hold_ns),
    recovery_ns: build_number(
        option_env!("PPMC_BUS_RECOVERY_NS"),
        BusTiming::DEFAULT.recovery_ns,
    ),
};

#[embassy_executor::main]
async fn main(_spawner: Spawner) {
    {
        static HEAP_MEM: StaticCell<[MaybeUninit<u8>; HEAP_SIZE]> = StaticCell::new();
        let mem = HEAP_MEM.init([MaybeUninit::uninit(); HEAP_SIZE]);
        // SAFETY: once, before anything allocates, with memory only the
        // heap owns.
        unsafe { HEAP.init(mem.as_mut_ptr() as usize, HEAP_SIZE) }
    }
    let p = embassy_rp::init(Default::default());
    let mut core = cortex_m::Peripherals::take().expect("taken once");
    let clock = clock::Clock::start(&mut core.DCB, &mut core.DWT, SYSCLK_HZ);

    // The straps: CSEL and VSEL sensed on their nets (open reads high).
    let csel = Input::new(p.PIN_46, Pull::Up);
    let vsel = Input::new(p.PIN_47, Pull::Up);
    let straps = Straps {
        sysclk_hz: CHIP_SYSCLK_HZ,
        csel_high: csel.is_high(),
        vsel_high: vsel.is_high(),
        ext_clock_hz: (EXT_CLOCK_HZ != 0).then_some(EXT_CLOCK_HZ),
    };

    // The bus: PIO0 plays steps on GPIO 0-12 (D0-D7, A0, CS*, DIR, RD*, WR*).
    let Pio {
        common: mut pio0,
        sm0: mut bus_sm,
        ..
    } = Pio::new(p.PIO0, Irqs);
    let player = pio0.load_program(&programs::bus_player());
    let bus_pins = [
        pio0.make_pio_pin(p.PIN_0),
        pio0.make_pio_pin(p.PIN_1),
        pio0.make_pio_pin(p.PIN_2),
        pio0.make_pio_pin(p.PIN_3),
        pio0.make_pio_pin(p.PIN_4),
        pio0.make_pio_pin(p.PIN_5),
        pio0.make_pio_pin(p.PIN_6),
        pio0.make_pio_pin(p.PIN_7),
        pio0.make_pio_pin(p.PIN_8),
        pio0.make_pio_pin(p.PIN_9),
        pio0.make_pio_pin(p.PIN_10),
        pio0.make_pio_pin(p.PIN_11),
        pio0.make_pio_pin(p.PIN_12),
    ];
    let all: [&pio::Pin<'_, PIO0>; 13] = core::array::from_fn(|i| &bus_pins[i]);
    let mut cfg = pio::Config::default();
    cfg.use_program(&player, &[]);
    cfg.set_out_pins(&all);
    cfg.set_in_pins(&all[..8]);
    cfg.shift_out = ShiftConfig {
        threshold: 32,
        direction: ShiftDirection::Right,
        auto_fill: false,
    };
    cfg.shift_in = ShiftConfig {
        threshold: 32,
        direction: ShiftDirection::Left,
        auto_fill: false,
    };
    cfg.fifo_join = FifoJoin::Duplex;
    bus_sm.set_config(&cfg);
    bus_sm.set_pin_dirs(pio::Direction::Out, &all);
    // Idle: CS*, DIR (towards the chip), RD*, WR* high.
    bus_sm.set_pins(Level::High, &all[9..]);
    bus_sm.set_enable(true);

    // The edge counters: PIO1, GPIO 32-36 (POUT, DIR, INT*, HOLD, AUX*).
    let Pio {
        common: mut pio1,
        sm0: mut pout_sm,
        sm1: mut int_sm,
        sm2: mut hold_sm,
        sm3: mut aux_sm,
        ..
    } = Pio::new(p.PIO1, Irqs);
    let rising = pio1.load_program(&programs::edge_capture(true));
    let both = pio1.load_program(&programs::edge_capture(false));
    let pout = pio1.make_pio_pin(p.PIN_32);
    let dir = pio1.make_pio_pin(p.PIN_33);
    let int = pio1.make_pio_pin(p.PIN_34);
    let hold = pio1.make_pio_pin(p.PIN_35);
    let aux = pio1.make_pio_pin(p.PIN_36);
    let edge_config = |program, jmp: &pio::Pin<'static, PIO1>, input: &pio::Pin<'static, PIO1>| {
        let mut c = pio::Config::default();
        c.use_program(program, &[]);
        c.set_jmp_pin(jmp);
        c.set_in_pins(&[input]);
        c.shift_in = ShiftConfig {
            threshold: 32,
            direction: ShiftDirection::Left,
            auto_fill: false,
        };
        c.fifo_join = FifoJoin::RxOnly;
        c
    };
    pout_sm.set_config(&edge_config(&rising, &pout, &dir));
    int_sm.set_config(&edge_config(&both, &int, &int));
    hold_sm.set_config(&edge_config(&both, &hold, &hold));
    aux_sm.set_config(&edge_config(&both, &aux, &aux));
    let mut batch = PioBatch::new();
    batch.set_enable(&mut pout_sm, true);
    batch.set_enable(&mut int_sm, true);
    batch.set_enable(&mut hold_sm, true);
    batch.set_enable(&mut aux_sm, true);
    // One register write starts all four counters: one timebase.
    let started = clock.ticks();
    batch.execute();

    // The chip's inputs (active low, released: high) and RESET*.
    let inputs = [
        Output::new(p.PIN_13, Level::High),
        Output::new(p.PIN_14, Level::High),
        Output::new(p.PIN_15, Level::High),
        Output::new(p.PIN_16, Level::High),
        Output::new(p.PIN_17, Level::High),
        Output::new(p.PIN_18, Level::High),
        Output::new(p.PIN_19, Level::High),
        Output::new(p.PIN_20, Level::High),
        Output::new(p.PIN_21, Level::High),
        Output::new(p.PIN_22, Level::High),
    ];
    let reset = Output::new(p.PIN_23, Level::High);
    // The capture's loop-back test signal: 100 kHz on GPIO 25, always on.
    // A jumper from GPIO 25 to POUT's capture input (with the chip's POUT
    // off the net) lets the host check the capture against a known rate
    // (docs/bridge-hardware.md, bring-up).
    let mut test_clock = embassy_rp::pwm::Config::default();
    test_clock.top = (SYSCLK_HZ / SELF_TEST_HZ - 1) as u16;
    test_clock.compare_b = (SYSCLK_HZ / SELF_TEST_HZ / 2) as u16;
    let _test_clock = embassy_rp::pwm::Pwm::new_output_b(p.PWM_SLICE4, p.PIN_25, test_clock);
    let sampled = Sampled {
        s: [
            Input::new(p.PIN_37, Pull::None),
            Input::new(p.PIN_38, Pull::None),
            Input::new(p.PIN_39, Pull::None),
            Input::new(p.PIN_40, Pull::None),
            Input::new(p.PIN_41, Pull::None),
        ],
        auxo: [
            Input::new(p.PIN_42, Pull::None),
            Input::new(p.PIN_43, Pull::None),
            Input::new(p.PIN_44, Pull::None),
            Input::new(p.PIN_45, Pull::None),
        ],
    };
    let machines = Machines {
        bus: bus_sm,
        pout: pout_sm,
        int: int_sm,
        hold: hold_sm,
        aux: aux_sm,
        started,
    };
    // A step holds 6.9 us at most: a longer time given at build cannot be
    // played, and the board says so in its name instead of starting.
    let (timing, firmware) = if BUS_TIMING.fits(SYSCLK_HZ) {
        (BUS_TIMING, FIRMWARE)
    } else {
        (BusTiming::DEFAULT, FIRMWARE_DEFAULT_TIMING)
    };
    let wiring = Wiring {
        sm: machines,
        inputs,
        reset,
        sampled,
    };
    let board = BoardBus::new(clock, SYSCLK_HZ, timing, straps, wiring);
    let timer = board.timer();
    let session = embassy_rp::clocks::RoscRng.next_u32();
    let mut engine = BridgeEngine::new(board, session, false, firmware)
        .with_timer(timer)
        .with_capture_capacity(CAPTURE_RECORDS);

    // USB CDC ACM.
    let driver = Driver::new(p.USB, Irqs);
    let mut config = embassy_usb::Config::new(0x1209, 0x0001);
    config.manufacturer = Some("ppmc");
    config.product = Some("PPMC-104BFP bus bridge");
    config.serial_number = None;
    config.max_power = 100;
    config.max_packet_size_0 = 64;
    static CONFIG_DESC: StaticCell<[u8; 256]> = StaticCell::new();
    static BOS_DESC: StaticCell<[u8; 256]> = StaticCell::new();
    static CONTROL_BUF: StaticCell<[u8; 64]> = StaticCell::new();
    static STATE: StaticCell<State> = StaticCell::new();
    let mut builder = embassy_usb::Builder::new(
        driver,
        config,
        CONFIG_DESC.init([0; 256]),
        BOS_DESC.init([0; 256]),
        &mut [],
        CONTROL_BUF.init([0; 64]),
    );
    let mut class = CdcAcmClass::new(&mut builder, STATE.init(State::new()), 64);
    let mut usb = builder.build();

    let serve = async {
        let mut buf = [0u8; 64];
        loop {
            class.wait_connection().await;
            'connected: loop {
                // Between requests the capture keeps draining.
                match select(class.read_packet(&mut buf), Delay::after_micros(50)).await {
                    Either::First(Ok(n)) => {
                        let reply = engine.on_bytes(&buf[..n]);
                        for chunk in reply.chunks(64) {
                            if class.write_packet(chunk).await.is_err() {
                                break 'connected;
                            }
                            engine.bus_mut().poll();
                        }
                        if !reply.is_empty() && reply.len().is_multiple_of(64) {
                            // A full last packet: end the transfer.
                            let _ = class.write_packet(&[]).await;
                        }
                    }
                    Either::First(Err(_)) => break 'connected,
                    Either::Second(()) => engine.bus_mut().poll(),
                }
            }
        }
    };
    join(usb.run(), serve).await;
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // The host sees the bridge go silent, and its health check fails.
    cortex_m::interrupt::disable();
    loop {
        cortex_m::asm::wfi();
    }
}

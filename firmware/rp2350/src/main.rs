//! The bus bridge firmware for an RP2350B board (the Pimoroni PGA2350;
//! docs/bridge-hardware.md has the board, the pin map and the wiring).
//!
//! - USB CDC ACM to the host; the bridge protocol through `BridgeEngine`
//!   from `ppmc-core`, the same code `ppmc bridge-sim` and the QEMU board
//!   run.
//! - Bus cycles played by a PIO state machine from timed steps
//!   (`ppmc_bridge_fw::bus_cycle`), inputs to the chip on GPIO outputs.
//! - POUT (with DIR) stamped by a PIO edge counter on PIO1, INT*, HOLD and
//!   AUX* by three on PIO2, all four started on one cycle, to two system
//!   clock cycles (13.3 ns at 150 MHz: `timer_hz` 75 MHz); S1..S5,
//!   AUXO0..3 and DIR sampled by the CPU between ops.
//! - The board code is `ppmc_bridge_fw::board`, over the hardware layer in
//!   `hw.rs`: the same code the board twin runs (`firmware/run-twin`). It
//!   runs with the protocol engine on core 1, so that its long ops (a
//!   delay, a wait for a status or for pulses, seconds long) never keep
//!   core 0's USB stack from answering the host; bytes cross between the
//!   cores through two pipes. A watchdog restarts the bridge if core 1's
//!   loop stops.
//! - Straps: CSEL and VSEL read from their nets at boot; SysClk and an
//!   external clock given at build time (`PPMC_SYSCLK_HZ`,
//!   `PPMC_EXT_CLOCK_HZ`), since the bridge cannot see the chip's crystal.
//!
//! - A debug log over RTT (defmt): boot, the last panic, USB connections,
//!   capture overruns and hardware faults, read with a debug probe
//!   (`probe-rs attach`, firmware/README.md). Nothing is logged inside an
//!   op: a log line costs a few microseconds with interrupts off.
//!
//! What has run where: firmware/README.md.

#![no_std]
#![no_main]

extern crate alloc;

mod hw;

use core::mem::MaybeUninit;
use defmt_rtt as _;
use embassy_executor::Spawner;
use embassy_futures::join::join3;
use embassy_rp::bind_interrupts;
use embassy_rp::block::ImageDef;
use embassy_rp::gpio::{Input, Level, Output, Pull};
use embassy_rp::multicore::{spawn_core1, Stack};
use embassy_rp::peripherals::{PIO0, PIO1, PIO2, USB};
use embassy_rp::pio::{self, Pio};
use embassy_rp::usb::{Driver, InterruptHandler as UsbIrq};
use embassy_rp::watchdog::Watchdog;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::pipe::Pipe;
use embassy_time::Timer as Delay;
use embassy_time::{with_timeout, Duration};
use embassy_usb::class::cdc_acm::{CdcAcmClass, State};
use embedded_alloc::LlffHeap as Heap;
use ppmc_bridge_fw::board::Board;
use ppmc_bridge_fw::bus_cycle::BusTiming;
use ppmc_bridge_fw::restart;
use ppmc_bridge_fw::{limits, pins, pioregs, programs, usb};
use ppmc_core::bridge::abort::{AbortLine, AbortWatch};
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
    PIO2_IRQ_0 => pio::InterruptHandler<PIO2>;
});

/// Bytes from the host to the engine on core 1, and its replies back.
static FROM_HOST: Pipe<CriticalSectionRawMutex, 512> = Pipe::new();
static TO_HOST: Pipe<CriticalSectionRawMutex, 2048> = Pipe::new();

/// How long the host may leave a reply packet unread before the bridge
/// takes it as gone (and waits for the next connection).
const WRITE_DEADLINE: Duration = Duration::from_millis(500);

/// Core 1's stack: the engine, the board code and a batch's replies live
/// on the heap; this holds their frames.
static CORE1_STACK: StaticCell<Stack<32768>> = StaticCell::new();

#[global_allocator]
static HEAP: Heap = Heap::empty();
/// The heap, for the capture and the engine's buffers: with the capture's
/// capacity, `ppmc_bridge_fw::limits`, which the QEMU board keeps too and
/// which has the arithmetic by which the capture fills before the heap.
const HEAP_SIZE: usize = limits::HEAP_BYTES;

/// The system clock embassy-rp sets up by default.
const SYSCLK_HZ: u32 = 150_000_000;

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
    core.DCB.enable_trace();
    core.DWT.enable_cycle_counter();

    // The chip's inputs (active low, released: high) and RESET* (high), the
    // buffers' enables (capture off, drive off): each level is set before
    // the pin becomes an output (embassy-rp's `Output::new` does so).
    let _inputs = [
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
    const _: () = assert!(pins::INPUTS[0] == 13 && pins::INPUTS[9] == 22);
    let _reset = Output::new(p.PIN_23, Level::High);
    const _: () = assert!(pins::RESET == 23 && pins::CAPTURE_OE == 24 && pins::DRIVE_EN == 26);
    let mut capture_oe = Output::new(p.PIN_24, Level::High);
    let mut drive_en = Output::new(p.PIN_26, Level::Low);

    // The straps: CSEL and VSEL through the capture buffer (open reads
    // high), read once it is enabled. CSEL is in GPIO bank 1, VSEL in bank
    // 0 (embassy-rp reads each from its own SIO GPIO_IN bank). GPIO 47,
    // the PGA2350's PSRAM chip select, is left alone.
    const _: () = assert!(pins::CSEL == 46 && pins::VSEL == 27);
    let csel = Input::new(p.PIN_46, Pull::Up);
    let vsel = Input::new(p.PIN_27, Pull::Up);

    // Outputs of the chip the CPU samples (input enables on).
    const _: () = assert!(pins::S[0] == 37 && pins::AUXO[3] == 45);
    let _sampled = (
        Input::new(p.PIN_37, Pull::None),
        Input::new(p.PIN_38, Pull::None),
        Input::new(p.PIN_39, Pull::None),
        Input::new(p.PIN_40, Pull::None),
        Input::new(p.PIN_41, Pull::None),
        Input::new(p.PIN_42, Pull::None),
        Input::new(p.PIN_43, Pull::None),
        Input::new(p.PIN_44, Pull::None),
        Input::new(p.PIN_45, Pull::None),
    );

    // The PIO blocks: one program each, at address 0
    // (ppmc_bridge_fw::programs), configured register by register
    // (ppmc_bridge_fw::pioregs; hw.rs).
    let [player, pout_program, pins_program] = programs::layout();
    let Pio {
        common: mut pio0, ..
    } = Pio::new(p.PIO0, Irqs);
    let Pio {
        common: mut pio1, ..
    } = Pio::new(p.PIO1, Irqs);
    let Pio {
        common: mut pio2, ..
    } = Pio::new(p.PIO2, Irqs);
    let gen = programs::relocate(programs::test_gen(), programs::test_gen_origin());
    hw::load(0, &player, 0);
    hw::load(0, &gen, programs::test_gen_origin());
    hw::load(1, &pout_program, 0);
    hw::load(2, &pins_program, 0);
    // The bus: GPIO 0-12 (D0-D7, A0, CS*, DIR, RD*, WR*) on PIO0.
    const _: () = assert!(pins::D0 == 0 && pins::WR == 12 && pins::BUS_COUNT == 13);
    let _bus_pins = [
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
    // Idle levels (CS*, DIR towards the chip, RD*, WR* high), then
    // directions, then the player's configuration, then enable.
    hw::bus_pins(ppmc_bridge_fw::bus_cycle::IDLE, 0x1FFF, 0x1FFF);
    hw::configure(0, 0, &pioregs::bus_player(&player));
    embassy_rp::pac::PIO0
        .ctrl()
        .write_value(embassy_rp::pac::pio::regs::Ctrl(1));
    // The counters' inputs: GPIO 32-33 on PIO1, 34-36 on PIO2.
    const _: () = assert!(pins::POUT == 32 && pins::DIR == 33 && pins::AUX == 36);
    // The capture's DMA rings: channels 0-3, one a counter (hw.rs),
    // claimed here so that nothing else in embassy-rp takes them.
    let _ring_channels = (p.DMA_CH0, p.DMA_CH1, p.DMA_CH2, p.DMA_CH3);
    hw::start_rings();
    let _capture_pins = (
        pio1.make_pio_pin(p.PIN_32),
        pio1.make_pio_pin(p.PIN_33),
        pio2.make_pio_pin(p.PIN_34),
        pio2.make_pio_pin(p.PIN_35),
        pio2.make_pio_pin(p.PIN_36),
    );

    // TEST_GEN (GPIO 25): PIO0's, undriven (SM1's direction stays 0)
    // except in the self-test, which drives it only while the capture
    // buffers are off (docs/bridge-hardware.md). The generator waits,
    // stopped, configured.
    const _: () = assert!(pins::TEST_GEN == 25);
    let _test_gen = pio0.make_pio_pin(p.PIN_25);
    hw::configure(0, pioregs::TEST_GEN_SM, &pioregs::test_gen(&gen));

    // The buffers: the chip's outputs in, then the bridge's out.
    capture_oe.set_low();
    drive_en.set_high();
    Delay::after_micros(10).await;
    let straps = Straps {
        sysclk_hz: CHIP_SYSCLK_HZ,
        csel_high: csel.is_high(),
        vsel_high: vsel.is_high(),
        ext_clock_hz: (EXT_CLOCK_HZ != 0).then_some(EXT_CLOCK_HZ),
    };

    // A step holds 6.9 us at most: a longer time given at build cannot be
    // played, and the board says so in its name instead of starting.
    let (timing, firmware) = if BUS_TIMING.fits(SYSCLK_HZ) {
        (BUS_TIMING, FIRMWARE)
    } else {
        (BusTiming::DEFAULT, FIRMWARE_DEFAULT_TIMING)
    };
    // HELLO_REPLY's firmware text says why the last reset happened (a
    // panic and where, a hard fault, a hang): the host prints it with
    // every run's identity.
    let restarted = last_restart();
    let firmware: alloc::string::String = match &restarted {
        Some(cause) => alloc::format!("{firmware}; restarted after {cause}"),
        None => firmware.into(),
    };
    defmt::info!(
        "{=str}: chip SysClk {=u32} Hz, CSEL {=bool}, VSEL {=bool}",
        firmware.as_str(),
        straps.sysclk_hz,
        straps.csel_high,
        straps.vsel_high
    );
    if let Some(cause) = &restarted {
        defmt::warn!("restarted after {=str}", cause.as_str());
    }
    // The engine on core 1, with its own cycle counter (each core has
    // one: the clock the board code reads is core 1's). It feeds the
    // watchdog from every loop of the board code (`Hal::keepalive`).
    let mut watchdog = Watchdog::new(p.WATCHDOG);
    watchdog.start(Duration::from_millis(hw::WATCHDOG_MS));
    let session = embassy_rp::clocks::RoscRng.next_u32();
    // The chip's ID: the USB serial number, and HELLO_REPLY's, so that two
    // bridges are told apart on a host (/dev/serial/by-id) and across a
    // network alike.
    let chip_serial = hex16(embassy_rp::otp::get_chipid().unwrap_or(0));
    // Raised by core 0 as an ABORT arrives, checked by core 1 between ops
    // and in its waits (`docs/bridge-protocol.md` section 5).
    let abort = AbortLine::new();
    let watch = AbortWatch::new(abort.clone());
    spawn_core1(p.CORE1, CORE1_STACK.init(Stack::new()), move || {
        // SAFETY: core 1's own DCB and DWT, set up once here.
        let mut core1 = unsafe { cortex_m::Peripherals::steal() };
        core1.DCB.enable_trace();
        core1.DWT.enable_cycle_counter();
        let hal = hw::Rp2350::new(SYSCLK_HZ, pout_program, pins_program, gen);
        let board = Board::new(hal, timing, straps);
        let timer = board.timer();
        let mut engine = BridgeEngine::new(board, session, false, firmware)
            .with_serial(core::str::from_utf8(&chip_serial).unwrap_or(""))
            .with_timer(timer)
            .with_capture_capacity(limits::CAPTURE_RECORDS)
            .with_abort(abort);
        let mut buf = [0u8; 64];
        // What the log has said about the board code so far.
        let (mut overruns, mut faulted) = (0u32, false);
        loop {
            let board = engine.bus();
            if board.overruns != overruns {
                overruns = board.overruns;
                defmt::warn!(
                    "capture overrun ({=u32} since boot): the counters restarted",
                    overruns
                );
            }
            if let (Some(what), false) = (ppmc_core::bus::Bus::fault(board), faulted) {
                faulted = true;
                defmt::error!("hardware fault: {=str}", what);
            }
            match FROM_HOST.try_read(&mut buf) {
                Ok(n) => {
                    let reply = engine.on_bytes(&buf[..n]);
                    let mut rest = &reply[..];
                    while !rest.is_empty() {
                        match TO_HOST.try_write(rest) {
                            Ok(k) => rest = &rest[k..],
                            // Core 0 sends as the host reads: the capture
                            // keeps draining meanwhile.
                            Err(_) => engine.bus_mut().poll(),
                        }
                    }
                }
                // Between requests the capture keeps draining.
                Err(_) => engine.bus_mut().poll(),
            }
        }
    });

    // USB CDC ACM.
    let driver = Driver::new(p.USB, Irqs);
    let mut config = embassy_usb::Config::new(0x1209, 0x0001);
    config.manufacturer = Some("ppmc");
    config.product = Some("PPMC-104BFP bus bridge");
    // The chip's ID, as HELLO_REPLY gives it.
    static SERIAL: StaticCell<[u8; 16]> = StaticCell::new();
    let serial = SERIAL.init(chip_serial);
    config.serial_number = core::str::from_utf8(serial).ok();
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
    let class = CdcAcmClass::new(&mut builder, STATE.init(State::new()), 64);
    let mut usb = builder.build();

    // Core 0 only moves bytes between the port and core 1's pipes, every
    // packet written with a deadline (ppmc_bridge_fw::usb, tested on the
    // host against the loop it replaced: defect 6).
    let serve = async {
        let mut cdc = Cdc(class);
        let pipes = CorePipes {
            watch: core::cell::RefCell::new(watch),
        };
        loop {
            usb::between_connections(&pipes, cdc.0.wait_connection()).await;
            defmt::info!("USB: the host opened the port");
            usb::serve_connection(&mut cdc, &pipes, &WriteDeadline).await;
            defmt::info!(
                "USB: the host closed the port, or stopped reading for {=u64} ms",
                WRITE_DEADLINE.as_millis()
            );
        }
    };
    // Core 0's heartbeat, for core 1's watchdog feeding (hw.rs).
    let heartbeat = async {
        loop {
            Delay::after_millis(100).await;
            hw::HEARTBEAT.fetch_add(1, core::sync::atomic::Ordering::Relaxed);
        }
    };
    join3(usb.run(), serve, heartbeat).await;
}

/// The CDC ACM class as `usb::Packets`.
struct Cdc<'d>(CdcAcmClass<'d, Driver<'d, USB>>);

impl usb::Packets for Cdc<'_> {
    async fn read_packet(&mut self, buf: &mut [u8]) -> Result<usize, ()> {
        self.0.read_packet(buf).await.map_err(drop)
    }

    async fn write_packet(&mut self, data: &[u8]) -> Result<(), ()> {
        self.0.write_packet(data).await.map_err(drop)
    }
}

/// The pipes between the cores as `usb::Pipes`, and the abort watch on
/// the way in: an ABORT is seen as its packet arrives, while core 1 is
/// busy, and before core 1 can read it. (While the pipe is full, core 0
/// reads no more packets: an ABORT behind a request longer than the pipe
/// is seen once core 1 has taken some. A host has one request out at a
/// time, so that is a retransmission of a long one.)
struct CorePipes {
    watch: core::cell::RefCell<AbortWatch>,
}

impl usb::Pipes for CorePipes {
    async fn to_engine(&self, data: &[u8]) -> usize {
        FROM_HOST.write(data).await
    }

    fn arrived(&self, packet: &[u8]) {
        self.watch.borrow_mut().on_bytes(packet);
    }

    async fn replies(&self, buf: &mut [u8]) -> usize {
        TO_HOST.read(buf).await
    }

    fn replies_empty(&self) -> bool {
        TO_HOST.is_empty()
    }

    fn forget_to_engine(&self) {
        FROM_HOST.clear();
        // A frame cut short here is not the start of the next host's.
        self.watch.borrow_mut().forget();
    }
}

/// [`WRITE_DEADLINE`] as `usb::Deadline`.
struct WriteDeadline;

impl usb::Deadline for WriteDeadline {
    async fn within<F: core::future::Future>(&self, f: F) -> Option<F::Output> {
        with_timeout(WRITE_DEADLINE, f).await.ok()
    }
}

/// `id` as 16 hexadecimal digits.
fn hex16(id: u64) -> [u8; 16] {
    let digits = b"0123456789ABCDEF";
    core::array::from_fn(|i| digits[(id >> (60 - 4 * i) & 0xF) as usize])
}

/// The restart's cause the last reset left, if any, as text; its record
/// cleared (`ppmc_bridge_fw::restart`).
fn last_restart() -> Option<alloc::string::String> {
    let wd = embassy_rp::pac::WATCHDOG;
    let scratch = [
        wd.scratch0().read(),
        wd.scratch1().read(),
        wd.scratch2().read(),
        wd.scratch3().read(),
    ];
    let reason = wd.reason().read().0;
    wd.scratch0().write_value(0);
    let cause = restart::cause(scratch, reason, in_flash)?;
    Some(alloc::format!("{cause}"))
}

/// `len` bytes of the image's flash at `address`, if all of them are in
/// it (the RP2350's XIP window: 16 MiB from 0x1000_0000).
fn in_flash(address: u32, len: usize) -> Option<&'static [u8]> {
    const XIP: core::ops::Range<u32> = 0x1000_0000..0x1100_0000;
    let end = address.checked_add(u32::try_from(len).ok()?)?;
    if !XIP.contains(&address) || end > XIP.end {
        return None;
    }
    // SAFETY: the range lies in the XIP window, which is mapped and
    // read-only for the whole life of the image.
    Some(unsafe { core::slice::from_raw_parts(address as *const u8, len) })
}

/// Keeps a record (`last_restart`) and resets the chip by its watchdog, set
/// up here in full (embassy-rp's `trigger_reset` does the same): a panic
/// before the watchdog was started would otherwise reset nothing.
fn record_and_reset(record: restart::Record) -> ! {
    cortex_m::interrupt::disable();
    let wd = embassy_rp::pac::WATCHDOG;
    let [s0, s1, s2, s3] = record.0;
    wd.scratch1().write_value(s1);
    wd.scratch2().write_value(s2);
    wd.scratch3().write_value(s3);
    wd.scratch0().write_value(s0);
    embassy_rp::pac::PSM
        .wdsel()
        .write_value(embassy_rp::pac::psm::regs::Wdsel(restart::PSM_WDSEL));
    wd.ctrl().modify(|w| {
        w.set_enable(true);
        w.set_trigger(true);
    });
    loop {
        cortex_m::asm::wfi();
    }
}

#[cortex_m_rt::exception]
unsafe fn HardFault(ef: &cortex_m_rt::ExceptionFrame) -> ! {
    defmt::error!("hard fault at pc {=u32:#010x}; restarting", ef.pc());
    record_and_reset(restart::Record::hard_fault(ef.pc()))
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    // Kept across the reset for HELLO to report (`last_restart`), then the
    // watchdog restarts the bridge: the host sees it come back, not a
    // bridge gone silent.
    let (file, line) = info.location().map_or(("?", 0), |l| (l.file(), l.line()));
    defmt::error!("panic at {=str}:{=u32}; restarting", file, line);
    record_and_reset(restart::Record::panic(
        file.as_ptr() as u32,
        file.as_bytes(),
        line,
    ))
}

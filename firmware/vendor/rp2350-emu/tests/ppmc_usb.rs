//! ppmc's tests of the USB device controller model and its virtual host
//! (`src/peripherals/usb.rs`, PPMC-CHANGES.md). Public API only: the
//! tests play the firmware through MMIO writes and reads, and the host
//! through `Emulator::usb_host`.

use rp2350_emu::{Config, DataPid, Emulator, EmulatorBuilder, Handshake, InResponse};

const RESETS_CLR: u32 = 0x4002_0000 + 0x3000;
const RESET_USBCTRL: u32 = 28;
const IRQ_USBCTRL: u32 = 14;

const REGS: u32 = 0x5011_0000;
const DPRAM: u32 = 0x5010_0000;
const SET: u32 = 0x2000;
const CLR: u32 = 0x3000;

const ADDR_ENDP: u32 = REGS;
const MAIN_CTRL: u32 = REGS + 0x40;
const SOF_RD: u32 = REGS + 0x48;
const SIE_CTRL: u32 = REGS + 0x4C;
const SIE_STATUS: u32 = REGS + 0x50;
const INT_EP_CTRL: u32 = REGS + 0x54;
const BUFF_STATUS: u32 = REGS + 0x58;
const BUFF_CPU_SHOULD_HANDLE: u32 = REGS + 0x5C;
const EP_ABORT: u32 = REGS + 0x60;
const EP_ABORT_DONE: u32 = REGS + 0x64;
const EP_STALL_ARM: u32 = REGS + 0x68;
const EP_STATUS_STALL_NAK: u32 = REGS + 0x70;
const USB_MUXING: u32 = REGS + 0x74;
const USB_PWR: u32 = REGS + 0x78;
const INTR: u32 = REGS + 0x8C;
const INTE: u32 = REGS + 0x90;
const INTF: u32 = REGS + 0x94;
const INTS: u32 = REGS + 0x98;

// SIE_STATUS
const VBUS_DETECTED: u32 = 1 << 0;
const RX_SHORT_PACKET: u32 = 1 << 12;
const CONNECTED: u32 = 1 << 16;
const SETUP_REC: u32 = 1 << 17;
const TRANS_COMPLETE: u32 = 1 << 18;
const BUS_RESET: u32 = 1 << 19;
const ACK_REC: u32 = 1 << 30;
const DATA_SEQ_ERROR: u32 = 1 << 31;

// INTR / INTE / INTS
const I_TRANS_COMPLETE: u32 = 1 << 3;
const I_BUFF_STATUS: u32 = 1 << 4;
const I_ERROR_DATA_SEQ: u32 = 1 << 5;
const I_BUS_RESET: u32 = 1 << 12;
const I_DEV_CONN_DIS: u32 = 1 << 13;
const I_DEV_RESUME: u32 = 1 << 15;
const I_DEV_SUSPEND: u32 = 1 << 14;
const I_SETUP_REQ: u32 = 1 << 16;
const I_DEV_SOF: u32 = 1 << 17;
const I_ABORT_DONE: u32 = 1 << 18;
const I_EP_STALL_NAK: u32 = 1 << 19;

// SIE_CTRL
const PULLUP_EN: u32 = 1 << 16;
const EP0_INT_1BUF: u32 = 1 << 29;
const EP0_INT_STALL: u32 = 1 << 31;

// Endpoint control
const EP_ENABLE: u32 = 1 << 31;
const EP_DOUBLE: u32 = 1 << 30;
const EP_PER_BUFF: u32 = 1 << 29;
const EP_TYPE_BULK: u32 = 2 << 26;

// Buffer control
const AVAILABLE: u32 = 1 << 10;
const STALL: u32 = 1 << 11;
const PID1: u32 = 1 << 13;
const LAST: u32 = 1 << 14;
const FULL: u32 = 1 << 15;

fn ep_in_ctrl(n: u32) -> u32 {
    DPRAM + 0x08 + 8 * (n - 1)
}
fn ep_out_ctrl(n: u32) -> u32 {
    DPRAM + 0x0C + 8 * (n - 1)
}
fn ep_in_buf(n: u32) -> u32 {
    DPRAM + 0x80 + 8 * n
}
fn ep_out_buf(n: u32) -> u32 {
    DPRAM + 0x84 + 8 * n
}

const CODE: u32 = 0x2000_0000;

/// An emulator whose core 0 spins on `b .` in SRAM (so `run` is
/// harmless) with core 1 halted, and USBCTRL out of reset.
fn emulator() -> Emulator {
    let mut emu = EmulatorBuilder::new(Config {
        sys_clk_hz: 150_000_000,
    })
    .step_quantum(16)
    .build()
    .expect("an emulator");
    emu.reset();
    emu.core_mut(1).halt();
    emu.load_image(CODE, &0xE7FEu16.to_le_bytes()); // b .
    emu.core_mut(0).regs.set_pc(CODE);
    emu.mmio_write32(RESETS_CLR, 1 << RESET_USBCTRL);
    emu
}

/// embassy-rp 0.10 `Driver::new` + `Driver::start`: zero the registers
/// and the control part of DPRAM, force VBUS detect, enable the
/// controller, enable its interrupts, EP0 interrupt per buffer, pull-up.
fn embassy_init(emu: &mut Emulator) {
    for i in 0..0x9C / 4 {
        emu.mmio_write32(REGS + 4 * i, 0);
    }
    for i in 0..0x100 / 4 {
        emu.mmio_write32(DPRAM + 4 * i, 0);
    }
    emu.mmio_write32(USB_MUXING, 1 | (1 << 3)); // TO_PHY | SOFTCON
    emu.mmio_write32(USB_PWR, (1 << 2) | (1 << 3)); // VBUS_DETECT | override
    emu.mmio_write32(MAIN_CTRL, 1); // CONTROLLER_EN
    emu.mmio_write32(
        INTE,
        I_BUS_RESET | I_BUFF_STATUS | I_DEV_RESUME | I_DEV_SUSPEND | I_SETUP_REQ,
    );
    emu.mmio_write32(INT_EP_CTRL, 0xFFFE);
    emu.mmio_write32(SIE_CTRL, EP0_INT_1BUF | PULLUP_EN);
}

fn irq_pending(emu: &Emulator) -> bool {
    emu.bus.atomics.irq_pending_load(0) & (1u64 << IRQ_USBCTRL) != 0
}

fn clear_irq(emu: &mut Emulator) {
    emu.bus.clear_irq_shared(IRQ_USBCTRL);
}

fn write_dpram(emu: &mut Emulator, offset: u32, bytes: &[u8]) {
    for (i, chunk) in bytes.chunks(4).enumerate() {
        let mut w = [0u8; 4];
        w[..chunk.len()].copy_from_slice(chunk);
        emu.mmio_write32(DPRAM + offset + 4 * i as u32, u32::from_le_bytes(w));
    }
}

fn read_dpram(emu: &mut Emulator, offset: u32, len: usize) -> Vec<u8> {
    (0..len)
        .map(|i| {
            let a = DPRAM + offset + i as u32;
            (emu.mmio_read32(a & !3) >> (8 * (a & 3))) as u8
        })
        .collect()
}

/// embassy-rp's two-step buffer-control arming: everything but
/// AVAILABLE first, then the same with AVAILABLE.
fn arm(emu: &mut Emulator, reg: u32, value: u32) {
    emu.mmio_write32(reg, value);
    emu.mmio_write32(reg, value | AVAILABLE);
}

#[test]
fn attach_reports_pullup_vbus_and_connection() {
    let mut emu = emulator();
    emu.mmio_write32(MAIN_CTRL, 1);
    assert!(!emu.usb_host().attach(), "no pull-up yet");
    assert_eq!(emu.mmio_read32(SIE_STATUS) & VBUS_DETECTED, VBUS_DETECTED);
    assert_eq!(emu.mmio_read32(SIE_STATUS) & CONNECTED, 0);
    emu.mmio_write32(SIE_CTRL + SET, PULLUP_EN);
    assert!(emu.usb_host().pullup_seen());
    assert_eq!(emu.mmio_read32(SIE_STATUS) & CONNECTED, CONNECTED);
    assert_eq!(emu.mmio_read32(INTR) & I_DEV_CONN_DIS, I_DEV_CONN_DIS);
    // DEV_CONN_DIS: cleared by writing SIE_STATUS.CONNECTED.
    emu.mmio_write32(SIE_STATUS, CONNECTED);
    assert_eq!(emu.mmio_read32(INTR) & I_DEV_CONN_DIS, 0);
    emu.usb_host().detach();
    assert_eq!(emu.mmio_read32(SIE_STATUS) & (VBUS_DETECTED | CONNECTED), 0);
    assert_eq!(emu.mmio_read32(INTR) & I_DEV_CONN_DIS, I_DEV_CONN_DIS);
    // USB_PWR's VBUS_DETECT override wins over the cable.
    emu.mmio_write32(USB_PWR, (1 << 2) | (1 << 3));
    assert_eq!(emu.mmio_read32(SIE_STATUS) & VBUS_DETECTED, VBUS_DETECTED);
}

#[test]
fn bus_reset_sets_status_intr_and_raises_irq() {
    let mut emu = emulator();
    embassy_init(&mut emu);
    emu.mmio_write32(ADDR_ENDP, 9);
    assert!(emu.usb_host().attach());
    assert!(!irq_pending(&emu));
    assert!(emu.usb_host().bus_reset());
    assert_eq!(emu.mmio_read32(SIE_STATUS) & BUS_RESET, BUS_RESET);
    assert_eq!(emu.mmio_read32(INTR) & I_BUS_RESET, I_BUS_RESET);
    assert_eq!(emu.mmio_read32(INTS), I_BUS_RESET);
    assert!(emu.usb_host().irq_asserted());
    assert!(irq_pending(&emu));
    // The address is firmware's: still 9 until it writes 0.
    assert_eq!(emu.mmio_read32(ADDR_ENDP), 9);
    // embassy Bus::poll: W1C BUS_RESET | SETUP_REC.
    emu.mmio_write32(SIE_STATUS, BUS_RESET | SETUP_REC);
    assert_eq!(emu.mmio_read32(INTS), 0);
    assert!(!emu.usb_host().irq_asserted());
}

#[test]
fn setup_is_stored_at_dpram_0_and_clears_ep_stall_arm() {
    let mut emu = emulator();
    embassy_init(&mut emu);
    emu.usb_host().attach();
    emu.mmio_write32(EP_STALL_ARM, 0b11);
    emu.mmio_write32(ep_in_buf(0), 0x1234);
    let req = [0x80, 0x06, 0x00, 0x01, 0x00, 0x00, 0x40, 0x00];
    assert_eq!(
        emu.usb_host().setup(3, req),
        Handshake::NoResponse,
        "wrong address"
    );
    assert_eq!(emu.usb_host().setup(0, req), Handshake::Ack);
    assert_eq!(read_dpram(&mut emu, 0, 8), req);
    assert_eq!(emu.mmio_read32(SIE_STATUS) & SETUP_REC, SETUP_REC);
    assert_eq!(emu.mmio_read32(INTS) & I_SETUP_REQ, I_SETUP_REQ);
    assert!(irq_pending(&emu));
    assert_eq!(emu.mmio_read32(EP_STALL_ARM), 0);
    assert_eq!(
        emu.mmio_read32(ep_in_buf(0)),
        0x1234,
        "buffer control untouched"
    );
    // W1C through the CLR alias (pico-sdk / TinyUSB style) clears too.
    emu.mmio_write32(SIE_STATUS + CLR, SETUP_REC);
    assert_eq!(emu.mmio_read32(SIE_STATUS) & SETUP_REC, 0);
}

#[test]
fn ep0_in_takes_full_available_buffer() {
    let mut emu = emulator();
    embassy_init(&mut emu);
    emu.usb_host().attach();
    assert_eq!(emu.usb_host().in_token(0, 0), InResponse::Nak);
    let data: Vec<u8> = (1..=18).collect();
    write_dpram(&mut emu, 0x100, &data);
    arm(&mut emu, ep_in_buf(0), 18 | PID1 | FULL);
    clear_irq(&mut emu);
    assert_eq!(
        emu.usb_host().in_token(0, 0),
        InResponse::Data {
            data: data.clone(),
            pid: DataPid::Data1
        }
    );
    let bc = emu.mmio_read32(ep_in_buf(0));
    assert_eq!(bc & (AVAILABLE | FULL), 0);
    assert_eq!(bc & (PID1 | 0x3FF), PID1 | 18, "PID and LENGTH kept");
    assert_eq!(emu.mmio_read32(BUFF_STATUS), 1, "BUFF_STATUS bit ep*2");
    assert_eq!(emu.mmio_read32(INTS), I_BUFF_STATUS);
    assert_eq!(emu.mmio_read32(SIE_STATUS) & ACK_REC, ACK_REC);
    assert!(irq_pending(&emu));
    assert_eq!(
        emu.usb_host().in_token(0, 0),
        InResponse::Nak,
        "buffer consumed"
    );
    // embassy's handler: write BUFF_STATUS back to clear it.
    emu.mmio_write32(BUFF_STATUS, 1);
    assert_eq!(emu.mmio_read32(INTR) & I_BUFF_STATUS, 0);
    // Without SIE_CTRL.EP0_INT_1BUF no BUFF_STATUS bit is set.
    emu.mmio_write32(SIE_CTRL + CLR, EP0_INT_1BUF);
    arm(&mut emu, ep_in_buf(0), FULL | LAST);
    assert_eq!(
        emu.usb_host().in_token(0, 0),
        InResponse::Data {
            data: vec![],
            pid: DataPid::Data0
        }
    );
    assert_eq!(emu.mmio_read32(BUFF_STATUS), 0);
    assert_eq!(emu.mmio_read32(SIE_STATUS) & TRANS_COMPLETE, TRANS_COMPLETE);
    assert_eq!(emu.mmio_read32(INTR) & I_TRANS_COMPLETE, I_TRANS_COMPLETE);
}

#[test]
fn ep0_out_status_stage_fills_buffer() {
    let mut emu = emulator();
    embassy_init(&mut emu);
    emu.usb_host().attach();
    assert_eq!(
        emu.usb_host().out_token(0, 0, &[], DataPid::Data1),
        Handshake::Nak
    );
    arm(&mut emu, ep_out_buf(0), PID1);
    assert_eq!(
        emu.usb_host().out_token(0, 0, &[], DataPid::Data1),
        Handshake::Ack
    );
    let bc = emu.mmio_read32(ep_out_buf(0));
    assert_eq!(
        bc & 0xFFFF,
        FULL | PID1,
        "FULL, LENGTH 0, PID 1, not AVAILABLE"
    );
    assert_eq!(
        emu.mmio_read32(BUFF_STATUS),
        1 << 1,
        "BUFF_STATUS bit ep*2+1"
    );
    assert_eq!(
        emu.usb_host().out_token(0, 0, &[], DataPid::Data1),
        Handshake::Nak
    );
}

#[test]
fn bulk_out_pid_short_packet_sequence_error_and_enable() {
    let mut emu = emulator();
    embassy_init(&mut emu);
    emu.usb_host().attach();
    emu.mmio_write32(ADDR_ENDP, 5);
    // embassy alloc_endpoint: disabled, buffer 0x180, per-buffer irq.
    emu.mmio_write32(ep_out_ctrl(2), EP_PER_BUFF | EP_TYPE_BULK | 0x180);
    arm(&mut emu, ep_out_buf(2), 64);
    assert_eq!(
        emu.usb_host().out_token(5, 2, b"hi", DataPid::Data0),
        Handshake::NoResponse,
        "endpoint not enabled"
    );
    emu.mmio_write32(
        ep_out_ctrl(2),
        EP_ENABLE | EP_PER_BUFF | EP_TYPE_BULK | 0x180,
    );
    assert_eq!(
        emu.usb_host().out_token(0, 2, b"hi", DataPid::Data0),
        Handshake::NoResponse,
        "wrong address"
    );
    assert_eq!(
        emu.usb_host().out_token(5, 2, &[0; 65], DataPid::Data0),
        Handshake::NoResponse,
        "longer than LENGTH"
    );
    assert_eq!(
        emu.usb_host().out_token(5, 2, b"hello", DataPid::Data0),
        Handshake::Ack
    );
    assert_eq!(read_dpram(&mut emu, 0x180, 5), b"hello");
    let bc = emu.mmio_read32(ep_out_buf(2));
    assert_eq!(bc & 0xFFFF, FULL | 5);
    assert_eq!(emu.mmio_read32(BUFF_STATUS), 1 << 5);
    assert_eq!(
        emu.mmio_read32(SIE_STATUS) & RX_SHORT_PACKET,
        RX_SHORT_PACKET
    );
    // Re-arm for DATA1 as embassy's read() does; a DATA0 retry is ACKed
    // and dropped with DATA_SEQ_ERROR.
    arm(&mut emu, ep_out_buf(2), PID1 | 64);
    assert_eq!(
        emu.usb_host().out_token(5, 2, b"again", DataPid::Data0),
        Handshake::Ack
    );
    assert_eq!(emu.mmio_read32(SIE_STATUS) & DATA_SEQ_ERROR, DATA_SEQ_ERROR);
    assert_eq!(emu.mmio_read32(INTR) & I_ERROR_DATA_SEQ, I_ERROR_DATA_SEQ);
    assert_eq!(
        emu.mmio_read32(ep_out_buf(2)) & 0xFFFF,
        PID1 | AVAILABLE | 64
    );
    assert_eq!(read_dpram(&mut emu, 0x180, 5), b"hello");
    assert_eq!(
        emu.usb_host().out_token(5, 2, b"world", DataPid::Data1),
        Handshake::Ack
    );
    assert_eq!(read_dpram(&mut emu, 0x180, 5), b"world");
    assert_eq!(emu.mmio_read32(ep_out_buf(2)) & 0xFFFF, FULL | PID1 | 5);
}

#[test]
fn stall_on_ep0_needs_ep_stall_arm() {
    let mut emu = emulator();
    embassy_init(&mut emu);
    emu.usb_host().attach();
    emu.mmio_write32(SIE_CTRL + SET, EP0_INT_STALL);
    // embassy reject(): arm both, then STALL in both buffer controls.
    emu.mmio_write32(ep_in_buf(0), STALL);
    emu.mmio_write32(ep_out_buf(0), STALL);
    assert_eq!(
        emu.usb_host().in_token(0, 0),
        InResponse::Nak,
        "STALL not armed"
    );
    emu.mmio_write32(EP_STALL_ARM + SET, 0b11);
    assert_eq!(emu.usb_host().in_token(0, 0), InResponse::Stall);
    assert_eq!(
        emu.usb_host().out_token(0, 0, &[], DataPid::Data1),
        Handshake::Stall
    );
    assert_eq!(emu.mmio_read32(EP_STATUS_STALL_NAK), 0b11);
    assert_eq!(emu.mmio_read32(INTR) & I_EP_STALL_NAK, I_EP_STALL_NAK);
    emu.mmio_write32(EP_STATUS_STALL_NAK, 0b11);
    assert_eq!(emu.mmio_read32(INTR) & I_EP_STALL_NAK, 0);
    // A SETUP clears EP_STALL_ARM: the stall is gone.
    assert_eq!(emu.usb_host().setup(0, [0; 8]), Handshake::Ack);
    assert_eq!(emu.usb_host().in_token(0, 0), InResponse::Nak);
    // Endpoints other than EP0 stall on the STALL bit alone.
    emu.mmio_write32(ep_in_ctrl(1), EP_ENABLE | EP_TYPE_BULK | 0x180);
    emu.mmio_write32(ep_in_buf(1), STALL);
    assert_eq!(emu.usb_host().in_token(0, 1), InResponse::Stall);
}

#[test]
fn ep_abort_naks_and_sets_abort_done() {
    let mut emu = emulator();
    embassy_init(&mut emu);
    emu.usb_host().attach();
    emu.mmio_write32(
        ep_in_ctrl(1),
        EP_ENABLE | EP_PER_BUFF | EP_TYPE_BULK | 0x1C0,
    );
    write_dpram(&mut emu, 0x1C0, b"abc");
    arm(&mut emu, ep_in_buf(1), FULL | 3);
    emu.mmio_write32(EP_ABORT + SET, 1 << 2);
    assert_eq!(emu.mmio_read32(EP_ABORT_DONE), 1 << 2);
    assert_eq!(emu.mmio_read32(INTR) & I_ABORT_DONE, I_ABORT_DONE);
    assert_eq!(emu.usb_host().in_token(0, 1), InResponse::Nak);
    emu.mmio_write32(EP_ABORT_DONE, 1 << 2);
    assert_eq!(emu.mmio_read32(INTR) & I_ABORT_DONE, 0);
    emu.mmio_write32(EP_ABORT + CLR, 1 << 2);
    assert_eq!(
        emu.usb_host().in_token(0, 1),
        InResponse::Data {
            data: b"abc".to_vec(),
            pid: DataPid::Data0
        }
    );
    assert_eq!(emu.mmio_read32(BUFF_STATUS), 1 << 2);
}

#[test]
fn double_buffered_in_alternates_buffers() {
    let mut emu = emulator();
    embassy_init(&mut emu);
    emu.usb_host().attach();
    emu.mmio_write32(
        ep_in_ctrl(3),
        EP_ENABLE | EP_DOUBLE | EP_PER_BUFF | EP_TYPE_BULK | 0x200,
    );
    write_dpram(&mut emu, 0x200, b"first");
    write_dpram(&mut emu, 0x240, b"second");
    let b0 = FULL | 5;
    let b1 = (FULL | LAST | PID1 | 6) << 16;
    emu.mmio_write32(ep_in_buf(3), b0 | b1);
    emu.mmio_write32(ep_in_buf(3), b0 | b1 | AVAILABLE | (AVAILABLE << 16));
    assert_eq!(
        emu.usb_host().in_token(0, 3),
        InResponse::Data {
            data: b"first".to_vec(),
            pid: DataPid::Data0
        }
    );
    assert_eq!(emu.mmio_read32(BUFF_CPU_SHOULD_HANDLE) & (1 << 6), 0);
    emu.mmio_write32(BUFF_STATUS, 1 << 6);
    assert_eq!(
        emu.usb_host().in_token(0, 3),
        InResponse::Data {
            data: b"second".to_vec(),
            pid: DataPid::Data1
        }
    );
    assert_eq!(emu.mmio_read32(BUFF_CPU_SHOULD_HANDLE) & (1 << 6), 1 << 6);
    assert_eq!(emu.mmio_read32(BUFF_STATUS), 1 << 6);
    assert_eq!(emu.mmio_read32(SIE_STATUS) & TRANS_COMPLETE, TRANS_COMPLETE);
    let bc = emu.mmio_read32(ep_in_buf(3));
    assert_eq!(
        bc & ((AVAILABLE | FULL) * 0x1_0001),
        0,
        "both buffers handed back"
    );
    assert_eq!(emu.usb_host().in_token(0, 3), InResponse::Nak);
}

#[test]
fn irq_line_is_level_like() {
    let mut emu = emulator();
    embassy_init(&mut emu);
    emu.usb_host().attach();
    emu.usb_host().bus_reset();
    assert!(irq_pending(&emu));
    // Still INTS != 0: re-asserted at the next quantum end.
    clear_irq(&mut emu);
    emu.run(64).expect("run");
    assert!(irq_pending(&emu));
    // embassy's handler masks the source (INTE clear): line drops.
    emu.mmio_write32(INTE + CLR, I_BUS_RESET);
    clear_irq(&mut emu);
    emu.run(64).expect("run");
    assert!(!irq_pending(&emu));
    // Re-enabling INTE while the status is still latched raises it at
    // once (embassy's poll/setup re-enable pattern).
    emu.mmio_write32(INTE + SET, I_BUS_RESET);
    assert!(irq_pending(&emu));
    emu.mmio_write32(SIE_STATUS, BUS_RESET);
    clear_irq(&mut emu);
    emu.run(64).expect("run");
    assert!(!irq_pending(&emu));
    // INTF forces through INTE.
    emu.mmio_write32(INTF, I_DEV_SOF);
    assert_eq!(emu.mmio_read32(INTS), 0);
    emu.mmio_write32(INTE + SET, I_DEV_SOF);
    assert_eq!(emu.mmio_read32(INTS), I_DEV_SOF);
    emu.mmio_write32(INTF, 0);
    // SOF latches DEV_SOF; reading SOF_RD clears it.
    assert!(emu.usb_host().sof(0x123));
    assert_eq!(emu.mmio_read32(INTS), I_DEV_SOF);
    assert_eq!(emu.mmio_read32(SOF_RD), 0x123);
    assert_eq!(emu.mmio_read32(INTS), 0);
}

#[test]
fn controller_held_in_reset_or_disabled_answers_nothing() {
    let mut emu = EmulatorBuilder::new(Config::default())
        .build()
        .expect("an emulator");
    assert!(!emu.usb_host().attach());
    assert!(!emu.usb_host().bus_reset());
    assert_eq!(emu.usb_host().setup(0, [0; 8]), Handshake::NoResponse);
    let mut emu = emulator();
    emu.usb_host().attach();
    emu.mmio_write32(SIE_CTRL, PULLUP_EN);
    assert!(emu.usb_host().pullup_seen());
    assert_eq!(
        emu.usb_host().setup(0, [0; 8]),
        Handshake::NoResponse,
        "CONTROLLER_EN clear"
    );
    emu.mmio_write32(MAIN_CTRL, 1);
    assert_eq!(emu.usb_host().setup(0, [0; 8]), Handshake::Ack);
}

/// The register sequence embassy-rp 0.10's driver performs during the
/// first control transfers of enumeration, played by hand against the
/// host: bus reset, GET_DESCRIPTOR(Device) with a DATA1 IN data stage
/// and a zero-length OUT status stage, then SET_ADDRESS with a
/// zero-length IN status stage after which the device answers its new
/// address only.
#[test]
fn embassy_enumeration_sequence() {
    let mut emu = emulator();
    embassy_init(&mut emu);
    assert!(emu.usb_host().attach(), "pull-up seen");

    // Bus reset; firmware (IRQ handler, then Bus::poll).
    assert!(emu.usb_host().bus_reset());
    assert!(irq_pending(&emu));
    assert_eq!(emu.mmio_read32(INTS) & I_BUS_RESET, I_BUS_RESET);
    emu.mmio_write32(INTE + CLR, I_BUS_RESET);
    assert_eq!(emu.mmio_read32(SIE_STATUS) & BUS_RESET, BUS_RESET);
    emu.mmio_write32(SIE_STATUS, BUS_RESET | SETUP_REC);
    emu.mmio_write32(BUFF_STATUS, 0xFFFF_FFFF);
    emu.mmio_write32(ADDR_ENDP, 0);
    emu.mmio_write32(INTE + SET, I_BUS_RESET | I_DEV_RESUME | I_DEV_SUSPEND);
    assert_eq!(emu.mmio_read32(INTS), 0);

    // GET_DESCRIPTOR(Device), wLength 64.
    emu.mmio_write32(INTE + SET, I_SETUP_REQ); // ControlPipe::setup
    clear_irq(&mut emu);
    let get_desc = [0x80, 0x06, 0x00, 0x01, 0x00, 0x00, 0x40, 0x00];
    assert_eq!(emu.usb_host().setup(0, get_desc), Handshake::Ack);
    assert!(irq_pending(&emu));
    assert_eq!(emu.mmio_read32(INTS), I_SETUP_REQ);
    emu.mmio_write32(INTE + CLR, I_SETUP_REQ); // handler
    assert_eq!(emu.mmio_read32(SIE_STATUS) & SETUP_REC, SETUP_REC);
    assert_eq!(read_dpram(&mut emu, 0, 8), get_desc);
    emu.mmio_write32(SIE_STATUS, SETUP_REC);
    emu.mmio_write32(ep_in_buf(0), 0); // PID 0 so the toggle gives DATA1
    emu.mmio_write32(ep_out_buf(0), 0);
    // The host's IN before the data is ready is NAKed.
    assert_eq!(emu.usb_host().in_token(0, 0), InResponse::Nak);
    // data_in(last): 18 bytes at 0x100, PID !0, FULL, then AVAILABLE.
    let desc: [u8; 18] = [
        18, 1, 0x00, 0x02, 0xEF, 0x02, 0x01, 64, 0xC0, 0x16, 0xE1, 0x27, 0x00, 0x01, 1, 2, 3, 1,
    ];
    write_dpram(&mut emu, 0x100, &desc);
    let pid = !emu.mmio_read32(ep_in_buf(0)) & PID1;
    arm(&mut emu, ep_in_buf(0), 18 | pid | FULL);
    clear_irq(&mut emu);
    assert_eq!(
        emu.usb_host().in_token(0, 0),
        InResponse::Data {
            data: desc.to_vec(),
            pid: DataPid::Data1
        }
    );
    assert!(irq_pending(&emu));
    let s = emu.mmio_read32(BUFF_STATUS); // handler
    assert_eq!(s, 1);
    emu.mmio_write32(BUFF_STATUS, s);
    assert_eq!(emu.mmio_read32(ep_in_buf(0)) & AVAILABLE, 0, "data_in done");
    // Status stage not armed yet: NAK until firmware arms it.
    assert_eq!(
        emu.usb_host().out_token(0, 0, &[], DataPid::Data1),
        Handshake::Nak
    );
    arm(&mut emu, ep_out_buf(0), PID1); // LENGTH 0, DATA1
    assert_eq!(
        emu.usb_host().out_token(0, 0, &[], DataPid::Data1),
        Handshake::Ack
    );
    assert_eq!(emu.mmio_read32(BUFF_STATUS), 1 << 1);
    emu.mmio_write32(BUFF_STATUS, 1 << 1);

    // SET_ADDRESS(5): no data stage; accept() sends a DATA1 ZLP.
    emu.mmio_write32(INTE + SET, I_SETUP_REQ);
    let set_addr = [0x00, 0x05, 0x05, 0x00, 0x00, 0x00, 0x00, 0x00];
    assert_eq!(emu.usb_host().setup(0, set_addr), Handshake::Ack);
    emu.mmio_write32(INTE + CLR, I_SETUP_REQ);
    emu.mmio_write32(SIE_STATUS, SETUP_REC);
    emu.mmio_write32(ep_in_buf(0), 0);
    emu.mmio_write32(ep_out_buf(0), 0);
    arm(&mut emu, ep_in_buf(0), PID1 | FULL);
    assert_eq!(
        emu.usb_host().in_token(0, 0),
        InResponse::Data {
            data: vec![],
            pid: DataPid::Data1
        }
    );
    let s = emu.mmio_read32(BUFF_STATUS);
    emu.mmio_write32(BUFF_STATUS, s);
    emu.mmio_write32(ADDR_ENDP, 5); // accept_set_address
    assert_eq!(emu.usb_host().setup(0, get_desc), Handshake::NoResponse);
    assert_eq!(emu.usb_host().setup(5, get_desc), Handshake::Ack);
}

//! ppmc's tests of its changes to the cores (PPMC-CHANGES.md): the
//! ARMv8-M load-acquire and store-release instructions, and core 1's side
//! of the inter-core FIFOs for a stand-in bootrom.

use rp2350_emu::{Config, Emulator, EmulatorBuilder};

const CODE: u32 = 0x2000_0000;
const DATA: u32 = 0x2000_1000;

/// An emulator with `halfwords` at [`CODE`] for core 0 to run, core 1
/// halted.
fn with_code(halfwords: &[u16]) -> Emulator {
    let mut emu = EmulatorBuilder::new(Config {
        sys_clk_hz: 150_000_000,
    })
    .step_quantum(1)
    .build()
    .expect("an emulator");
    emu.reset();
    emu.core_mut(1).halt();
    let bytes: Vec<u8> = halfwords.iter().flat_map(|h| h.to_le_bytes()).collect();
    emu.load_image(CODE, &bytes);
    emu.core_mut(0).regs.set_pc(CODE);
    emu
}

/// Runs core 0 until it reaches `b .` (its pc stays put).
fn run_to_the_end(emu: &mut Emulator, end: u32) {
    for _ in 0..10_000 {
        if emu.core(0).regs.pc() == end {
            return;
        }
        emu.step().expect("a step");
    }
    panic!(
        "core 0 never reached {end:#x}: pc {:#x}",
        emu.core(0).regs.pc()
    );
}

/// DDI0553 C2.4 (LDA, LDAB, LDAH, LDAEX, STL, STLB, STLH, STLEX): each is
/// its plain or exclusive access on a single core. Before the change, the
/// decoder took these encodings for LDRD/STRD.
#[test]
fn load_acquire_and_store_release_move_the_sizes_they_name() {
    let program = [
        0xE8D0, 0x1F8F, // ldab r1, [r0]
        0xE8D0, 0x2F9F, // ldah r2, [r0]
        0xE8D0, 0x3FAF, // lda r3, [r0]
        0xE8C5, 0x4F8F, // stlb r4, [r5]
        0xE8C6, 0x4F9F, // stlh r4, [r6]
        0xE8C7, 0x4FAF, // stl r4, [r7]
        0xE8D7, 0x8FEF, // ldaex r8, [r7]
        0xE8C7, 0x4FE9, // stlex r9, r4, [r7]: the monitor is set
        0xE8C7, 0x4FEA, // stlex r10, r4, [r7]: it was cleared
        0xE7FE, // b .
    ];
    let mut emu = with_code(&program);
    emu.poke(DATA, 0x8899_AABB);
    for (a, v) in [(0x100, 0xFFFF_FFFF), (0x104, 0xFFFF_FFFF), (0x108, 0)] {
        emu.poke(DATA + a, v);
    }
    {
        let r = &mut emu.core_mut(0).regs.r;
        r[0] = DATA;
        r[4] = 0x1122_3344;
        r[5] = DATA + 0x100;
        r[6] = DATA + 0x104;
        r[7] = DATA + 0x108;
        r[9] = 0xDEAD;
        r[10] = 0xDEAD;
    }
    run_to_the_end(&mut emu, CODE + 36);
    let r = emu.core(0).regs.r;
    assert_eq!(r[1], 0xBB, "ldab");
    assert_eq!(r[2], 0xAABB, "ldah");
    assert_eq!(r[3], 0x8899_AABB, "lda");
    assert_eq!(emu.peek(DATA + 0x100), 0xFFFF_FF44, "stlb writes one byte");
    assert_eq!(emu.peek(DATA + 0x104), 0xFFFF_3344, "stlh writes two");
    assert_eq!(emu.peek(DATA + 0x108), 0x1122_3344, "stl");
    assert_eq!(r[8], 0x1122_3344, "ldaex");
    assert_eq!(r[9], 0, "stlex with the monitor set succeeds");
    assert_eq!(r[10], 1, "stlex after it fails");
}

/// RP2350 datasheet 3.1.5: what core 0 writes to FIFO_WR, core 1 reads;
/// what core 1 writes, core 0 reads from FIFO_RD.
#[test]
fn the_host_plays_core_1_on_the_fifos() {
    let program = [
        0x6541, // str r1, [r0, #0x54]: FIFO_WR
        0xE7FE, // b .
        0x6D82, // ldr r2, [r0, #0x58]: FIFO_RD
        0xE7FE, // b .
    ];
    let mut emu = with_code(&program);
    emu.core_mut(0).regs.r[0] = 0xD000_0000;
    emu.core_mut(0).regs.r[1] = 0x1234_5678;
    assert_eq!(emu.bus.sio.core1_fifo_pop(), None, "empty before");
    run_to_the_end(&mut emu, CODE + 2);
    assert_eq!(emu.bus.sio.core1_fifo_pop(), Some(0x1234_5678));
    assert_eq!(emu.bus.sio.core1_fifo_pop(), None, "taken once");
    emu.bus.sio.core1_fifo_push(0xCAFE);
    emu.core_mut(0).regs.set_pc(CODE + 4);
    run_to_the_end(&mut emu, CODE + 6);
    assert_eq!(emu.core(0).regs.r[2], 0xCAFE);
}

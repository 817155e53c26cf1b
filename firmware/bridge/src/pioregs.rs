//! The PIO configuration of the bridge as the register values the RP2350
//! image writes: one function computes them, the image writes them through
//! the PAC, and the board twin ([`crate::twin`]) runs its PIO model from the
//! very same values. Field positions are the RP2350 datasheet's (PIO
//! chapter, the SMx_EXECCTRL, SMx_SHIFTCTRL, SMx_PINCTRL, CTRL, FDEBUG and
//! GPIOBASE registers); a test holds them to `rp-pac`, which is generated
//! from Raspberry Pi's SVD.
//!
//! Why not embassy-rp's `Config`: embassy-rp 0.10 subtracts GPIOBASE from
//! the IN, OUT, SET and side-set bases but writes the JMP pin's GPIO number
//! raw into its 5-bit field (embassy-rs/embassy#5498, open), so with
//! GPIOBASE = 16 a `jmp pin` on GPIO 32 tests GPIO 16. Every pin field
//! here is relative to the block's window, the JMP pin included.

use crate::hal::Counter;
use crate::pins;
#[cfg(test)]
use crate::programs;
use crate::programs::Loaded;

/// SMx_EXECCTRL fields.
pub mod execctrl {
    pub const WRAP_BOTTOM: u32 = 7;
    pub const WRAP_TOP: u32 = 12;
    pub const JMP_PIN: u32 = 24;
    /// 1: side-set writes pin directions, not levels.
    pub const SIDE_PINDIR: u32 = 29;
    /// 1: the side-set's top bit enables it (`.side_set n opt`).
    pub const SIDE_EN: u32 = 30;
}

/// SMx_SHIFTCTRL fields.
pub mod shiftctrl {
    pub const IN_COUNT: u32 = 0;
    pub const AUTOPUSH: u32 = 16;
    pub const AUTOPULL: u32 = 17;
    /// 1: shift right.
    pub const IN_SHIFTDIR: u32 = 18;
    /// 1: shift right.
    pub const OUT_SHIFTDIR: u32 = 19;
    /// 0 means 32.
    pub const PUSH_THRESH: u32 = 20;
    pub const PULL_THRESH: u32 = 25;
    pub const FJOIN_TX: u32 = 30;
    pub const FJOIN_RX: u32 = 31;
}

/// SMx_PINCTRL fields.
pub mod pinctrl {
    pub const OUT_BASE: u32 = 0;
    pub const SET_BASE: u32 = 5;
    pub const SIDESET_BASE: u32 = 10;
    pub const IN_BASE: u32 = 15;
    pub const OUT_COUNT: u32 = 20;
    pub const SET_COUNT: u32 = 26;
    pub const SIDESET_COUNT: u32 = 29;
}

/// CTRL fields.
pub mod ctrl {
    pub const SM_ENABLE: u32 = 0;
    pub const SM_RESTART: u32 = 4;
    pub const CLKDIV_RESTART: u32 = 8;
    pub const NEXT_PIO_MASK: u32 = 20;
    pub const NEXTPREV_SM_ENABLE: u32 = 24;
    pub const NEXTPREV_SM_DISABLE: u32 = 25;
    pub const NEXTPREV_CLKDIV_RESTART: u32 = 26;
}

/// FDEBUG fields (4 bits, one per state machine; write 1 to clear).
pub mod fdebug {
    pub const RXSTALL: u32 = 0;
    pub const RXUNDER: u32 = 8;
    pub const TXOVER: u32 = 16;
    pub const TXSTALL: u32 = 24;
}

/// SMx_CLKDIV for a divider of 1: every system clock cycle.
pub const CLKDIV_1: u32 = 1 << 16;

/// What one state machine is given: its registers, and the instruction it
/// starts at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SmRegs {
    pub clkdiv: u32,
    pub execctrl: u32,
    pub shiftctrl: u32,
    pub pinctrl: u32,
    /// Address the state machine starts at (a forced `jmp`).
    pub start: u8,
    /// X at start (a forced `mov x, ~null` for the edge counters).
    pub x: u32,
    /// The side-set value the forced instructions carry, for a program
    /// with a side-set ([`Loaded::side`]): the state machine decodes them
    /// with its side-set configuration, as it does its program.
    pub side: Option<u8>,
}

impl SmRegs {
    /// The instructions the CPU forces into the state machine (SMx_INSTR)
    /// after writing its registers and before enabling it: X to its start
    /// value (`mov x, ~null` or `set x, 0`), then a jump to its start.
    pub fn start_instructions(&self) -> [u16; 2] {
        use pio::{
            Instruction, InstructionOperands, JmpCondition, MovDestination, MovOperation,
            MovSource, SetDestination, SideSet,
        };
        let set_x = if self.x == u32::MAX {
            InstructionOperands::MOV {
                destination: MovDestination::X,
                op: MovOperation::Invert,
                source: MovSource::NULL,
            }
        } else {
            InstructionOperands::SET {
                destination: SetDestination::X,
                data: (self.x & 0x1F) as u8,
            }
        };
        let jmp = InstructionOperands::JMP {
            condition: JmpCondition::Always,
            address: self.start,
        };
        let count = (self.pinctrl >> pinctrl::SIDESET_COUNT & 0b111) as u8;
        let side_set = SideSet::new(
            false,
            count,
            self.execctrl >> execctrl::SIDE_PINDIR & 1 == 1,
        );
        [set_x, jmp].map(|operands| {
            Instruction {
                operands,
                delay: 0,
                side_set: self.side.filter(|_| count > 0),
            }
            .encode(side_set)
        })
    }
}

/// A GPIO outside a block's 32-pin window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OutsideWindow {
    pub gpio: u32,
    pub gpiobase: u32,
}

/// `gpio` as an index in the window starting at `gpiobase` (0 or 16).
pub const fn in_window(gpio: u32, gpiobase: u32) -> Result<u32, OutsideWindow> {
    if gpio >= gpiobase && gpio < gpiobase + 32 {
        Ok(gpio - gpiobase)
    } else {
        Err(OutsideWindow { gpio, gpiobase })
    }
}

const fn idx(gpio: u32, gpiobase: u32) -> u32 {
    match in_window(gpio, gpiobase) {
        Ok(i) => i,
        Err(_) => panic!("a pin outside its block's window"),
    }
}

fn wrap(p: &Loaded) -> u32 {
    u32::from(p.wrap_top) << execctrl::WRAP_TOP | u32::from(p.wrap_bottom) << execctrl::WRAP_BOTTOM
}

/// The PIO blocks the bridge uses and their windows.
pub mod block {
    /// The bus player: GPIO 0-12.
    pub const BUS: usize = 0;
    /// The POUT counter: GPIO 32-33.
    pub const POUT: usize = 1;
    /// The INT*, HOLD and AUX* counters: GPIO 34-36.
    pub const PINS: usize = 2;
    /// GPIOBASE of each block.
    pub const GPIOBASE: [u32; 3] = [0, 16, 16];
}

/// The bus player (PIO0, SM0) running `p` ([`crate::programs::bus_player`]): OUT
/// pins GPIO 0-12, IN base GPIO 0 (D0-D7), OUT shift right, IN shift left,
/// no autopull or autopush, FIFOs not joined (it pushes the bytes it
/// reads): 4 steps queue in the TX FIFO. Its side-set (to directions,
/// not optional) covers A0, CS*, DIR, RD* and WR*: GPIO 8-12.
pub fn bus_player(p: &Loaded) -> SmRegs {
    let base = block::GPIOBASE[block::BUS];
    let side = p.program.side_set;
    SmRegs {
        clkdiv: CLKDIV_1,
        execctrl: wrap(p)
            | u32::from(side.pindirs()) << execctrl::SIDE_PINDIR
            | u32::from(side.optional()) << execctrl::SIDE_EN,
        shiftctrl: 1 << shiftctrl::OUT_SHIFTDIR | 8 << shiftctrl::IN_COUNT,
        pinctrl: idx(pins::D0, base) << pinctrl::OUT_BASE
            | pins::BUS_COUNT << pinctrl::OUT_COUNT
            | idx(pins::D0, base) << pinctrl::IN_BASE
            | idx(pins::A0, base) << pinctrl::SIDESET_BASE
            | u32::from(side.bits()) << pinctrl::SIDESET_COUNT,
        start: p.start,
        x: 0,
        side: p.side,
    }
}

/// The self-test generator (PIO0, SM1) running `p` ([`crate::programs::test_gen`],
/// relocated to its origin): SET pin TEST_GEN, FIFOs not joined (a
/// burst's three words fit the TX FIFO's four), no side-set.
pub fn test_gen(p: &Loaded) -> SmRegs {
    let base = block::GPIOBASE[block::BUS];
    SmRegs {
        clkdiv: CLKDIV_1,
        execctrl: wrap(p),
        shiftctrl: 1 << shiftctrl::OUT_SHIFTDIR,
        pinctrl: idx(pins::TEST_GEN, base) << pinctrl::SET_BASE | 1 << pinctrl::SET_COUNT,
        start: p.start,
        x: 0,
        side: p.side,
    }
}

/// The generator's state machine in PIO0.
pub const TEST_GEN_SM: usize = 1;

/// PIO0's CTRL with the bus player (SM0) running and the generator
/// stopped and restarted (its ISR, OSR counters and delay cleared).
pub const TEST_GEN_STOP: u32 = 1 << ctrl::SM_ENABLE | 1 << (TEST_GEN_SM as u32 + ctrl::SM_RESTART);

/// PIO0's CTRL with both the bus player and the generator running.
pub const TEST_GEN_RUN: u32 = (1 | 1 << TEST_GEN_SM) << ctrl::SM_ENABLE;

/// A `set pins` (or `set pindirs`) of `value`, with no delay or side-set:
/// what the CPU forces on the generator's state machine to drive or
/// release TEST_GEN.
pub const fn force_set(pindirs: bool, value: u8) -> u16 {
    let dest: u16 = if pindirs { 0b100 } else { 0b000 };
    0b111 << 13 | dest << 5 | (value as u16 & 0x1F)
}

/// An edge counter running `p`: JMP pin `pin`, IN base `input` (one pin),
/// RX FIFO joined (8 words), counting from all ones, started in the loop
/// for the level `pin` has (`high`), so that starting is not an edge.
fn counter(p: &Loaded, block: usize, pin: u32, input: u32, high: bool) -> SmRegs {
    let base = block::GPIOBASE[block];
    SmRegs {
        clkdiv: CLKDIV_1,
        execctrl: wrap(p) | idx(pin, base) << execctrl::JMP_PIN,
        shiftctrl: 1 << shiftctrl::FJOIN_RX | 1 << shiftctrl::IN_COUNT,
        pinctrl: idx(input, base) << pinctrl::IN_BASE,
        start: if high { p.start } else { p.start_low },
        x: u32::MAX,
        side: p.side,
    }
}

/// The POUT counter (PIO1, SM0) running `p` ([`crate::programs::edge_counter`]
/// `(true)`): rising edges of POUT, with DIR; `pout_high` is POUT's level
/// now.
pub fn pout_counter(p: &Loaded, pout_high: bool) -> SmRegs {
    counter(p, block::POUT, pins::POUT, pins::DIR, pout_high)
}

/// The INT*, HOLD and AUX* counters (PIO2, SM0-2) running `p`
/// ([`crate::programs::edge_counter`]`(false)`): both edges, with the new level;
/// `levels` are the three pins' levels now.
pub fn pin_counters(p: &Loaded, levels: [bool; 3]) -> [SmRegs; 3] {
    [
        counter(p, block::PINS, pins::INT, pins::INT, levels[0]),
        counter(p, block::PINS, pins::HOLD, pins::HOLD, levels[1]),
        counter(p, block::PINS, pins::AUX, pins::AUX, levels[2]),
    ]
}

/// Where each edge counter runs: (block, state machine).
pub const fn counter_sm(c: Counter) -> (usize, usize) {
    match c {
        Counter::Pout => (block::POUT, 0),
        Counter::Int => (block::PINS, 0),
        Counter::Hold => (block::PINS, 1),
        Counter::Aux => (block::PINS, 2),
    }
}

/// The state machines of each block that are edge counters, as a mask.
pub const COUNTERS: [u32; 3] = [0, 0b0001, 0b0111];

/// The CTRL value that restarts (SM_RESTART) the counters of block `b`,
/// leaving every state machine of it disabled.
pub const fn restart_counters(b: usize) -> u32 {
    COUNTERS[b] << ctrl::SM_RESTART
}

/// The CTRL value written to the POUT block (PIO1) that enables its SM0
/// and, in the same write, SM0-2 of the next block (PIO2): the four
/// counters start on one clock cycle, one timebase.
pub const START_COUNTERS: u32 = COUNTERS[block::POUT] << ctrl::SM_ENABLE
    | COUNTERS[block::POUT] << ctrl::CLKDIV_RESTART
    | COUNTERS[block::PINS] << ctrl::NEXT_PIO_MASK
    | 1 << ctrl::NEXTPREV_SM_ENABLE
    | 1 << ctrl::NEXTPREV_CLKDIV_RESTART;

/// The CTRL value written to PIO1 that stops the four counters at once.
pub const STOP_COUNTERS: u32 =
    COUNTERS[block::PINS] << ctrl::NEXT_PIO_MASK | 1 << ctrl::NEXTPREV_SM_DISABLE;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_pin_field_is_relative_to_its_blocks_window() {
        // The JMP pin of the POUT counter is GPIO 32, index 16 of PIO1's
        // window (GPIOBASE 16); embassy-rp would have written 0 (GPIO 16).
        let pout = pout_counter(&programs::edge_counter(true), false);
        assert_eq!(pout.execctrl >> execctrl::JMP_PIN & 0x1F, 16);
        assert_eq!(pout.pinctrl >> pinctrl::IN_BASE & 0x1F, 17, "DIR, GPIO 33");
        let [int, hold, aux] = pin_counters(&programs::edge_counter(false), [true; 3]);
        for (regs, gpio) in [(int, pins::INT), (hold, pins::HOLD), (aux, pins::AUX)] {
            assert_eq!(regs.execctrl >> execctrl::JMP_PIN & 0x1F, gpio - 16);
            assert_eq!(regs.pinctrl >> pinctrl::IN_BASE & 0x1F, gpio - 16);
        }
        assert_eq!(
            in_window(12, 16),
            Err(OutsideWindow {
                gpio: 12,
                gpiobase: 16
            })
        );
        assert_eq!(in_window(47, 16), Ok(31));
    }

    #[test]
    fn field_positions_are_the_svds() {
        // rp-pac is generated from Raspberry Pi's SVD for the RP2350: our
        // positions read back through its accessors.
        use rp_pac::pio::regs::{Ctrl, Fdebug, SmExecctrl, SmPinctrl, SmShiftctrl};
        let rising = programs::edge_counter(true);
        let pout = pout_counter(&rising, false);
        let e = SmExecctrl(pout.execctrl);
        assert_eq!(
            (e.jmp_pin(), e.wrap_top(), e.wrap_bottom()),
            (16, rising.wrap_top, rising.wrap_bottom)
        );
        let s = SmShiftctrl(pout.shiftctrl);
        assert!(s.fjoin_rx() && !s.fjoin_tx() && !s.autopush() && !s.in_shiftdir());
        assert_eq!((s.in_count(), s.push_thresh()), (1, 0));
        let player = bus_player(&programs::bus_player());
        let s = SmShiftctrl(player.shiftctrl);
        assert!(s.out_shiftdir() && !s.in_shiftdir() && !s.fjoin_rx() && !s.fjoin_tx());
        let p = SmPinctrl(player.pinctrl);
        assert_eq!((p.out_base(), p.out_count(), p.in_base()), (0, 13, 0));
        assert_eq!((p.sideset_base(), p.sideset_count()), (8, 5), "A0..WR*");
        let e = SmExecctrl(player.execctrl);
        assert!(e.side_pindir() && !e.side_en());
        let p = SmPinctrl(pout.pinctrl);
        assert_eq!(p.in_base(), 17);
        let c = Ctrl(START_COUNTERS);
        assert_eq!((c.sm_enable(), c.next_pio_mask()), (1, 0b0111));
        assert!(c.nextprev_sm_enable() && c.nextprev_clkdiv_restart());
        let c = Ctrl(STOP_COUNTERS);
        assert!(c.nextprev_sm_disable() && c.sm_enable() == 0);
        let mut f = Fdebug(0);
        f.set_txover(1 << 2);
        f.set_rxstall(1 << 1);
        assert_eq!(f.0, 1 << (fdebug::TXOVER + 2) | 1 << (fdebug::RXSTALL + 1));
    }
}

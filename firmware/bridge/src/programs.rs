//! The PIO programs of the RP2350 bridge, assembled by the `pio` crate at
//! compile time, and where each is loaded.
//!
//! Each PIO block holds 32 instruction words, shared by every program
//! loaded into it (RP2350 datasheet, PIO chapter). The bridge gives each
//! program a block of its own, at address 0, so that the addresses the
//! assembler computed are the ones that run:
//!
//! | block | program | words | state machines |
//! |---|---|---|---|
//! | PIO0 | [`bus_player`] | 9 | SM0 |
//! | PIO0, at 9 | [`test_gen`]: the self-test's pulses on TEST_GEN | 12 | SM1 |
//! | PIO1 | [`edge_counter`]`(true)`: POUT's rising edges with DIR | 11 | SM0 |
//! | PIO2 | [`edge_counter`]`(false)`: both edges | 21 | SM0-2 (INT*, HOLD, AUX*) |
//!
//! (Until issue 28 both counters shared PIO1: 13 + 23 words, which
//! embassy-rp's `load_program` refuses with a panic at boot.)

use pio::{
    Assembler, InSource, JmpCondition, MovDestination, MovOperation, MovSource, OutDestination,
    Program, SetDestination, SideSet,
};

/// Instructions a PIO block holds.
pub const SIZE: usize = 32;

/// A program as loaded at address 0 of its block: its words, its wrap, and
/// the addresses a state machine may start at.
#[derive(Debug)]
pub struct Loaded {
    pub program: Program<SIZE>,
    pub wrap_top: u8,
    pub wrap_bottom: u8,
    /// Where to start: for the bus player, its `pull`; for an edge
    /// counter, its loop for a pin that reads high.
    pub start: u8,
    /// For an edge counter, its loop for a pin that reads low.
    pub start_low: u8,
    /// The side-set value every instruction of the program carries, when
    /// it has a side-set: instructions the CPU forces must carry it too.
    pub side: Option<u8>,
}

impl Loaded {
    fn new(program: Program<SIZE>, start: u8, start_low: u8, side: Option<u8>) -> Loaded {
        Loaded {
            wrap_top: program.wrap.source,
            wrap_bottom: program.wrap.target,
            program,
            start,
            start_low,
            side,
        }
    }

    /// The words loaded, from address 0.
    pub fn words(&self) -> &[u16] {
        &self.program.code
    }
}

/// The bus cycle player (PIO0, SM0).
///
/// Each word from the TX FIFO is one *step* ([`crate::bus_cycle::Steps`]): the
/// directions of D0-D7, then the levels of D0-D7, A0, CS*, DIR (of the
/// level shifter), RD* and WR* (the 13 OUT pins, GPIO 0-12), then whether
/// to sample D0-D7 at the end of the step, then how long the step lasts:
/// `x + 7` cycles, `x + 9` with a sample ([`crate::bus_cycle::STEP_CYCLES`]).
/// A sampled byte goes to the RX FIFO. Between cycles the machine waits at
/// `pull` with the pins as the last step left them.
///
/// Its configuration is [`crate::pioregs::bus_player`]. The FIFOs are not
/// joined (the RX FIFO takes the bytes read), so the TX FIFO holds 4
/// steps: the firmware pushes a step only when the FIFO has room
/// ([`crate::board`]).
///
/// `out pindirs, 8` writes all 13 OUT pins' directions: the 8 bits shifted
/// out, and zeroes above them (RP2350 datasheet 11.4.5.2, "the remainder
/// are zeroes", and 11.5.6, the mapping "continues for PINCTRL_OUT_COUNT
/// bits"). Alone it would leave A0, CS*, DIR, RD* and WR* undriven from
/// the first step on (until issue 28 it did; pioemu showed it). So every
/// instruction side-sets those five pins' directions to driven
/// ([`PLAYER_SIDE`], side-set to PINDIRS at A0): a side-set takes
/// precedence over an OUT to the same pins on the same cycle (11.5.6), and
/// takes effect even while `pull` stalls. It costs no cycle; the price is
/// the delay field, which side-set takes whole (the program uses none).
pub fn bus_player() -> Loaded {
    let s = PLAYER_SIDE;
    let mut a = Assembler::<SIZE>::new_with_side_set(SideSet::new(false, 5, true));
    let (mut wrap_target, mut wrap_source) = (a.label(), a.label());
    let (mut step, mut hold) = (a.label(), a.label());
    a.bind(&mut wrap_target);
    a.bind(&mut step);
    a.pull_with_side_set(false, true, s);
    a.out_with_side_set(OutDestination::PINDIRS, 8, s);
    a.out_with_side_set(OutDestination::PINS, 13, s);
    a.out_with_side_set(OutDestination::Y, 1, s);
    a.out_with_side_set(OutDestination::X, 10, s);
    a.bind(&mut hold);
    a.jmp_with_side_set(JmpCondition::XDecNonZero, &mut hold, s);
    a.jmp_with_side_set(JmpCondition::YIsZero, &mut step, s);
    a.in_with_side_set(InSource::PINS, 8, s);
    a.push_with_side_set(false, true, s);
    a.bind(&mut wrap_source);
    Loaded::new(
        a.assemble_with_wrap(wrap_source, wrap_target),
        0,
        0,
        Some(PLAYER_SIDE),
    )
}

/// The bus player's side-set: A0, CS*, DIR, RD* and WR* driven.
pub const PLAYER_SIDE: u8 = 0b11111;

/// An edge counter on the JMP pin.
///
/// X counts down once every two cycles, on every path through the program,
/// from all ones (the firmware sets it before starting), so that
/// [`crate::timebase`] can turn a pushed count into time. A rising edge
/// pushes `bit << 31 | (X & 0x7FFF_FFFF)`:
///
/// - `rising_only` (POUT): rising edges only, `bit` being the IN pin (DIR)
///   sampled at the edge;
/// - otherwise both edges, `bit` being the level after the change.
///
/// Every `jmp x--` goes where it would go if X were not zero: its target
/// is the next instruction, or the wrap takes it there. At X = 0 a
/// `jmp x--` does not jump, and a program that fell through into its edge
/// code there would push an edge that never happened, once every 2^32
/// ticks (57.3 s at 75 MHz; until issue 28 this one did).
///
/// A DMA channel moves each pushed word into a ring in RAM the cycle
/// after ([`crate::ring`]), so the RX FIFO (8 words, joined) does not fill
/// and `push block` does not stall; should it ever (the DMA held off the
/// bus), the firmware sees the stall in FDEBUG.RXSTALL, reports the
/// capture lost, and restarts the counters, as it does for a ring the DMA
/// came round on before the CPU read it.
///
/// After an edge a program runs its push path before it looks at the pin
/// again: a change that comes sooner is not seen, and nothing says so.
/// On the twin, POUT's counter sees pulses and gaps of 8 cycles; the
/// both-edge counter misses changes 8 cycles apart and sees them 18
/// apart (`changes_shorter_than_the_both_edge_counters_path_are_missed_and_the_selftests_are_not`).
/// The chip's outputs change microseconds apart; `ppmc selftest` makes no
/// level shorter than 18 cycles.
pub fn edge_counter(rising_only: bool) -> Loaded {
    let mut a = Assembler::<SIZE>::new();
    let (mut wrap_target, mut wrap_source) = (a.label(), a.label());
    let (mut rise, mut still_high, mut high, mut low) =
        (a.label(), a.label(), a.label(), a.label());
    a.bind(&mut rise);
    jmp_x_next(&mut a);
    push_edge(&mut a, (!rising_only).then_some(1));
    a.bind(&mut still_high);
    a.jmp(JmpCondition::XDecNonZero, &mut high);
    a.bind(&mut high);
    a.jmp(JmpCondition::PinHigh, &mut still_high);
    if rising_only {
        a.jmp(JmpCondition::XDecNonZero, &mut low);
    } else {
        let mut fall = a.label();
        a.jmp(JmpCondition::XDecNonZero, &mut fall);
        a.bind(&mut fall);
        push_edge(&mut a, Some(0));
        a.jmp(JmpCondition::XDecNonZero, &mut low);
    }
    a.bind(&mut wrap_target);
    a.bind(&mut low);
    a.jmp(JmpCondition::PinHigh, &mut rise);
    a.jmp(JmpCondition::XDecNonZero, &mut low);
    a.bind(&mut wrap_source);
    let (h, l) = (a.label_offset(&high), a.label_offset(&low));
    Loaded::new(a.assemble_with_wrap(wrap_source, wrap_target), h, l, None)
}

/// `jmp x-- next`: X counts down, and the next instruction runs either way.
pub(crate) fn jmp_x_next(a: &mut Assembler<SIZE>) {
    let mut l = a.label();
    a.jmp(JmpCondition::XDecNonZero, &mut l);
    a.bind(&mut l);
}

/// An edge counter's push path: its bit (`level` into the ISR through Y,
/// or the IN pin when `None`), then X's low 31 bits, then `push block`,
/// X counting down on the way as on every path.
pub(crate) fn push_edge(a: &mut Assembler<SIZE>, level: Option<u8>) {
    match level {
        Some(v) => {
            a.set(SetDestination::Y, v);
            jmp_x_next(a);
            a.r#in(InSource::Y, 1);
        }
        None => a.r#in(InSource::PINS, 1),
    }
    jmp_x_next(a);
    a.r#in(InSource::X, 31);
    jmp_x_next(a);
    a.push(false, true);
}

/// What each PIO block is loaded with, in block order, at address 0. PIO0
/// also holds [`test_gen`], at [`test_gen_origin`].
pub fn layout() -> [Loaded; 3] {
    [bus_player(), edge_counter(true), edge_counter(false)]
}

/// The self-test generator (PIO0, SM1): `count` pulses on TEST_GEN, each
/// high for `high` cycles and low for `low`, from three TX FIFO words
/// ([`test_gen_words`]); then it waits at its first `pull` for the next
/// burst, the pin low.
///
/// From the cycle it is enabled with the three words in its FIFO, its
/// first `set pins, 1` runs on cycle [`TEST_GEN_LEAD`] - 1, so the pin is
/// high from cycle [`TEST_GEN_LEAD`] on; each pulse is `high` cycles high
/// (`set`, `mov`, X + 1 times `jmp x--`) and `low` low (the same, and the
/// `jmp y--`), whatever the count: the board code predicts every edge
/// from the cycle it enabled the machine on.
///
/// Assembled for address 0; [`test_gen_origin`] relocates it.
pub fn test_gen() -> Loaded {
    let mut a = Assembler::<SIZE>::new();
    let (mut wrap_target, mut wrap_source) = (a.label(), a.label());
    let (mut pulse, mut high, mut low) = (a.label(), a.label(), a.label());
    a.bind(&mut wrap_target);
    a.pull(false, true);
    a.out(OutDestination::Y, 32);
    a.pull(false, true);
    a.mov(MovDestination::ISR, MovOperation::None, MovSource::OSR);
    a.pull(false, true);
    a.bind(&mut pulse);
    a.set(SetDestination::PINS, 1);
    a.mov(MovDestination::X, MovOperation::None, MovSource::OSR);
    a.bind(&mut high);
    a.jmp(JmpCondition::XDecNonZero, &mut high);
    a.set(SetDestination::PINS, 0);
    a.mov(MovDestination::X, MovOperation::None, MovSource::ISR);
    a.bind(&mut low);
    a.jmp(JmpCondition::XDecNonZero, &mut low);
    a.jmp(JmpCondition::YDecNonZero, &mut pulse);
    a.bind(&mut wrap_source);
    Loaded::new(a.assemble_with_wrap(wrap_source, wrap_target), 0, 0, None)
}

/// Cycles from enabling [`test_gen`] to its pin's first rise.
pub const TEST_GEN_LEAD: u64 = 6;

/// The shortest high and low times [`test_gen`] makes (cycles).
pub const TEST_GEN_MIN: (u64, u64) = (3, 4);

/// The three TX FIFO words of a burst of `count` pulses, `high` and `low`
/// cycles each; `None` if [`test_gen`] cannot make them (count 0, times
/// under [`TEST_GEN_MIN`] or over 2^32 cycles).
pub fn test_gen_words(count: u32, high: u64, low: u64) -> Option<[u32; 3]> {
    let n = count.checked_sub(1)?;
    let h = u32::try_from(high.checked_sub(TEST_GEN_MIN.0)?).ok()?;
    let l = u32::try_from(low.checked_sub(TEST_GEN_MIN.1)?).ok()?;
    Some([n, l, h])
}

/// Where [`test_gen`] is loaded in PIO0: after the bus player.
pub fn test_gen_origin() -> u8 {
    bus_player().words().len() as u8
}

/// `p`, assembled for address 0, relocated to `origin`: its jumps' targets, its wrap and its start
/// addresses moved by `origin`, as embassy-rp's `load_program` relocates.
pub fn relocate(p: Loaded, origin: u8) -> Loaded {
    let mut program = p.program;
    for w in program.code.iter_mut() {
        // JMP: opcode 000 in bits 15-13, the address in bits 4-0.
        if *w >> 13 == 0 {
            *w = (*w & !0x1F) | ((*w & 0x1F) + u16::from(origin)) & 0x1F;
        }
    }
    program.origin = Some(origin);
    Loaded {
        program,
        wrap_top: p.wrap_top + origin,
        wrap_bottom: p.wrap_bottom + origin,
        start: p.start + origin,
        start_low: p.start_low + origin,
        side: p.side,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bus_cycle::{BusTiming, Cycle, IDLE};
    use crate::pioregs;
    use crate::twin::pio::{Inputs, World};
    use std::vec::Vec;

    /// The output enables of A0, CS*, DIR, RD* and WR* on each cycle of a
    /// write and a read played by `p`, configured and fed as the firmware
    /// does it.
    fn control_enables(p: &Loaded) -> Vec<u32> {
        let mut w = World::with_program(0, 0, p.words(), 0, &pioregs::bus_player(p));
        let all = (1u64 << 13) - 1;
        w.blocks[0].force_pins(all, u64::from(IDLE), all);
        let mut steps: std::collections::VecDeque<u32> =
            [Cycle::Write { a0: true, byte: 1 }, Cycle::Read { a0: true }]
                .iter()
                .flat_map(|c| {
                    let s = BusTiming::DEFAULT.steps(*c, 150_000_000).expect("fits");
                    s.words().to_vec()
                })
                .collect();
        let mut outside = Inputs(|_, _, _| (0, 0xFF));
        let mut enables = Vec::new();
        while !(steps.is_empty() && w.blocks[0].tx_empty(0) && w.blocks[0].sm[0].stalled) {
            if !w.blocks[0].tx_full(0) {
                if let Some(s) = steps.pop_front() {
                    w.blocks[0].txf_write(0, s);
                }
            }
            w.step(&mut outside);
            enables.push((w.driven().1 >> 8 & 0x1F) as u32);
        }
        enables
    }

    #[test]
    fn relocating_moves_the_jumps_wrap_and_start_and_nothing_else() {
        let at0 = test_gen();
        let moved = relocate(test_gen(), 9);
        assert_eq!(at0.words().len(), moved.words().len());
        let mut jumps = 0;
        for (a, b) in at0.words().iter().zip(moved.words()) {
            if a >> 13 == 0 {
                jumps += 1;
                assert_eq!((a & !0x1F, (a & 0x1F) + 9), (b & !0x1F, b & 0x1F));
            } else {
                assert_eq!(a, b);
            }
        }
        assert_eq!(jumps, 3, "jmp x-- high, jmp x-- low, jmp y-- pulse");
        assert_eq!(
            (moved.wrap_top, moved.wrap_bottom, moved.start),
            (at0.wrap_top + 9, at0.wrap_bottom + 9, 9)
        );
    }

    #[test]
    fn the_generator_makes_each_pulse_as_asked_from_its_lead_on() {
        // Two bursts, counted cycle by cycle on the PIO model at its origin
        // in PIO0: rises at TEST_GEN_LEAD + k x (high + low), each high
        // for `high` cycles.
        use crate::pins;
        let origin = test_gen_origin();
        let gen = relocate(test_gen(), origin);
        let regs = pioregs::test_gen(&gen);
        let mut w = World::new();
        w.blocks[0].load(gen.words(), origin).expect("fits");
        w.blocks[0].configure(1, &regs).expect("modelled");
        for g in 0..48 {
            w.func[g] = crate::twin::pio::Func::Pio(0);
        }
        let mut outside = Inputs(|_, _, _| (0, 0));
        w.blocks[0].exec(1, pioregs::force_set(true, 1), 0);
        for (count, high, low) in [(3u32, 3u64, 4u64), (5, 10, 12)] {
            let words = test_gen_words(count, high, low).expect("makeable");
            for word in words {
                w.blocks[0].txf_write(1, word);
            }
            w.write_ctrl(0, pioregs::TEST_GEN_RUN);
            let enabled = w.cycle;
            let mut rises = Vec::new();
            let mut last = false;
            let mut high_for = Vec::new();
            let mut since = 0;
            for _ in 0..(TEST_GEN_LEAD + u64::from(count) * (high + low) + 20) {
                w.step(&mut outside);
                let level = w.pads() >> pins::TEST_GEN & 1 == 1;
                if level && !last {
                    rises.push(w.cycle - enabled);
                    since = w.cycle;
                }
                if !level && last {
                    high_for.push(w.cycle - since);
                }
                last = level;
            }
            let want: Vec<u64> = (0..u64::from(count))
                .map(|k| TEST_GEN_LEAD + k * (high + low))
                .collect();
            assert_eq!(rises, want, "{count} pulses of {high} + {low} cycles");
            assert!(high_for.iter().all(|h| *h == high), "{high_for:?}");
            w.write_ctrl(0, pioregs::TEST_GEN_STOP);
        }
        assert_eq!(test_gen_words(1, 2, 4), None, "high under 3 cycles");
        assert_eq!(test_gen_words(0, 3, 4), None, "no pulse");
    }

    #[test]
    fn defect_out_pindirs_released_the_strobes_and_the_side_set_keeps_them_driven() {
        // The player until issue 28: `out pindirs, 8` writes zeroes to the
        // directions of the five OUT pins above D0-D7 (RP2350 datasheet
        // 11.4.5.2, 11.5.6), which nothing set again.
        let old = {
            let mut a = Assembler::<SIZE>::new();
            let (mut wrap_target, mut wrap_source) = (a.label(), a.label());
            let (mut step, mut hold) = (a.label(), a.label());
            a.bind(&mut wrap_target);
            a.bind(&mut step);
            a.pull(false, true);
            a.out(OutDestination::PINDIRS, 8);
            a.out(OutDestination::PINS, 13);
            a.out(OutDestination::Y, 1);
            a.out(OutDestination::X, 10);
            a.bind(&mut hold);
            a.jmp(JmpCondition::XDecNonZero, &mut hold);
            a.jmp(JmpCondition::YIsZero, &mut step);
            a.r#in(InSource::PINS, 8);
            a.push(false, true);
            a.bind(&mut wrap_source);
            a.assemble_with_wrap(wrap_source, wrap_target)
        };
        let old = control_enables(&Loaded::new(old, 0, 0, None));
        assert_eq!(old[0], 0b11111, "driven until the first `out pindirs`");
        assert!(
            old[1..].iter().all(|e| *e == 0),
            "A0..WR* undriven from then on"
        );
        let ours = control_enables(&bus_player());
        assert!(ours.len() > 100);
        assert!(
            ours.iter().all(|e| *e == 0b11111),
            "A0..WR* driven on every cycle"
        );
    }
}

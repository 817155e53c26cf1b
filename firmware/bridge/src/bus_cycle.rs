//! Bus cycles as steps for [`crate::programs::bus_player`].
//!
//! The chip's bus (Section 3-1): D0-D7, A0 (high: command register on a
//! write, status on a read; low: data register), CS*, RD*, WR*, behind a
//! 74LVC8T245 level shifter whose DIR pin the bridge drives (high: bridge
//! to chip). A cycle is a few steps, each a state of all those pins held
//! for a number of system clock cycles:
//!
//! | cycle | steps |
//! |---|---|
//! | write | setup (CS*, A0, data, DIR towards the chip) - strobe (WR* low) - hold (WR* high, data kept) - idle (CS* high) |
//! | read | setup (data lines in, DIR towards the bridge, CS*, A0) - strobe (RD* low, sampled at its end) - hold (RD* and CS* high, the chip lets go of the bus) - turn (DIR towards the chip, lines still in) - idle (lines out) |
//!
//! so that the bridge never drives the shifter while the shifter drives
//! the bridge, and the shifter never drives the chip's bus while the chip
//! does. The tests play every cycle on the twin's PIO model and check that, and
//! the times, cycle by cycle.

/// Bit positions of the bus pins in a step's pin field (and their GPIO
/// numbers: the OUT pins are GPIO 0-12).
pub mod pin {
    pub const D0: u32 = 0;
    pub const A0: u32 = 8;
    pub const CS: u32 = 9;
    pub const DIR: u32 = 10;
    pub const RD: u32 = 11;
    pub const WR: u32 = 12;
    /// OUT pins, from GPIO 0.
    pub const COUNT: u32 = 13;
}

/// Cycles a step lasts beyond its count: `x + STEP_CYCLES`, or
/// `x + STEP_CYCLES_SAMPLED` for a step that samples D0-D7.
pub const STEP_CYCLES: u32 = 7;
pub const STEP_CYCLES_SAMPLED: u32 = 9;
/// Cycles from the start of a sampling step to the sample.
pub const SAMPLE_AT: u32 = 5;
/// The largest count a step holds (10 bits).
pub const MAX_COUNT: u32 = 1023;

/// Bus timing, in nanoseconds. The datasheet's bus-timing chapter is not
/// in our hands (docs/datasheet-notes.md N46): the defaults are
/// deliberately slow for an 8-bit bus peripheral of the chip's kind, and a
/// board can set its own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BusTiming {
    /// CS*, A0 (and, on a write, the data) before the strobe falls.
    pub setup_ns: u32,
    /// RD* or WR* low. A read samples the data lines
    /// `STEP_CYCLES_SAMPLED - SAMPLE_AT` cycles before RD* rises.
    pub strobe_ns: u32,
    /// After the strobe rises: data, A0 and CS* kept on a write; on a read,
    /// the time the chip has to let go of the bus before the shifter turns.
    pub hold_ns: u32,
    /// Bus idle between two cycles.
    pub recovery_ns: u32,
}

impl BusTiming {
    /// The defaults: 100 ns setup, 400 ns strobe, 100 ns hold, 200 ns
    /// between cycles.
    pub const DEFAULT: BusTiming = BusTiming {
        setup_ns: 100,
        strobe_ns: 400,
        hold_ns: 100,
        recovery_ns: 200,
    };

    /// Whether every cycle fits the player at `sysclk_hz`.
    pub fn fits(&self, sysclk_hz: u32) -> bool {
        [Cycle::Write { a0: true, byte: 0 }, Cycle::Read { a0: true }]
            .into_iter()
            .all(|c| self.steps(c, sysclk_hz).is_ok())
    }
}

impl Default for BusTiming {
    fn default() -> Self {
        BusTiming::DEFAULT
    }
}

/// One bus cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cycle {
    /// Write `byte`: to the command register with `a0`, else the data
    /// register.
    Write { a0: bool, byte: u8 },
    /// Read the status register with `a0`, else the data register.
    Read { a0: bool },
}

/// A time the player cannot hold in one step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TooLong {
    pub ns: u32,
    pub max_ns: u64,
}

/// The steps of a cycle, as TX FIFO words, at most [`Steps::MAX`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Steps {
    words: [u32; Steps::MAX],
    len: usize,
}

impl Steps {
    pub const MAX: usize = 5;

    pub fn words(&self) -> &[u32] {
        &self.words[..self.len]
    }

    fn push(&mut self, w: u32) {
        self.words[self.len] = w;
        self.len += 1;
    }
}

/// Cycles from a step's `pull` to the cycle its pins show: `pull`,
/// `out pindirs`, `out pins`.
pub const PINS_AT: u32 = 2;

/// How many system clock cycles the step `word` lasts, from its `pull` to
/// the next: `x + 7`, or `x + 9` when it samples.
pub fn step_cycles(word: u32) -> u32 {
    let sampled = word >> 21 & 1 == 1;
    (word >> 22 & MAX_COUNT)
        + if sampled {
            STEP_CYCLES_SAMPLED
        } else {
            STEP_CYCLES
        }
}

impl Cycle {
    /// The step whose pins make the cycle's moment: for a write, the hold
    /// step, on whose first cycle WR* rises and the chip takes the byte;
    /// for a read, the strobe step, on whose first cycle RD* falls and the
    /// chip answers (Section 3-1).
    pub fn moment_step(self) -> usize {
        match self {
            Cycle::Write { .. } => 2,
            Cycle::Read { .. } => 1,
        }
    }
}

/// The counts of a bus cycle's steps ([`BusTiming::counts`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepCounts {
    setup: u32,
    strobe: u32,
    strobe_sampled: u32,
    hold: u32,
    recovery: u32,
}

impl StepCounts {
    /// The steps of `cycle`.
    pub fn steps(&self, cycle: Cycle) -> Steps {
        let mut s = Steps {
            words: [0; Steps::MAX],
            len: 0,
        };
        let a0 = |a: bool| u32::from(a) << pin::A0;
        match cycle {
            Cycle::Write { a0: a, byte } => {
                let on = a0(a) | 1 << pin::DIR | 1 << pin::RD | 1 << pin::WR | u32::from(byte);
                s.push(step(0xFF, on, false, self.setup));
                s.push(step(0xFF, on & !(1 << pin::WR), false, self.strobe));
                s.push(step(0xFF, on, false, self.hold));
                s.push(step(0xFF, IDLE, false, self.recovery));
            }
            Cycle::Read { a0: a } => {
                let on = a0(a) | 1 << pin::RD | 1 << pin::WR; // DIR low: towards the bridge
                s.push(step(0x00, on, false, self.setup));
                s.push(step(0x00, on & !(1 << pin::RD), true, self.strobe_sampled));
                s.push(step(0x00, on | 1 << pin::CS, false, self.hold));
                s.push(step(0x00, IDLE, false, 0));
                s.push(step(0xFF, IDLE, false, self.recovery));
            }
        }
        s
    }
}

/// One step's word: D0-D7 directions (1 = driven), the 13 pin levels,
/// sample, count.
pub const fn step(dirs: u8, pins: u32, sample: bool, count: u32) -> u32 {
    dirs as u32 | (pins & 0x1FFF) << 8 | (sample as u32) << 21 | (count & MAX_COUNT) << 22
}

/// The idle bus: strobes and CS* high, shifter towards the chip, D0-D7
/// driven low.
pub const IDLE: u32 = 1 << pin::CS | 1 << pin::DIR | 1 << pin::RD | 1 << pin::WR;

impl BusTiming {
    /// The count that makes a step last at least `ns` at `sysclk_hz`.
    fn count(&self, ns: u32, sysclk_hz: u32, fixed: u32) -> Result<u32, TooLong> {
        let cycles = (u64::from(ns) * u64::from(sysclk_hz)).div_ceil(1_000_000_000);
        let count = cycles.saturating_sub(u64::from(fixed));
        if count > u64::from(MAX_COUNT) {
            return Err(TooLong {
                ns,
                max_ns: u64::from(MAX_COUNT + fixed) * 1_000_000_000 / u64::from(sysclk_hz.max(1)),
            });
        }
        Ok(count as u32)
    }

    /// The steps of `cycle` at a system clock of `sysclk_hz`.
    pub fn steps(&self, cycle: Cycle, sysclk_hz: u32) -> Result<Steps, TooLong> {
        Ok(self.counts(sysclk_hz)?.steps(cycle))
    }

    /// Each step's count at a system clock of `sysclk_hz`, worked out once:
    /// the board code plays a cycle in every op, and each count is a
    /// 64-bit division (some 240 cycles of a Cortex-M33).
    pub fn counts(&self, sysclk_hz: u32) -> Result<StepCounts, TooLong> {
        let n = |ns| self.count(ns, sysclk_hz, STEP_CYCLES);
        Ok(StepCounts {
            setup: n(self.setup_ns)?,
            strobe: n(self.strobe_ns)?,
            strobe_sampled: self.count(self.strobe_ns, sysclk_hz, STEP_CYCLES_SAMPLED)?,
            hold: n(self.hold_ns)?,
            recovery: self.recovery(sysclk_hz)?,
        })
    }

    /// The idle step's count: the next cycle changes the data lines'
    /// directions a cycle before its pins, so the idle lasts until then.
    fn recovery(&self, sysclk_hz: u32) -> Result<u32, TooLong> {
        self.count(self.recovery_ns, sysclk_hz, STEP_CYCLES - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pioregs;
    use crate::programs::bus_player;
    use crate::twin::pio::{Inputs, World};
    use std::vec::Vec;
    extern crate std;

    /// Cycle by cycle: (levels, dirs) of the OUT pins while `cycle` plays,
    /// the chip driving `chip_byte` whenever RD* and CS* are low; and the
    /// byte the machine pushed.
    fn play(
        t: &BusTiming,
        cycle: Cycle,
        sysclk: u32,
        chip_byte: u8,
    ) -> (Vec<(u64, u64)>, Option<u32>) {
        play_all(t, &[cycle], sysclk, chip_byte)
    }

    /// The bus player on the RP2350 PIO model, as the firmware configures
    /// it, fed as the board code feeds it: a step whenever the TX FIFO (4
    /// deep) has room.
    fn play_all(
        t: &BusTiming,
        cycles: &[Cycle],
        sysclk: u32,
        chip_byte: u8,
    ) -> (Vec<(u64, u64)>, Option<u32>) {
        let program = bus_player();
        let mut w = World::with_program(0, 0, program.words(), 0, &pioregs::bus_player(&program));
        let all = (1u64 << pin::COUNT) - 1;
        w.blocks[0].force_pins(all, u64::from(IDLE), all);
        let mut steps: std::collections::VecDeque<u32> = cycles
            .iter()
            .flat_map(|c| t.steps(*c, sysclk).expect("fits").words().to_vec())
            .collect();
        let mut chip = Inputs(|_, out: u64, _| {
            let chip_drives = out >> pin::RD & 1 == 0 && out >> pin::CS & 1 == 0;
            (if chip_drives { u64::from(chip_byte) } else { 0 }, 0xFF)
        });
        let mut wave = Vec::new();
        let mut byte = None;
        // Until the machine waits for the next cycle at `pull`.
        for _ in 0..100_000 {
            if !w.blocks[0].tx_full(0) {
                if let Some(s) = steps.pop_front() {
                    w.blocks[0].txf_write(0, s);
                }
            }
            w.step(&mut chip);
            let (out, oe) = w.driven();
            wave.push((out & all, oe & all));
            byte = byte.or_else(|| w.pull(0, 0));
            if w.blocks[0].sm[0].stalled && steps.is_empty() && w.blocks[0].tx_empty(0) {
                break;
            }
        }
        assert_eq!(
            w.blocks[0].fdebug() >> crate::pioregs::fdebug::TXOVER & 1,
            0,
            "no step lost"
        );
        (wave, byte)
    }

    fn bit(v: u64, b: u32) -> bool {
        v >> b & 1 == 1
    }

    /// The length of the run of cycles, from the first on which `cond`
    /// holds, for which it holds.
    fn run_of(wave: &[(u64, u64)], cond: impl Fn(u64, u64) -> bool) -> (usize, usize) {
        let start = wave.iter().position(|&(l, d)| cond(l, d)).expect("happens");
        let len = wave[start..]
            .iter()
            .take_while(|&&(l, d)| cond(l, d))
            .count();
        (start, len)
    }

    fn cycles(ns: u32, sysclk: u32) -> usize {
        (u64::from(ns) * u64::from(sysclk)).div_ceil(1_000_000_000) as usize
    }

    /// The rules of the bus and the shifter, on every cycle of a play.
    fn safe(wave: &[(u64, u64)]) {
        for (i, &(l, d)) in wave.iter().enumerate() {
            let towards_chip = bit(l, pin::DIR);
            let bridge_drives = d & 0xFF != 0;
            let chip_drives = !bit(l, pin::RD) && !bit(l, pin::CS);
            // The bridge drives its side only with the shifter pointing
            // away from it.
            assert!(
                !bridge_drives || towards_chip,
                "cycle {i}: both drive the bridge side"
            );
            assert!(
                !(chip_drives && towards_chip),
                "cycle {i}: both drive the chip's bus"
            );
            assert!(
                bit(l, pin::RD) || bit(l, pin::WR),
                "cycle {i}: RD* and WR* both low"
            );
        }
    }

    #[test]
    fn a_write_meets_its_times_and_keeps_the_bus_safe() {
        for sysclk in [125_000_000, 150_000_000, 200_000_000] {
            for t in [
                BusTiming::default(),
                BusTiming {
                    setup_ns: 0,
                    strobe_ns: 60,
                    hold_ns: 0,
                    recovery_ns: 0,
                },
                BusTiming {
                    setup_ns: 1_000,
                    strobe_ns: 2_000,
                    hold_ns: 500,
                    recovery_ns: 3_000,
                },
            ] {
                let (wave, pushed) = play(
                    &t,
                    Cycle::Write {
                        a0: true,
                        byte: 0xA5,
                    },
                    sysclk,
                    0,
                );
                safe(&wave);
                assert_eq!(pushed, None, "a write pushes nothing");
                let (fall, width) = run_of(&wave, |l, _| !bit(l, pin::WR));
                // Exactly as long as asked (or the player's shortest step).
                assert_eq!(
                    width,
                    cycles(t.strobe_ns, sysclk).max(STEP_CYCLES as usize),
                    "{t:?} at {sysclk}"
                );
                let (cs, _) = run_of(&wave, |l, _| !bit(l, pin::CS));
                assert!(fall - cs >= cycles(t.setup_ns, sysclk), "setup {t:?}");
                // From CS* low to CS* high: A0 high and the byte on D0-D7,
                // driven, all along, and for the hold after WR* rises.
                let (_, selected) = run_of(&wave, |l, _| !bit(l, pin::CS));
                for &(l, d) in &wave[cs..cs + selected] {
                    assert!(bit(l, pin::A0));
                    assert_eq!((l & 0xFF, d & 0xFF), (0xA5, 0xFF));
                }
                assert!(
                    cs + selected - (fall + width) >= cycles(t.hold_ns, sysclk),
                    "hold {t:?}"
                );
                assert_eq!(wave.last().map(|w| w.0 & 0x1FFF), Some(u64::from(IDLE)));
                // Back to back with a read: idle for the recovery time in
                // between, and both cycles safe.
                let (two, byte) = play_all(
                    &t,
                    &[
                        Cycle::Write {
                            a0: true,
                            byte: 0xA5,
                        },
                        Cycle::Read { a0: true },
                    ],
                    sysclk,
                    0x5A,
                );
                safe(&two);
                assert_eq!(byte, Some(0x5A));
                let idle = cs + selected;
                let gap = two[idle..]
                    .iter()
                    .take_while(|w| (w.0 & 0x1FFF, w.1 & 0xFF) == (u64::from(IDLE), 0xFF))
                    .count();
                assert!(
                    gap >= cycles(t.recovery_ns, sysclk),
                    "recovery {t:?}: {gap} cycles"
                );
            }
        }
    }

    #[test]
    fn a_read_samples_the_chip_inside_the_strobe_and_turns_the_shifter_safely() {
        for sysclk in [125_000_000, 150_000_000] {
            for t in [
                BusTiming::default(),
                BusTiming {
                    setup_ns: 0,
                    strobe_ns: 0,
                    hold_ns: 0,
                    recovery_ns: 0,
                },
            ] {
                let (wave, pushed) = play(&t, Cycle::Read { a0: false }, sysclk, 0x3C);
                safe(&wave);
                assert_eq!(pushed, Some(0x3C), "the byte the chip drove");
                let (fall, width) = run_of(&wave, |l, _| !bit(l, pin::RD));
                assert_eq!(
                    width,
                    cycles(t.strobe_ns, sysclk).max(STEP_CYCLES_SAMPLED as usize)
                );
                let (cs, _) = run_of(&wave, |l, _| !bit(l, pin::CS));
                assert!(fall - cs >= cycles(t.setup_ns, sysclk));
                assert!(!bit(wave[fall].0, pin::A0), "A0 low: the data register");
                // The shifter turns back only after the hold.
                let (turn, _) = run_of(&wave[fall + width..], |l, _| bit(l, pin::DIR));
                assert!(turn >= cycles(t.hold_ns, sysclk));
                assert_eq!(
                    wave.last().map(|w| w.1 & 0xFF),
                    Some(0xFF),
                    "lines driven again"
                );
            }
        }
        // A sample only ever sees what the chip drives while RD* is low.
        let (_, none) = play(
            &BusTiming::default(),
            Cycle::Read { a0: true },
            150_000_000,
            0,
        );
        assert_eq!(none, Some(0));
    }

    #[test]
    fn a_time_a_step_cannot_hold_is_refused() {
        let t = BusTiming {
            strobe_ns: 100_000,
            ..BusTiming::default()
        };
        let e = t
            .steps(Cycle::Write { a0: false, byte: 0 }, 150_000_000)
            .expect_err("too long");
        assert_eq!(e.ns, 100_000);
        assert_eq!(e.max_ns, 6_866);
    }
}

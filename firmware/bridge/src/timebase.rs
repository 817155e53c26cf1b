//! The capture's timebase: the edge-capture state machines count down from
//! all ones, one tick every two system clock cycles, and push the low 31
//! bits of their count with each edge ([`crate::programs::edge_counter`]).
//! The firmware turns that into ticks since the timebase started, given a
//! later time it knows (its own clock, read at the same rate): any edge
//! drained within 2^30 ticks (14 s at 75 MHz) of happening is placed
//! exactly.

/// Ticks per second of the capture's timebase at a system clock of
/// `sysclk_hz`: what HELLO_REPLY announces as `timer_hz`.
pub const fn timer_hz(sysclk_hz: u32) -> u64 {
    sysclk_hz as u64 / 2
}

/// One pushed capture word: bit 31 and the tick it happened at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    /// DIR at a POUT edge; the pin's new level for a both-edge capture.
    pub bit: bool,
    /// Ticks since the timebase started.
    pub at: u64,
}

/// Places a pushed word in time, `now` being a tick the firmware knows to
/// be at or after the edge, less than 2^30 ticks later.
pub fn place(word: u32, now: u64) -> Edge {
    const LOW: u64 = (1 << 31) - 1;
    // The count is all ones minus the ticks elapsed: its complement is the
    // ticks, modulo 2^31.
    let ticks_low = u64::from(!word) & LOW;
    let behind = now.wrapping_sub(ticks_low) & LOW;
    Edge {
        bit: word >> 31 == 1,
        at: now - behind.min(now),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pins::{DIR, POUT};
    use crate::pioregs::{self, block};
    use crate::programs::edge_counter;
    use crate::twin::pio::{Inputs, World};
    extern crate std;
    use std::vec::Vec;

    /// A train of pulses with gaps and widths from a small generator: the
    /// input levels for each cycle, and the (cycle, DIR) of each rising
    /// edge.
    fn train(seed: u64, pulses: usize) -> (Vec<u64>, Vec<(u64, bool)>) {
        let mut s = seed;
        let mut next = move |m: u64| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s % m
        };
        let mut levels = Vec::new();
        let mut edges = Vec::new();
        levels.extend(std::iter::repeat_n(0u64, 5 + next(20) as usize));
        for _ in 0..pulses {
            let dir = next(2) == 1;
            let d = u64::from(dir) << DIR;
            edges.push((levels.len() as u64, dir));
            // High for at least 10 cycles, low for at least 10: POUT's
            // pulses are microseconds long, the program needs 8 cycles.
            let high = 10 + next(40) as usize;
            let low = 10 + next(300) as usize;
            levels.extend(std::iter::repeat_n(1 << POUT | d, high));
            levels.extend(std::iter::repeat_n(d, low));
        }
        (levels, edges)
    }

    /// Runs an edge counter, configured as the firmware configures it, on
    /// the RP2350 PIO model, the pins following `levels` cycle by cycle;
    /// what it pushed.
    fn run(rising_only: bool, levels: &[u64]) -> Vec<u32> {
        let program = edge_counter(rising_only);
        let (b, regs) = if rising_only {
            (block::POUT, pioregs::pout_counter(&program, false))
        } else {
            // The INT* counter, here watching POUT's stimulus on its pin.
            (block::PINS, pioregs::pin_counters(&program, [false; 3])[0])
        };
        let pin = if rising_only { POUT } else { crate::pins::INT };
        let mut w = World::with_program(b, 16, program.words(), 0, &regs);
        let mut pushed = Vec::new();
        let mut x_at = Vec::new();
        let mut outside = Inputs(|c: u64, _, _| {
            let l = levels.get(c as usize).copied().unwrap_or(0);
            // POUT's train on the counter's own pin; DIR as given.
            let on = (l >> POUT & 1) << pin | (l & 1 << DIR);
            (on, 1 << pin | 1 << DIR)
        });
        for _ in levels {
            w.step(&mut outside);
            x_at.push(w.blocks[b].sm[0].x());
            while let Some(word) = w.pull(b, 0) {
                pushed.push(word);
            }
        }
        // The counter ticks every second cycle, on every path.
        for (c, win) in x_at.windows(3).enumerate() {
            assert_eq!(
                win[0].wrapping_sub(win[2]),
                1,
                "cycles {c}..{}: one tick per two cycles",
                c + 2
            );
        }
        pushed
    }

    #[test]
    fn pout_edges_are_stamped_to_two_cycles_with_their_direction() {
        for seed in 1..20 {
            let (levels, edges) = train(seed, 200);
            let pushed = run(true, &levels);
            assert_eq!(pushed.len(), edges.len(), "seed {seed}: no edge lost");
            let now = levels.len() as u64 / 2 + 10;
            let placed: Vec<Edge> = pushed.iter().map(|w| place(*w, now)).collect();
            // Each edge at its cycle / 2, up to one tick, plus a constant.
            let offset = placed[0].at as i64 - (edges[0].0 / 2) as i64;
            for (p, (cycle, dir)) in placed.iter().zip(&edges) {
                assert_eq!(p.bit, *dir);
                let err = p.at as i64 - (cycle / 2) as i64 - offset;
                assert!(
                    (-1..=1).contains(&err),
                    "seed {seed}: edge at cycle {cycle} placed at {}",
                    p.at
                );
            }
        }
    }

    #[test]
    fn both_edges_of_a_pin_are_stamped_with_the_new_level() {
        let (levels, rising) = train(7, 100);
        let pushed = run(false, &levels);
        assert_eq!(
            pushed.len(),
            2 * rising.len(),
            "a rise and a fall per pulse"
        );
        let placed: Vec<Edge> = pushed.iter().map(|w| place(*w, 1 << 20)).collect();
        for pair in placed.chunks(2) {
            assert!(pair[0].bit && !pair[1].bit);
            assert!(pair[1].at > pair[0].at + 4);
        }
    }

    #[test]
    fn placing_extends_31_bits_from_a_later_time() {
        // Ticks 5, and 2^31 + 5: the same word; the later time decides.
        let word = |ticks: u64| !(ticks as u32) & 0x7FFF_FFFF;
        assert_eq!(place(word(5), 100).at, 5);
        assert_eq!(place(word(5), (1 << 31) + 100).at, (1 << 31) + 5);
        assert_eq!(
            place(word((1 << 31) - 1) | 1 << 31, (1 << 31) + 3),
            Edge {
                bit: true,
                at: (1 << 31) - 1
            }
        );
        assert_eq!(timer_hz(150_000_000), 75_000_000);
    }
}

//! The bridge's clock: system clock cycles since boot, 64 bits, from two
//! counters the RP2350 image reads together: the Cortex-M33's cycle
//! counter (DWT CYCCNT: exact, 32 bits, but it stops while the core sleeps
//! in `wfe`/`wfi`, where the embassy executor waits) and the 1 MHz system
//! timer (64 bits, from the reference clock: it never stops).
//!
//! Each reading adds the cycles since the last one: the counter's, when
//! they agree with the timer's microseconds (to two microseconds and a
//! few cycles), else the timer's. A core that slept costs precision for
//! that one interval (a microsecond), never the seconds a stopped counter
//! would put between the CPU's clock and the edge counters' (until issue
//! 28, the clock took the counter's low 32 bits as truth whatever the
//! timer said).

/// Cycles since boot, from (cycle counter, timer) readings.
#[derive(Debug, Clone)]
pub struct Clock {
    per_us: i64,
    /// Cycles at timer zero: the timer's microseconds as cycles, plus
    /// this, is the timer's idea of the cycles now.
    base: i64,
    last_fine: u32,
    cycles: u64,
}

impl Clock {
    /// A clock at `sysclk_hz` (a whole number of MHz) whose first reading
    /// is (`fine`, `us`), counted as `cycles`.
    pub fn new(sysclk_hz: u32, fine: u32, us: u64, cycles: u64) -> Clock {
        let per_us = i64::from(sysclk_hz / 1_000_000);
        Clock {
            per_us,
            base: cycles as i64 - us as i64 * per_us,
            last_fine: fine,
            cycles,
        }
    }

    /// Cycles now, from a new reading: the cycle counter's value `fine`
    /// and the timer's `us`, read back to back. Never less than the last.
    pub fn update(&mut self, fine: u32, us: u64) -> u64 {
        // The timer's cycles: right to within a microsecond.
        let timer = (self.base + us as i64 * self.per_us).max(0);
        let last = self.cycles as i64;
        let rough = (timer - last).max(0);
        // The counter's cycles since the last reading: the count whose low
        // 32 bits it gives, nearest the timer's.
        let d_fine = fine.wrapping_sub(self.last_fine);
        let delta = i64::from(d_fine.wrapping_sub(rough as u32) as i32);
        let counted = last + rough + delta;
        let tolerance = self.per_us + 32;
        self.cycles = if counted >= last && (counted - timer).abs() <= tolerance {
            counted as u64
        } else {
            // The counter stopped (the core slept) or jumped: the timer.
            timer.max(last) as u64
        };
        self.last_fine = fine;
        self.cycles
    }

    /// Cycles now from the cycle counter alone (`fine`), if it cannot have
    /// wrapped since the last [`Clock::update`] (2^30 cycles: 7 s at
    /// 150 MHz): exact unless the core slept since.
    pub fn extend(&self, fine: u32) -> Option<u64> {
        let d = fine.wrapping_sub(self.last_fine);
        (d < 1 << 30).then_some(self.cycles + u64::from(d))
    }

    /// The last reading's cycles.
    pub fn cycles(&self) -> u64 {
        self.cycles
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;
    use proptest::prelude::*;
    use std::vec::Vec;

    const HZ: u32 = 150_000_000;

    /// The readings of a core that runs and sleeps: (true cycles, CYCCNT,
    /// timer us) at each reading; CYCCNT stops while the core sleeps.
    fn readings(spans: &[(u64, bool)]) -> Vec<(u64, u32, u64)> {
        let mut t = 1_000u64;
        let mut cyccnt = 77u32;
        let mut out = Vec::new();
        for &(span, asleep) in spans {
            t += span;
            if !asleep {
                cyccnt = cyccnt.wrapping_add(span as u32);
            }
            out.push((t, cyccnt, t / 150));
        }
        out
    }

    /// The clock before issue 28 (`clock.rs` of the RP2350 image): the
    /// counter's low 32 bits nearest the timer's count since start.
    fn old(c0: u32, t0: u64, fine: u32, us: u64) -> u64 {
        let fine = fine.wrapping_sub(c0);
        let coarse = (us - t0) * 150;
        let delta = fine.wrapping_sub(coarse as u32) as i32;
        coarse.wrapping_add_signed(i64::from(delta))
    }

    #[test]
    fn a_core_that_slept_does_not_move_the_clock_by_seconds() {
        // Runs 1 ms, sleeps 3 s (the executor waiting for USB), runs on.
        let r = readings(&[(150_000, false), (450_000_000, true), (150_000, false)]);
        let (t0, c0, u0) = (1_000u64, 77u32, 1_000 / 150);
        let mut clock = Clock::new(HZ, c0, u0, t0);
        for &(t, fine, us) in &r {
            let got = clock.update(fine, us);
            assert!(got.abs_diff(t) <= 2 * 150, "{got} against {t}");
        }
        // The old clock is wrong by the whole sleep (3 s) after it.
        let &(t, fine, us) = r.last().expect("three readings");
        let was = old(c0, u0, fine, us) + t0;
        assert!(
            was.abs_diff(t) > 400_000_000,
            "the old clock: {was} against {t}"
        );
    }

    proptest! {
        #[test]
        fn the_clock_stays_within_two_microseconds_and_never_goes_back(
            spans in proptest::collection::vec((1u64..2_000_000_000, any::<bool>()), 1..60)
        ) {
            let r = readings(&spans);
            let mut clock = Clock::new(HZ, 77, 1_000 / 150, 1_000);
            let mut last = 0;
            for &(t, fine, us) in &r {
                let got = clock.update(fine, us);
                prop_assert!(got >= last);
                prop_assert!(got.abs_diff(t) <= 2 * 150 + 32, "{} against {}", got, t);
                last = got;
            }
        }

        #[test]
        fn an_awake_core_is_exact(spans in proptest::collection::vec(1u64..4_000_000_000, 1..60)) {
            let spans: Vec<(u64, bool)> = spans.into_iter().map(|s| (s, false)).collect();
            let r = readings(&spans);
            let mut clock = Clock::new(HZ, 77, 1_000 / 150, 1_000);
            for &(t, fine, us) in &r {
                prop_assert_eq!(clock.update(fine, us), t);
            }
        }
    }
}

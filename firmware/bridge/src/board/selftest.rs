//! The self-test ([`Bus::self_test`]): the PIO generator's bursts into
//! the capture inputs of POUT and INT*, each burst's first rise predicted
//! from the cycle the generator was enabled on.
//!
//! [`Bus::self_test`]: ppmc_core::bus::Bus::self_test

use super::capture::SETTLE_TICKS;
use super::Board;
use crate::hal::Hal;
use crate::programs::{self, TEST_GEN_LEAD};
use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;
use ppmc_core::bus::{SelfTestPlan, SelfTestReply};
use ppmc_core::time::Duration;

/// The longest self-test the board runs in one request (cycles at most
/// 2^40: two hours at 150 MHz; the host asks for far less).
const SELF_TEST_MOST_CYCLES: u64 = 1 << 40;

impl<H: Hal> Board<H> {
    /// The self-test ([`Bus::self_test`]): the generator connected to the
    /// capture inputs of POUT and INT* (the chip's outputs cut off), a
    /// chip reset (a fresh record and timebase, started with the
    /// generator's level), the bursts, each started when the last one and
    /// its gap have passed, the capture drained throughout; then the
    /// inputs given back to the chip. Each burst's first rise is predicted
    /// from the cycle the generator was enabled on
    /// ([`programs::TEST_GEN_LEAD`]): what the capture says about it is
    /// the capture's offset.
    pub(super) fn run_self_test(&mut self, plan: &SelfTestPlan) -> Result<SelfTestReply, String> {
        // Ticks are two cycles: times in whole ticks keep every edge on
        // the counters' grid.
        let cycles = |d: Duration| 2 * self.timer.to_ticks(d.as_nanos());
        let (high, low, gap) = (cycles(plan.high), cycles(plan.low), cycles(plan.gap));
        let words = programs::test_gen_words(plan.count, high, low).ok_or_else(|| {
            format!(
                "the generator cannot make pulses {} high and {} low: each must be at least {} and at most 2^32 cycles",
                plan.high,
                plan.low,
                Duration::from_nanos(self.timer.to_nanos(2))
            )
        })?;
        let burst = (high + low).saturating_mul(u64::from(plan.count));
        let total = (burst + gap).saturating_mul(u64::from(plan.bursts));
        if total > SELF_TEST_MOST_CYCLES {
            return Err(format!(
                "a self-test of {} bursts of {} pulses takes longer than the bridge allows in one request",
                plan.bursts, plan.count
            ));
        }
        self.hal.resync();
        self.hal.gen_connect(true);
        self.reset_chip();
        let mut starts = Vec::with_capacity(usize::from(plan.bursts));
        // The first burst a little after the reset (the counters started).
        let mut next = self.hal.cycles() + u64::from(self.sysclk_hz / 500_000);
        for _ in 0..plan.bursts {
            self.drain_until(next / 2);
            let enabled = self.hal.gen_start(words);
            let first = enabled + TEST_GEN_LEAD;
            starts.push(self.time_of_cycle(first));
            let end = first + burst;
            self.drain_until(end.div_ceil(2) + SETTLE_TICKS);
            self.hal.gen_stop();
            next = end + gap;
        }
        // Every edge of the last burst into the record, then the chip's
        // outputs back.
        let settled = self.now_ticks() + 2 * SETTLE_TICKS;
        self.drain_until(settled);
        self.refresh();
        self.hal.gen_connect(false);
        self.moment = self.now_ticks();
        self.batch_done = true;
        let dur = |c: u64| Duration::from_nanos(self.timer.to_nanos(c / 2));
        Ok(SelfTestReply {
            starts,
            high: dur(high),
            low: dur(low),
        })
    }
}

//! The bridge's clock: CPU cycles since boot, exact, from the Cortex-M33's
//! cycle counter (DWT CYCCNT, 32 bits at the system clock) made 64 bits
//! with the 1 MHz system timer, which says which wrap of the counter it is.
//! The bridge's ticks (its `timer_hz`) are cycles / 2, the rate of the PIO
//! capture's counter.

use cortex_m::peripheral::{DCB, DWT};

#[derive(Debug)]
pub struct Clock {
    sysclk_hz: u32,
    /// The cycle counter and the timer at the same instant, at start.
    c0: u32,
    t0: u64,
}

impl Clock {
    /// Starts the cycle counter.
    pub fn start(dcb: &mut DCB, dwt: &mut DWT, sysclk_hz: u32) -> Clock {
        dcb.enable_trace();
        dwt.enable_cycle_counter();
        let t0 = embassy_time::Instant::now().as_micros();
        let c0 = DWT::cycle_count();
        Clock { sysclk_hz, c0, t0 }
    }

    /// CPU cycles since [`Clock::start`].
    pub fn cycles(&self) -> u64 {
        let fine = DWT::cycle_count().wrapping_sub(self.c0);
        let us = embassy_time::Instant::now().as_micros() - self.t0;
        let coarse = us * u64::from(self.sysclk_hz / 1_000_000);
        // The counter is exact, the timer says which wrap: the cycles are
        // the value near `coarse` whose low 32 bits are `fine`.
        let delta = fine.wrapping_sub(coarse as u32) as i32;
        coarse.wrapping_add_signed(i64::from(delta))
    }

    /// Bridge ticks since start: cycles / 2.
    pub fn ticks(&self) -> u64 {
        self.cycles() / 2
    }
}

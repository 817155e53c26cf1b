//! Section 3-2: initialization, its boundary values, clocks, the frozen
//! winding rule, the ramp, and the speed limit.

use ppmc::scenario::prelude::*;

pub fn scenarios() -> Vec<Scenario> {
    vec![
        s3_2_1_initialization_sets_the_phase_outputs(),
        s3_2_2_init_processing_with_pa_4(),
        s3_2_2_init_processing_with_pa_11220(),
        s3_2_2_boundary_rates_are_accepted(),
        s3_2_1_winding_is_frozen_until_software_reset(),
        s3_2_2_rates_change_by_reinitializing(),
        s3_2_2_ramp_runs_from_rl_to_rh(),
        s3_2_2_external_clock(),
        s3_2_2_over_speed_locks_out_the_host(),
        s3_2_2_pout_mode_allows_40_kpps(),
    ]
}

/// the phase outputs are set 44 us after the final byte (Table 3-3)
#[scenario(tags("init", "timing", "phases"))]
fn s3_2_1_initialization_sets_the_phase_outputs(d: &mut Driver) -> Outcome {
    d.expect_phases(0)?;
    d.init(Init::four_phase())?;
    d.wait(ms(1))?;
    d.expect_latency(TimingId::InitOutputsSet)?;
    d.expect_phases(0b11000)
}

/// initialization with the fewest acceleration pulses: 16.5 ms (Table 3-3 min)
#[scenario(tags("init", "timing", "boundary"))]
fn s3_2_2_init_processing_with_pa_4(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase().accel_pulses(4))?;
    d.expect_no_error()?;
    d.expect_latency(TimingId::InitProcessing)?;
    d.run(Move::accel(Cw, 20))?;
    d.expect_pulses(20, Cw)
}

/// initialization with the most acceleration pulses: 162.8 ms (Table 3-3 max)
#[scenario(tags("init", "timing", "boundary"))]
fn s3_2_2_init_processing_with_pa_11220(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase().rates(200, 20).accel_pulses(11_220))?;
    d.expect_no_error()?;
    d.expect_latency(TimingId::InitProcessing)?;
    d.run(Move::accel(Cw, 30))?;
    d.expect_pulses(30, Cw)
}

/// RL = 254, RH = 1 and RL = 21, RH = 20 are accepted
#[scenario(tags("init", "boundary"))]
fn s3_2_2_boundary_rates_are_accepted(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase().rates(254, 1))?;
    d.expect_no_error()?;
    d.init(Init::four_phase().rates(21, 20))?;
    d.expect_no_error()?;
    d.run(Move::accel(Cw, 300))?;
    let (lo, hi) = (d.period(20), d.period(21));
    d.expect_intervals(lo, hi)
}

/// type, excitation and logic ignore re-initialization until a software reset
#[scenario(tags("init", "phases", "reset"))]
fn s3_2_1_winding_is_frozen_until_software_reset(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    // Ask for 3-phase, 1-2 excitation, positive logic: ignored.
    d.init(Init::new(MotorType::ThreePhase).half_step().positive_logic())?;
    d.expect_no_error()?;
    d.run(Move::single_step(Cw))?;
    d.expect_phases(0b01100)?;
    // S2 S3 energized, negative logic: levels 10011; HOLD off; CW.
    d.expect_output_status(0b1001_1000)?;
    d.command(0xC0)?;
    d.init(Init::new(MotorType::ThreePhase).half_step().positive_logic())?;
    d.run(Move::single_step(Cw))?;
    d.expect_phases(0b11000)?;
    d.expect_output_status(0b1100_0000)
}

/// a new RH takes effect without a reset (Equation 3-1)
#[scenario(tags("init", "rates"))]
fn s3_2_2_rates_change_by_reinitializing(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    d.run(Move::accel(Cw, 300))?;
    let (fast, slow) = (d.period(20), d.period(100));
    d.expect_intervals(fast, slow)?;
    d.init(Init::four_phase().rates(100, 40))?;
    d.run(Move::accel(Ccw, 300))?;
    let fast = d.period(40);
    d.expect_intervals(fast, slow)
}

/// an accel/decel move spans the RL and RH periods and is symmetric
#[scenario(tags("init", "rates", "accel"))]
fn s3_2_2_ramp_runs_from_rl_to_rh(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    d.run(Move::accel(Cw, 1_000))?;
    d.expect_pulses(1_000, Cw)?;
    let (fast, slow) = (d.period(20), d.period(100));
    d.expect_intervals(fast, slow)
}

/// the external clock sets Tclock; with none fitted the chip never pulses
#[scenario(section = "3-2-1", tags("init", "clock"))]
fn s3_2_2_external_clock(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase().external_clock())?;
    // Tclock = 1 / the CLOCK pin's frequency: (99 + 1) x Tclock, plus
    // VSEL low's term (Equations 3-1, 3-3).
    match d.period_on(ClockSource::External, 99) {
        Some(period) => {
            d.run(Move::constant(Cw, 99, 10))?;
            d.expect_intervals(period, period)
        }
        None => {
            d.start(Move::constant(Cw, 99, 10))?;
            let idle = d.await_flag(Flag::Busy, false, ms(100))?;
            d.check("BUSY without a base clock", None, idle)?;
            d.expect_pulses(0, Cw)
        }
    }
}

/// above 27 kpps in phase mode the chip takes no host byte until it slows down
#[scenario(tags("init", "speed-limit"))]
fn s3_2_2_over_speed_locks_out_the_host(d: &mut Driver) -> Outcome {
    // A high speed rate over the limit on this board (RH = 17 at 16 MHz).
    let Some(rh) = d.speed_limit_rates(false).1 else {
        return d.check("a rate over the speed limit exists on this board", true, false);
    };
    d.init(Init::four_phase().rates(100.max(rh + 1), rh))?;
    d.start(Move::accel(Cw, 5_000))?;
    d.after_pulses(2_000)?;
    d.raw_command(0x40)?;
    let taken = d.await_flag(Flag::Ibf, false, ms(20))?;
    d.check("IBF cleared while over the speed limit", None, taken)?;
    d.wait_idle()?;
    // Taken during the deceleration, once under the limit.
    let n = d.expect_pulses_between(4_900, 4_999)?;
    d.check("stopped before the end", true, n < 5_000)?;
    d.expect_finish(0xC3)
}

/// the same 35.7 kpps is within the POUT-mode limit: commands are taken
#[scenario(tags("init", "speed-limit", "pout"))]
fn s3_2_2_pout_mode_allows_40_kpps(d: &mut Driver) -> Outcome {
    // A rate over the phase-mode limit but within POUT mode's (13 at 16 MHz).
    let rh = match (d.speed_limit_rates(true).0, d.speed_limit_rates(false).1) {
        (Some(a), Some(b)) if a <= b => a,
        _ => return d.check("a rate between the POUT and phase-mode limits exists", true, false),
    };
    d.init(Init::four_phase().rates(100.max(rh + 1), rh))?;
    d.start(Move::accel(Cw, 5_000).pout())?;
    d.after_pulses(2_000)?;
    d.raw_command(Register::InputSignals.code())?;
    d.expect_flag(Flag::Ibf, false, ms(1))?;
    d.expect_error(ErrorCode::NotAllowedWhileBusy)?;
    d.wait_idle()?;
    d.expect_pulses(5_000, Cw)
}

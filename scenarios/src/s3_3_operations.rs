//! Section 3-3: the operation commands, their variants and their stops.

use ppmc::scenario::prelude::*;

pub fn scenarios() -> Vec<Scenario> {
    vec![
        s3_3_4_accel_one_step(),
        s3_3_4_accel_triangle_199_steps(),
        s3_3_4_accel_trapezoid_200_steps(),
        s3_3_4_accel_1000_steps_cw(),
        s3_3_4_accel_ccw_masked_interrupt(),
        s3_3_4_accel_ffffff_is_16777216_steps(),
        s3_3_4_pout_mode_holds_the_phases(),
        s3_3_2_decel_stop_at_high_speed(),
        s3_3_2_decel_stop_while_accelerating(),
        s3_3_1_immediate_stop_of_accel_move(),
        s3_3_1_immediate_stop_and_resume(),
        s3_3_5_constant_speed_100_steps(),
        s3_3_5_constant_rate_255(),
        s3_3_2_decel_stop_of_constant_move(),
        s3_3_6_continuous_until_l1(),
        s3_3_6_continuous_ccw_until_l2(),
        s3_3_7_high_speed_until_l3(),
        s3_3_7_high_speed_l4_while_accelerating(),
        s3_3_7_pout_high_speed_ignores_l3_while_accelerating(),
        s3_3_7_high_speed_decel_stop(),
        s3_3_4_l1_stops_accel_move(),
        s3_3_4_l4_ignored_in_cw(),
        s3_3_4_alm_stops_ccw_accel_move(),
        s3_3_6_alm_stops_continuous_move(),
        s3_3_5_limit_already_on_gives_no_pulse(),
        s3_3_8_origin_search_stops_at_cnp(),
        s3_3_8_cnp_ignored_by_other_moves(),
        s3_3_3_single_step_cw_then_ccw(),
    ]
}

fn ready(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::four_phase())?;
    Ok(())
}

/// N - 1 = 0 moves exactly one step
#[scenario(tags("operation", "accel", "boundary"))]
fn s3_3_4_accel_one_step(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::accel(Cw, 1))?;
    d.expect_pulses(1, Cw)?;
    d.expect_finish(0x83)?;
    d.expect_remaining(0)
}

/// fewer than 2 x PA steps: triangular drive, first POUT later than the 0.2 ms minimum
#[scenario(tags("operation", "accel", "triangle", "timing"))]
fn s3_3_4_accel_triangle_199_steps(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::accel(Cw, 199))?;
    d.expect_pulses(199, Cw)?;
    let first = d.expect_latency(TimingId::AccelFirstPout)?;
    let minimum = d.fw(us(200));
    d.check("triangle: first POUT later than the trapezoid minimum", true, first > minimum)
}

/// 2 x PA steps: a trapezoid reaching RH; first POUT at the 0.2 ms minimum
#[scenario(tags("operation", "accel", "trapezoid", "timing"))]
fn s3_3_4_accel_trapezoid_200_steps(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::accel(Cw, 200))?;
    d.expect_pulses(200, Cw)?;
    d.expect_latency(TimingId::AccelFirstPout)?;
    let (rh, rl) = (d.period(20), d.period(100));
    d.expect_intervals(rh, rl)
}

/// 1,000 steps written as 0x0003E7; finish 0x83, remaining 0, Table 3-3 termination times
#[scenario(tags("operation", "accel", "timing"))]
fn s3_3_4_accel_1000_steps_cw(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::accel(Cw, 1_000))?;
    d.expect_latency(TimingId::BusyRise)?;
    d.expect_latency(TimingId::NextCommand)?;
    d.expect_latency(TimingId::InterruptOutput)?;
    d.expect_pulses(1_000, Cw)?;
    d.expect_pins(Some(true), None, None, None)?;
    d.expect_finish(0x83)?;
    d.expect_pins(Some(false), None, None, None)?;
    d.expect_remaining(0)?;
    let hold = d.fw(ms(4));
    d.wait(hold)?;
    d.expect_latency(TimingId::HoldOn)?;
    Ok(())
}

/// CCW with the termination interrupt masked: DIR = CCW, INT* never asserted
#[scenario(tags("operation", "accel", "direction", "interrupt"))]
fn s3_3_4_accel_ccw_masked_interrupt(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::accel(Ccw, 50).masked())?;
    d.expect_pulses(50, Ccw)?;
    d.expect_pins(Some(false), None, None, None)?;
    // Output status bit 1: CCW; 50 CCW steps from S1S2: S3S4 (levels 11001).
    d.expect_output_status(0b1100_1010)?;
    d.expect_finish(0x83)
}

/// FFFFFF moves 16,777,216 steps, the maximum (10 minutes or more on a board)
#[scenario(tags("operation", "accel", "boundary", "long"), budget = Duration::from_secs(7_200))]
fn s3_3_4_accel_ffffff_is_16777216_steps(d: &mut Driver) -> Outcome {
    // The fastest high speed within the limit keeps a board run short.
    let rh = d.speed_limit_rates(false).0.unwrap_or(18);
    d.init(Init::four_phase().rates(rh.saturating_add(12).min(254), rh).accel_pulses(10))?;
    d.run(Move::accel(Cw, 16_777_216))?;
    d.expect_pulses(16_777_216, Cw)?;
    d.expect_finish(0x83)?;
    d.expect_remaining(0)
}

/// POUT mode outputs pulses only; finish status carries code 011
#[scenario(tags("operation", "accel", "pout"))]
fn s3_3_4_pout_mode_holds_the_phases(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::accel(Cw, 7).pout())?;
    d.expect_pulses(7, Cw)?;
    d.expect_phases(0b11000)?;
    d.expect_finish(0x83)?;
    d.run(Move::accel(Cw, 7))?;
    d.expect_phases(0b10010)
}

/// Decelerating Stop at high speed: 17 us, then PA more pulses; finish 0xC3
#[scenario(tags("operation", "stop", "decel-stop", "timing"))]
fn s3_3_2_decel_stop_at_high_speed(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::accel(Cw, 5_000))?;
    d.after_pulses(500)?;
    d.wait(us(10))?;
    d.decel_stop()?;
    d.expect_latency(TimingId::DecelStopProcessing)?;
    let n = d.expect_pulses_between(600, 620)?;
    d.expect_finish(0xC3)?;
    d.expect_remaining(5_000 - n as u32 - 1)
}

/// Decelerating Stop during acceleration ramps down from the speed reached
#[scenario(tags("operation", "stop", "decel-stop"))]
fn s3_3_2_decel_stop_while_accelerating(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::accel(Cw, 5_000))?;
    d.after_pulses(20)?;
    d.decel_stop()?;
    d.wait_idle()?;
    // Ramp down from where it got: 21 up, 20 down at most.
    d.expect_pulses_between(40, 44)?;
    d.expect_finish(0xC3)
}

/// Immediate Stop cuts pulses at once; abnormal termination within 0.2 ms
#[scenario(tags("operation", "stop", "immediate-stop", "timing"))]
fn s3_3_1_immediate_stop_of_accel_move(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::accel(Ccw, 5_000))?;
    d.after_pulses(300)?;
    d.immediate_stop()?;
    d.wait_idle()?;
    d.expect_no_pulses_after_trigger(us(10))?;
    d.expect_latency(TimingId::AbnormalTermination)?;
    let n = d.expect_pulses_between(300, 301)?;
    d.expect_finish(0xC3)?;
    d.expect_remaining(5_000 - n as u32 - 1)
}

/// a constant move stopped at once resumes from the remaining count as read
#[scenario(tags("operation", "stop", "immediate-stop", "constant", "remaining"))]
fn s3_3_1_immediate_stop_and_resume(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::constant(Cw, 50, 300))?;
    d.after_pulses(120)?;
    d.immediate_stop()?;
    d.wait_idle()?;
    let done = d.expect_pulses_between(120, 121)?;
    let read = d.read_register(Register::RemainingPulses)?;
    let left = u32::from_le_bytes([read[0], read[1], read[2], 0]) + 1;
    d.check("pulses done + remaining", 300, done as u32 + left)?;
    d.run(Move::constant(Cw, 50, left))?;
    d.expect_pulses(u64::from(left), Cw)
}

/// 100 steps at rate 50 (102 us); first POUT 194 us; finish 0x84
#[scenario(tags("operation", "constant", "timing"))]
fn s3_3_5_constant_speed_100_steps(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::constant(Cw, 50, 100))?;
    d.expect_pulses(100, Cw)?;
    d.expect_latency(TimingId::ConstantFirstPout)?;
    let p = d.period(50);
    d.expect_intervals(p, p)?;
    d.expect_finish(0x84)?;
    d.expect_remaining(0)
}

/// the slowest constant rate, 255: 512 us per pulse
#[scenario(tags("operation", "constant", "boundary"))]
fn s3_3_5_constant_rate_255(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::constant(Ccw, 255, 5))?;
    d.expect_pulses(5, Ccw)?;
    let p = d.period(255);
    d.expect_intervals(p, p)
}

/// Decelerating Stop stops a constant-speed move at once (notes N13)
#[scenario(tags("operation", "constant", "stop", "decel-stop"))]
fn s3_3_2_decel_stop_of_constant_move(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::constant(Cw, 50, 500))?;
    d.after_pulses(100)?;
    d.decel_stop()?;
    d.wait_idle()?;
    d.expect_no_pulses_after_trigger(us(10))?;
    d.expect_finish(0xC4)
}

/// continuous CW runs until L1; L2 is ignored; remaining tells the distance
#[scenario(tags("operation", "continuous", "limit", "input"))]
fn s3_3_6_continuous_until_l1(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::continuous(Cw, 50))?;
    d.after_pulses(200)?;
    d.set(Input::L2, true)?;
    d.after_pulses(400)?;
    d.set(Input::L1, true)?;
    d.wait_idle()?;
    d.expect_no_pulses_after_trigger(Duration::ZERO)?;
    d.expect_pulses(400, Cw)?;
    d.expect_finish(0x95)?;
    d.expect_remaining(16_777_216 - 400 - 1)
}

/// continuous CCW runs until L2; L1 is ignored
#[scenario(tags("operation", "continuous", "limit", "input", "direction"))]
fn s3_3_6_continuous_ccw_until_l2(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::continuous(Ccw, 50))?;
    d.after_pulses(50)?;
    d.set(Input::L1, true)?;
    d.after_pulses(80)?;
    d.set(Input::L2, true)?;
    d.wait_idle()?;
    d.expect_pulses(80, Ccw)?;
    d.expect_finish(0x95)
}

/// continuous high speed CW decelerates at L3 within 17 us; finish 0x8E
#[scenario(tags("operation", "high-speed", "hs-limit", "input", "timing"))]
fn s3_3_7_high_speed_until_l3(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::high_speed(Cw))?;
    d.after_pulses(400)?;
    d.wait(us(5))?;
    d.set(Input::L3, true)?;
    d.after_pulses(402)?;
    // Deceleration goes on with the limit released.
    d.set(Input::L3, false)?;
    d.expect_latency(TimingId::HighSpeedLimitCruise)?;
    // Pulse index 400 was being timed: it and 99 more decelerate.
    d.expect_pulses(400 + 100, Cw)?;
    d.expect_finish(0x8E)
}

/// L4 during CCW acceleration decelerates within 12 us
#[scenario(tags("operation", "high-speed", "hs-limit", "input", "timing"))]
fn s3_3_7_high_speed_l4_while_accelerating(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::high_speed(Ccw))?;
    d.after_pulses(30)?;
    d.wait(us(5))?;
    d.set(Input::L4, true)?;
    d.expect_latency(TimingId::HighSpeedLimitAccel)?;
    // Pulse 31 (index 30) was being timed: 30 up, 30 down.
    d.expect_pulses(60, Ccw)?;
    d.expect_finish(0x8E)
}

/// POUT mode does not check L3 while accelerating; it decelerates on reaching RH
#[scenario(section = "3-3-4", tags("operation", "high-speed", "pout", "hs-limit", "input"))]
fn s3_3_7_pout_high_speed_ignores_l3_while_accelerating(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::high_speed(Cw).pout())?;
    d.after_pulses(30)?;
    d.set(Input::L3, true)?;
    d.wait_idle()?;
    let rh = d.period(20);
    let rl = d.period(100);
    d.expect_intervals(rh, rl)?;
    // 100 pulses reach high speed, then PA = 100 decelerate.
    d.expect_pulses(200, Cw)?;
    d.expect_finish(0x8E)
}

/// a Decelerating Stop brings continuous high speed down over PA pulses
#[scenario(tags("operation", "high-speed", "stop", "decel-stop"))]
fn s3_3_7_high_speed_decel_stop(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::high_speed(Ccw))?;
    d.after_pulses(1_000)?;
    d.decel_stop()?;
    d.wait_idle()?;
    d.expect_pulses_between(1_100, 1_102)?;
    d.expect_finish(0xC6)
}

/// L1 during a CW accel/decel move stops it at once; finish 0x93
#[scenario(tags("operation", "accel", "limit", "input", "timing"))]
fn s3_3_4_l1_stops_accel_move(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::accel(Cw, 2_000))?;
    d.after_pulses(700)?;
    d.set(Input::L1, true)?;
    d.wait_idle()?;
    d.expect_no_pulses_after_trigger(Duration::ZERO)?;
    d.expect_latency(TimingId::AbnormalTermination)?;
    d.expect_pulses(700, Cw)?;
    d.expect_finish(0x93)?;
    d.expect_remaining(2_000 - 700 - 1)
}

/// the CCW high-speed limit does not act on a CW move
#[scenario(tags("operation", "accel", "hs-limit", "input", "direction"))]
fn s3_3_4_l4_ignored_in_cw(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::accel(Cw, 600))?;
    d.after_pulses(300)?;
    d.set(Input::L4, true)?;
    d.set(Input::L2, true)?;
    d.wait_idle()?;
    d.expect_pulses(600, Cw)?;
    d.expect_finish(0x83)
}

/// ALM stops a move in either direction; finish 0xA3
#[scenario(tags("operation", "accel", "alarm", "input"))]
fn s3_3_4_alm_stops_ccw_accel_move(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::accel(Ccw, 2_000))?;
    d.after_pulses(150)?;
    d.set(Input::Alm, true)?;
    d.wait_idle()?;
    d.expect_no_pulses_after_trigger(Duration::ZERO)?;
    d.expect_pulses(150, Ccw)?;
    d.expect_finish(0xA3)
}

/// ALM stops continuous constant speed; finish 0xA5
#[scenario(tags("operation", "continuous", "alarm", "input"))]
fn s3_3_6_alm_stops_continuous_move(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::continuous(Cw, 80))?;
    d.after_pulses(33)?;
    d.set(Input::Alm, true)?;
    d.wait_idle()?;
    d.expect_pulses(33, Cw)?;
    d.expect_finish(0xA5)
}

/// a move into an asserted limit stops before its first pulse
#[scenario(tags("operation", "constant", "limit", "input"))]
fn s3_3_5_limit_already_on_gives_no_pulse(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.set(Input::L2, true)?;
    d.run(Move::constant(Ccw, 50, 200))?;
    d.expect_pulses(0, Ccw)?;
    d.expect_finish(0x94)?;
    d.expect_remaining(199)
}

/// origin search stops at CNP; finish 0x87; remaining gives the distance
#[scenario(tags("operation", "origin", "input", "remaining"))]
fn s3_3_8_origin_search_stops_at_cnp(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::origin(Ccw, 30))?;
    d.after_pulses(777)?;
    d.set(Input::Cnp, true)?;
    d.wait_idle()?;
    d.expect_no_pulses_after_trigger(Duration::ZERO)?;
    d.expect_pulses(777, Ccw)?;
    d.expect_finish(0x87)?;
    d.expect_remaining(16_777_216 - 777 - 1)
}

/// CNP does not stop a constant-speed move
#[scenario(tags("operation", "origin", "input"))]
fn s3_3_8_cnp_ignored_by_other_moves(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::constant(Cw, 30, 200))?;
    d.after_pulses(10)?;
    d.set(Input::Cnp, true)?;
    d.wait_idle()?;
    d.expect_pulses(200, Cw)?;
    d.expect_finish(0x84)
}

/// one step each way; Table 3-3 single step time 112 us; finish 0x82
#[scenario(tags("operation", "single-step", "timing", "phases"))]
fn s3_3_3_single_step_cw_then_ccw(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::single_step(Cw))?;
    d.expect_latency(TimingId::SingleStep)?;
    d.expect_pulses(1, Cw)?;
    d.expect_phases(0b01100)?;
    d.expect_finish(0x82)?;
    d.run(Move::single_step(Ccw))?;
    d.expect_pulses(1, Ccw)?;
    d.expect_phases(0b11000)?;
    d.run(Move::single_step(Ccw))?;
    d.expect_phases(0b10010)
}

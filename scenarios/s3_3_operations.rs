//! Section 3-3: the operation commands, their variants and their stops.

use crate::scenario::prelude::*;

pub fn scenarios() -> Vec<Scenario> {
    vec![
        Scenario::new("s3_3_4_accel_one_step", "3-3-4",
            "N - 1 = 0 moves exactly one step", &["operation", "accel", "boundary"], accel_one),
        Scenario::new("s3_3_4_accel_triangle_199_steps", "3-3-4",
            "fewer than 2 x PA steps: triangular drive, first POUT later than the 0.2 ms minimum",
            &["operation", "accel", "triangle", "timing"], accel_triangle),
        Scenario::new("s3_3_4_accel_trapezoid_200_steps", "3-3-4",
            "2 x PA steps: a trapezoid reaching RH; first POUT at the 0.2 ms minimum",
            &["operation", "accel", "trapezoid", "timing"], accel_trapezoid),
        Scenario::new("s3_3_4_accel_1000_steps_cw", "3-3-4",
            "1,000 steps written as 0x0003E7; finish 0x83, remaining 0, Table 3-3 termination times",
            &["operation", "accel", "timing"], accel_thousand),
        Scenario::new("s3_3_4_accel_ccw_masked_interrupt", "3-3-4",
            "CCW with the termination interrupt masked: DIR = CCW, INT* never asserted",
            &["operation", "accel", "direction", "interrupt"], accel_ccw_masked),
        Scenario::new("s3_3_4_accel_ffffff_is_16777216_steps", "3-3-4",
            "FFFFFF moves 16,777,216 steps, the maximum (10 minutes or more on a board)",
            &["operation", "accel", "boundary", "long"], accel_ffffff)
            .budget(Duration::from_secs(7_200)),
        Scenario::new("s3_3_4_pout_mode_holds_the_phases", "3-3-4",
            "POUT mode outputs pulses only; finish status carries code 011",
            &["operation", "accel", "pout"], pout_accel),
        Scenario::new("s3_3_2_decel_stop_at_high_speed", "3-3-2",
            "Decelerating Stop at high speed: 17 us, then PA more pulses; finish 0xC3",
            &["operation", "stop", "decel-stop", "timing"], decel_stop_cruise),
        Scenario::new("s3_3_2_decel_stop_while_accelerating", "3-3-2",
            "Decelerating Stop during acceleration ramps down from the speed reached",
            &["operation", "stop", "decel-stop"], decel_stop_accel),
        Scenario::new("s3_3_1_immediate_stop_of_accel_move", "3-3-1",
            "Immediate Stop cuts pulses at once; abnormal termination within 0.2 ms",
            &["operation", "stop", "immediate-stop", "timing"], immediate_stop_accel),
        Scenario::new("s3_3_1_immediate_stop_and_resume", "3-3-1",
            "a constant move stopped at once resumes from the remaining count as read",
            &["operation", "stop", "immediate-stop", "constant", "remaining"], stop_and_resume),
        Scenario::new("s3_3_5_constant_speed_100_steps", "3-3-5",
            "100 steps at rate 50 (102 us); first POUT 194 us; finish 0x84",
            &["operation", "constant", "timing"], constant_move),
        Scenario::new("s3_3_5_constant_rate_255", "3-3-5",
            "the slowest constant rate, 255: 512 us per pulse",
            &["operation", "constant", "boundary"], constant_slowest),
        Scenario::new("s3_3_2_decel_stop_of_constant_move", "3-3-2",
            "Decelerating Stop stops a constant-speed move at once (notes N13)",
            &["operation", "constant", "stop", "decel-stop"], constant_decel_stop),
        Scenario::new("s3_3_6_continuous_until_l1", "3-3-6",
            "continuous CW runs until L1; L2 is ignored; remaining tells the distance",
            &["operation", "continuous", "limit", "input"], continuous_l1),
        Scenario::new("s3_3_6_continuous_ccw_until_l2", "3-3-6",
            "continuous CCW runs until L2; L1 is ignored",
            &["operation", "continuous", "limit", "input", "direction"], continuous_l2),
        Scenario::new("s3_3_7_high_speed_until_l3", "3-3-7",
            "continuous high speed CW decelerates at L3 within 17 us; finish 0x8E",
            &["operation", "high-speed", "hs-limit", "input", "timing"], high_speed_l3),
        Scenario::new("s3_3_7_high_speed_l4_while_accelerating", "3-3-7",
            "L4 during CCW acceleration decelerates within 12 us",
            &["operation", "high-speed", "hs-limit", "input", "timing"], high_speed_l4_accel),
        Scenario::new("s3_3_7_pout_high_speed_ignores_l3_while_accelerating", "3-3-4",
            "POUT mode does not check L3 while accelerating; it decelerates on reaching RH",
            &["operation", "high-speed", "pout", "hs-limit", "input"], pout_high_speed_l3),
        Scenario::new("s3_3_7_high_speed_decel_stop", "3-3-7",
            "a Decelerating Stop brings continuous high speed down over PA pulses",
            &["operation", "high-speed", "stop", "decel-stop"], high_speed_decel_stop),
        Scenario::new("s3_3_4_l1_stops_accel_move", "3-3-4",
            "L1 during a CW accel/decel move stops it at once; finish 0x93",
            &["operation", "accel", "limit", "input", "timing"], accel_l1),
        Scenario::new("s3_3_4_l4_ignored_in_cw", "3-3-4",
            "the CCW high-speed limit does not act on a CW move",
            &["operation", "accel", "hs-limit", "input", "direction"], accel_l4_ignored),
        Scenario::new("s3_3_4_alm_stops_ccw_accel_move", "3-3-4",
            "ALM stops a move in either direction; finish 0xA3",
            &["operation", "accel", "alarm", "input"], accel_alm),
        Scenario::new("s3_3_6_alm_stops_continuous_move", "3-3-6",
            "ALM stops continuous constant speed; finish 0xA5",
            &["operation", "continuous", "alarm", "input"], continuous_alm),
        Scenario::new("s3_3_5_limit_already_on_gives_no_pulse", "3-3-5",
            "a move into an asserted limit stops before its first pulse",
            &["operation", "constant", "limit", "input"], limit_at_start),
        Scenario::new("s3_3_8_origin_search_stops_at_cnp", "3-3-8",
            "origin search stops at CNP; finish 0x87; remaining gives the distance",
            &["operation", "origin", "input", "remaining"], origin_cnp),
        Scenario::new("s3_3_8_cnp_ignored_by_other_moves", "3-3-8",
            "CNP does not stop a constant-speed move",
            &["operation", "origin", "input"], cnp_ignored),
        Scenario::new("s3_3_3_single_step_cw_then_ccw", "3-3-3",
            "one step each way; Table 3-3 single step time 112 us; finish 0x82",
            &["operation", "single-step", "timing", "phases"], single_steps),
    ]
}

fn ready(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::four_phase())?;
    Ok(())
}

fn accel_one(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::accel(Cw, 1))?;
    d.expect_pulses(1, Cw)?;
    d.expect_finish(0x83)?;
    d.expect_remaining(0)
}

fn accel_triangle(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::accel(Cw, 199))?;
    d.expect_pulses(199, Cw)?;
    let first = d.expect_latency(TimingId::AccelFirstPout)?;
    let minimum = d.fw(us(200));
    d.check("triangle: first POUT later than the trapezoid minimum", true, first > minimum)
}

fn accel_trapezoid(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::accel(Cw, 200))?;
    d.expect_pulses(200, Cw)?;
    d.expect_latency(TimingId::AccelFirstPout)?;
    let (rh, rl) = (d.period(20), d.period(100));
    d.expect_intervals(rh, rl)
}

fn accel_thousand(d: &mut Driver) -> Outcome {
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

fn accel_ccw_masked(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::accel(Ccw, 50).masked())?;
    d.expect_pulses(50, Ccw)?;
    d.expect_pins(Some(false), None, None, None)?;
    // Output status bit 1: CCW; 50 CCW steps from S1S2: S3S4 (levels 11001).
    d.expect_output_status(0b1100_1010)?;
    d.expect_finish(0x83)
}

fn accel_ffffff(d: &mut Driver) -> Outcome {
    // The fastest high speed within the limit keeps a board run short.
    let rh = d.speed_limit_rates(false).0.unwrap_or(18);
    d.init(Init::four_phase().rates(rh.saturating_add(12).min(254), rh).accel_pulses(10))?;
    d.run(Move::accel(Cw, 16_777_216))?;
    d.expect_pulses(16_777_216, Cw)?;
    d.expect_finish(0x83)?;
    d.expect_remaining(0)
}

fn pout_accel(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::accel(Cw, 7).pout())?;
    d.expect_pulses(7, Cw)?;
    d.expect_phases(0b11000)?;
    d.expect_finish(0x83)?;
    d.run(Move::accel(Cw, 7))?;
    d.expect_phases(0b10010)
}

fn decel_stop_cruise(d: &mut Driver) -> Outcome {
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

fn decel_stop_accel(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::accel(Cw, 5_000))?;
    d.after_pulses(20)?;
    d.decel_stop()?;
    d.wait_idle()?;
    // Ramp down from where it got: 21 up, 20 down at most.
    d.expect_pulses_between(40, 44)?;
    d.expect_finish(0xC3)
}

fn immediate_stop_accel(d: &mut Driver) -> Outcome {
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

fn stop_and_resume(d: &mut Driver) -> Outcome {
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

fn constant_move(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::constant(Cw, 50, 100))?;
    d.expect_pulses(100, Cw)?;
    d.expect_latency(TimingId::ConstantFirstPout)?;
    let p = d.period(50);
    d.expect_intervals(p, p)?;
    d.expect_finish(0x84)?;
    d.expect_remaining(0)
}

fn constant_slowest(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::constant(Ccw, 255, 5))?;
    d.expect_pulses(5, Ccw)?;
    let p = d.period(255);
    d.expect_intervals(p, p)
}

fn constant_decel_stop(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::constant(Cw, 50, 500))?;
    d.after_pulses(100)?;
    d.decel_stop()?;
    d.wait_idle()?;
    d.expect_no_pulses_after_trigger(us(10))?;
    d.expect_finish(0xC4)
}

fn continuous_l1(d: &mut Driver) -> Outcome {
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

fn continuous_l2(d: &mut Driver) -> Outcome {
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

fn high_speed_l3(d: &mut Driver) -> Outcome {
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

fn high_speed_l4_accel(d: &mut Driver) -> Outcome {
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

fn pout_high_speed_l3(d: &mut Driver) -> Outcome {
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

fn high_speed_decel_stop(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::high_speed(Ccw))?;
    d.after_pulses(1_000)?;
    d.decel_stop()?;
    d.wait_idle()?;
    d.expect_pulses_between(1_100, 1_102)?;
    d.expect_finish(0xC6)
}

fn accel_l1(d: &mut Driver) -> Outcome {
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

fn accel_l4_ignored(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::accel(Cw, 600))?;
    d.after_pulses(300)?;
    d.set(Input::L4, true)?;
    d.set(Input::L2, true)?;
    d.wait_idle()?;
    d.expect_pulses(600, Cw)?;
    d.expect_finish(0x83)
}

fn accel_alm(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::accel(Ccw, 2_000))?;
    d.after_pulses(150)?;
    d.set(Input::Alm, true)?;
    d.wait_idle()?;
    d.expect_no_pulses_after_trigger(Duration::ZERO)?;
    d.expect_pulses(150, Ccw)?;
    d.expect_finish(0xA3)
}

fn continuous_alm(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::continuous(Cw, 80))?;
    d.after_pulses(33)?;
    d.set(Input::Alm, true)?;
    d.wait_idle()?;
    d.expect_pulses(33, Cw)?;
    d.expect_finish(0xA5)
}

fn limit_at_start(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.set(Input::L2, true)?;
    d.run(Move::constant(Ccw, 50, 200))?;
    d.expect_pulses(0, Ccw)?;
    d.expect_finish(0x94)?;
    d.expect_remaining(199)
}

fn origin_cnp(d: &mut Driver) -> Outcome {
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

fn cnp_ignored(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::constant(Cw, 30, 200))?;
    d.after_pulses(10)?;
    d.set(Input::Cnp, true)?;
    d.wait_idle()?;
    d.expect_pulses(200, Cw)?;
    d.expect_finish(0x84)
}

fn single_steps(d: &mut Driver) -> Outcome {
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

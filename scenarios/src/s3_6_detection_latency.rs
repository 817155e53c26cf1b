//! Section 3-6, Table 3-3: the latencies that only show in which pulse a
//! deceleration starts from. Each probe places the trigger just inside or
//! just outside the row's band before a pulse whose time is known, so that
//! a latency 1 % off the datasheet figure moves the deceleration by a pulse.

use ppmc::scenario::prelude::*;

pub fn scenarios() -> Vec<Scenario> {
    vec![
        s3_6_decel_stop_17us_not_before(),
        s3_6_decel_stop_17us_not_after(),
        s3_6_hs_limit_cruise_17us_not_before(),
        s3_6_hs_limit_cruise_17us_not_after(),
        s3_6_hs_limit_accel_12us_not_before(),
        s3_6_hs_limit_accel_12us_not_after(),
        s3_3_4_longest_triangle_first_pout(),
    ]
}

/// At high speed (RH = 20), stands on pulse 500 of a long CW move, waits
/// until `ahead` before pulse 501 and triggers; the move then outputs
/// `pulses` (where the trigger landed where it was aimed:
/// [`Driver::expect_probe`]).
fn at_speed_probe(
    d: &mut Driver,
    ahead: Duration,
    trigger: fn(&mut Driver) -> Outcome,
    id: TimingId,
    pulses: u64,
) -> Outcome {
    d.init_and_wait(Init::four_phase())?;
    d.start(Move::accel(Cw, 5_000))?;
    d.after_pulses(500)?;
    let (period, ahead) = (d.period(20), d.fw(ahead));
    d.wait(period.saturating_sub(ahead))?;
    trigger(d)?;
    d.expect_latency(id)?;
    d.wait_idle()?;
    d.expect_probe(id, 500, ahead, |d| d.expect_pulses(pulses, Cw))
}

/// Early on the ramp of RL = 21 -> RH = 20 (periods of 44 us, whatever the
/// curve), stands on pulse 11, waits until `ahead` before pulse 12, asserts
/// L3; the move then outputs `pulses` (as [`at_speed_probe`]).
fn accel_probe(d: &mut Driver, ahead: Duration, pulses: u64) -> Outcome {
    let id = TimingId::HighSpeedLimitAccel;
    d.init_and_wait(Init::four_phase().rates(21, 20))?;
    d.start(Move::high_speed(Cw))?;
    d.after_pulses(11)?;
    let (period, ahead) = (d.period(21), d.fw(ahead));
    d.wait(period.saturating_sub(ahead))?;
    d.set(Input::L3, true)?;
    d.expect_latency(id)?;
    d.expect_finish(0x8E)?;
    d.expect_probe(id, 11, ahead, |d| d.expect_pulses(pulses, Cw))
}

fn decel_stop(d: &mut Driver) -> Outcome {
    d.decel_stop().map(|_| ())
}

fn l3(d: &mut Driver) -> Outcome {
    d.set(Input::L3, true).map(|_| ())
}

/// a Decelerating Stop 16.6 us before a pulse: that pulse is still output at speed
#[scenario(tags("timing", "decel-stop", "latency-probe"))]
fn s3_6_decel_stop_17us_not_before(d: &mut Driver) -> Outcome {
    // Pulse index 500 still at speed; 501 and 99 more decelerate.
    at_speed_probe(d, Duration::from_nanos(16_600), decel_stop, TimingId::DecelStopProcessing, 501 + 100)
}

/// a Decelerating Stop 17.4 us before a pulse: the deceleration starts from it
#[scenario(tags("timing", "decel-stop", "latency-probe"))]
fn s3_6_decel_stop_17us_not_after(d: &mut Driver) -> Outcome {
    at_speed_probe(d, Duration::from_nanos(17_400), decel_stop, TimingId::DecelStopProcessing, 500 + 100)
}

/// L3 at high speed 16.6 us before a pulse: that pulse is still output at speed
#[scenario(tags("timing", "hs-limit", "latency-probe"))]
fn s3_6_hs_limit_cruise_17us_not_before(d: &mut Driver) -> Outcome {
    at_speed_probe(d, Duration::from_nanos(16_600), l3, TimingId::HighSpeedLimitCruise, 501 + 100)
}

/// L3 at high speed 17.4 us before a pulse: the deceleration starts from it
#[scenario(tags("timing", "hs-limit", "latency-probe"))]
fn s3_6_hs_limit_cruise_17us_not_after(d: &mut Driver) -> Outcome {
    at_speed_probe(d, Duration::from_nanos(17_400), l3, TimingId::HighSpeedLimitCruise, 500 + 100)
}

/// L3 while accelerating 11.7 us before a pulse: that pulse is still on the ramp up
#[scenario(tags("timing", "hs-limit", "latency-probe"))]
fn s3_6_hs_limit_accel_12us_not_before(d: &mut Driver) -> Outcome {
    // Pulse index 11 still goes out on the way up; the ramp turns at 12.
    accel_probe(d, Duration::from_nanos(11_700), 24)
}

/// L3 while accelerating 12.3 us before a pulse: the ramp turns down from it
#[scenario(tags("timing", "hs-limit", "latency-probe"))]
fn s3_6_hs_limit_accel_12us_not_after(d: &mut Driver) -> Outcome {
    accel_probe(d, Duration::from_nanos(12_300), 22)
}

/// 22,000 steps with PA = 11,220: the longest triangles take nearly 1.1 ms to the first POUT
#[scenario(tags("timing", "accel", "triangle", "boundary"))]
fn s3_3_4_longest_triangle_first_pout(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::four_phase().rates(200, 20).accel_pulses(11_220))?;
    d.run(Move::accel(Cw, 22_000))?;
    d.expect_pulses(22_000, Cw)?;
    let first = d.expect_latency(TimingId::AccelFirstPout)?;
    let near_max = d.fw(us(1_000));
    d.check("the longest triangles take nearly the 1.1 ms maximum", true, first > near_max)
}

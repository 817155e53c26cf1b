//! The X axis of our board: a 4-phase motor, ramp from rate 200 to rate 40
//! over 300 pulses, a home switch on CNP and a CW end stop on L1.

use ppmc::scenario::prelude::*;

pub fn scenarios() -> Vec<Scenario> {
    vec![
        x_axis_travel_4000_steps(),
        x_axis_homes_on_cnp(),
        x_axis_end_stop_l1(),
    ]
}

/// Our ramp: RL 200, RH 40, PA 300 (Section 3-2-2).
fn ready(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::four_phase().rates(200, 40).accel_pulses(300))
}

/// a full-travel move: 4,000 CW steps, every interval between the RH and RL periods
#[scenario(section = "3-3-4", tags("board", "x-axis"))]
fn x_axis_travel_4000_steps(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::accel(Cw, 4_000))?;
    d.expect_pulses(4_000, Cw)?;
    let (fast, slow) = (d.period(40), d.period(200));
    d.expect_intervals(fast, slow)?;
    d.expect_finish(0x83)?;
    d.expect_remaining(0)
}

/// homing: origin search CCW at rate 100 stops on the home switch after 1,500 steps
#[scenario(section = "3-3-8", tags("board", "x-axis", "homing"))]
fn x_axis_homes_on_cnp(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::origin(Ccw, 100))?;
    d.after_pulses(1_500)?;
    d.set(Input::Cnp, true)?;
    d.wait_idle()?;
    d.expect_pulses(1_500, Ccw)?;
    d.expect_finish(0x87)?;
    d.expect_remaining(16_777_216 - 1_500 - 1)
}

/// the CW end stop (L1) ends a long move at once, 2,500 steps in
#[scenario(section = "3-3-4", tags("board", "x-axis", "limit"))]
fn x_axis_end_stop_l1(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::accel(Cw, 10_000))?;
    d.after_pulses(2_500)?;
    d.set(Input::L1, true)?;
    d.wait_idle()?;
    d.expect_pulses(2_500, Cw)?;
    d.expect_finish(0x93)?;
    d.expect_remaining(10_000 - 2_500 - 1)
}

//! Section 3-5: switching parameters, AUX* ON/OFF, auxiliary outputs,
//! software reset and recovery from it.

use ppmc::scenario::prelude::*;

pub fn scenarios() -> Vec<Scenario> {
    vec![
        s3_5_1_default_switching_chops_the_phases(),
        s3_5_1_switching_parameters(),
        s3_5_1_switching_parameters_while_busy(),
        s3_5_2_aux_on_off_before_initialization(),
        s3_5_2_aux_on_while_busy(),
        s3_5_3_aux_output_drives_auxo(),
        s3_5_4_software_reset_frees_the_motor(),
        s3_5_4_software_reset_while_busy_is_aux_on(),
        s3_5_4_recovery_after_software_reset(),
    ]
}

/// Samples the energized phases every `step` over `span` (one batch);
/// returns the number of on-to-off and off-to-on changes seen. (Used where
/// nothing should chop; [`Driver::expect_chopping`] measures real chopping.)
fn count_chops(d: &mut Driver, step: Duration, span: Duration) -> Result<(u32, u32), ppmc::scenario::Stop> {
    let n = (span.as_nanos() / step.as_nanos().max(1)) as usize + 1;
    let samples = d.sample_pins(step, n)?;
    let (mut offs, mut ons) = (0, 0);
    for w in samples.windows(2) {
        let (a, b) = (w[0].1.phases != 0, w[1].1.phases != 0);
        if a && !b {
            offs += 1;
        }
        if !a && b {
            ons += 1;
        }
    }
    Ok((offs, ons))
}

/// with stop switching on, the phases chop at about 5.8 kHz once HOLD is on
#[scenario(tags("auxiliary", "switching", "phases"))]
fn s3_5_1_default_switching_chops_the_phases(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::four_phase().stop_switching())?;
    // Diagram 3-5: 65 us ON, 108.75 us OFF at 16 MHz.
    let (on, off) = (d.fw(us(65)), d.fw(Duration::from_nanos(108_750)));
    d.expect_chopping(on, off, Duration::from_nanos(250))?;
    d.run(Move::accel(Cw, 20))?;
    // HOLD comes on 3.4 ms after the last pulse at 16 MHz (Table 3-3).
    let (offs, _) = count_chops(d, us(5), d.fw(ms(3)))?;
    d.check("no chopping until HOLD", 0, offs)
}

/// Pon = 10, Poff = 20 give 57 us on, 93 us off (Equations 3-5, 3-6)
#[scenario(tags("auxiliary", "switching", "phases"))]
fn s3_5_1_switching_parameters(d: &mut Driver) -> Outcome {
    d.command(0x84)?;
    d.data(10)?;
    d.data(20)?;
    d.expect_no_error()?;
    d.init_and_wait(Init::four_phase().stop_switching())?;
    let (on, off) = (d.straps().switching_on_time(10), d.straps().switching_off_time(20));
    d.expect_chopping(on, off, Duration::from_nanos(250))
}

/// the switching parameter command is refused during BUSY (error 1)
#[scenario(tags("auxiliary", "switching", "error", "busy"))]
fn s3_5_1_switching_parameters_while_busy(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::four_phase())?;
    d.start(Move::accel(Cw, 500))?;
    d.command(0x84)?;
    d.expect_error(ErrorCode::NotAllowedWhileBusy)
}

/// AUX ON / OFF work before initialization, 14 us each (Table 3-3)
#[scenario(tags("auxiliary", "aux", "timing"))]
fn s3_5_2_aux_on_off_before_initialization(d: &mut Driver) -> Outcome {
    d.expect_pins(None, None, Some(false), Some(0))?;
    d.trigger_command(0xC1)?;
    d.wait(d.fw(us(50)))?;
    d.expect_latency(TimingId::AuxOn)?;
    d.expect_no_error()?;
    d.expect_pins(None, None, Some(true), None)?;
    d.trigger_command(0xC2)?;
    d.wait(d.fw(us(50)))?;
    d.expect_latency(TimingId::AuxOff)?;
    d.expect_pins(None, None, Some(false), None)
}

/// AUX ON is taken during a move without disturbing it
#[scenario(tags("auxiliary", "aux", "busy"))]
fn s3_5_2_aux_on_while_busy(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::four_phase())?;
    d.start(Move::accel(Cw, 500))?;
    d.trigger_command(0xC1)?;
    d.wait(d.fw(us(50)))?;
    d.expect_no_error()?;
    d.expect_latency(TimingId::AuxOn)?;
    d.wait_idle()?;
    d.expect_pulses(500, Cw)?;
    d.expect_pins(None, None, Some(true), None)
}

/// a 1 bit drives AUXO low; the upper nibble is ignored; works while BUSY
#[scenario(tags("auxiliary", "auxo", "busy"))]
fn s3_5_3_aux_output_drives_auxo(d: &mut Driver) -> Outcome {
    d.command(0x86)?;
    d.data(0b0101)?;
    d.wait(d.fw(us(50)))?;
    d.expect_pins(None, None, None, Some(0b0101))?;
    d.init_and_wait(Init::four_phase())?;
    d.start(Move::accel(Cw, 500))?;
    d.command(0x86)?;
    d.data(0xFA)?;
    d.wait(d.fw(us(50)))?;
    d.expect_no_error()?;
    d.expect_pins(None, None, None, Some(0b1010))?;
    d.wait_idle()?;
    d.expect_pulses(500, Cw)
}

/// software reset turns the phases off in 18 us (Table 3-3) and cancels initialization
#[scenario(tags("auxiliary", "reset", "timing", "phases"))]
fn s3_5_4_software_reset_frees_the_motor(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::four_phase())?;
    d.expect_phases(0b11000)?;
    d.trigger_command(0xC0)?;
    d.wait(d.fw(us(50)))?;
    d.expect_latency(TimingId::ExcitationOff)?;
    d.expect_phases(0)?;
    d.command(Move::single_step(Cw).code())?;
    d.expect_error(ErrorCode::NotInitialized)
}

/// software reset during a move is taken as AUX ON
#[scenario(tags("auxiliary", "reset", "aux", "busy"))]
fn s3_5_4_software_reset_while_busy_is_aux_on(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::four_phase())?;
    d.start(Move::accel(Cw, 500))?;
    d.command(0xC0)?;
    d.wait_idle()?;
    d.expect_pulses(500, Cw)?;
    d.expect_pins(None, None, Some(true), None)?;
    d.run(Move::single_step(Cw))?;
    d.expect_pulses(1, Cw)
}

/// after a reset the chip takes a new initialization with another excitation and moves
#[scenario(tags("auxiliary", "reset", "recovery", "phases"))]
fn s3_5_4_recovery_after_software_reset(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::four_phase())?;
    d.run(Move::accel(Cw, 101))?;
    d.command(0xC0)?;
    d.init_and_wait(Init::four_phase().half_step())?;
    d.expect_phases(0b10000)?;
    d.run(Move::accel(Cw, 3))?;
    d.expect_pulses(3, Cw)?;
    // S1 -> S1S2 -> S2 -> S2S3.
    d.expect_phases(0b01100)?;
    d.expect_finish(0x83)
}

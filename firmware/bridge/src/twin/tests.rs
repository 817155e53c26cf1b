//! The board code on the twin, held to the RP2350's rules, and the image's
//! defects before issue 28, each reproduced (in the model, on the old
//! program or configuration) and each shown fixed.

use super::pio::{Inputs, World};
use super::*;
use crate::pins;
use ppmc_core::bus::{Bus, EmuBus, Op, Reply, SelfTestPlan};
use ppmc_core::protocol::Status;
use ppmc_core::time::Duration;
use std::string::ToString;
use std::vec::Vec;

fn twin() -> TwinBoard {
    board(Straps::default(), ModelConfig::default()).expect("the twin boots")
}

/// docs/examples/accel-1000-steps.ppmc, as ops: initialization, then 1,000
/// steps CW with accel/decel (Section 3-2).
fn accel_move(steps: u32) -> Vec<Op> {
    let mut ops = init_and_move(20, Duration::from_millis(200), 0x43, steps);
    ops.extend([
        Op::AwaitStatus {
            mask: Status::BUSY,
            value: Status::BUSY,
            timeout: Duration::from_millis(1),
        },
        Op::AwaitStatus {
            mask: Status::BUSY,
            value: 0,
            timeout: Duration::from_secs(2),
        },
        Op::ReadPulses,
    ]);
    ops
}

fn run(bus: &mut impl Bus, ops: &[Op]) -> Vec<Reply> {
    ops.iter().map(|op| bus.run(*op)).collect()
}

/// `ops` run as the engine runs a batch: each op told the one after it
/// (`Bus::next_op`), so that delays aim the next op's moment.
fn run_as_engine(b: &mut TwinBoard, ops: &[Op]) -> Vec<Reply> {
    (0..ops.len())
        .map(|i| {
            b.next_op(ops.get(i + 1).copied());
            b.run(ops[i])
        })
        .collect()
}

/// The times of the pin reads among `replies`, in ns.
fn pin_read_times(replies: &[Reply]) -> Vec<u64> {
    replies
        .iter()
        .filter_map(|r| match r {
            Reply::Pins { at, .. } => Some(at.as_nanos()),
            _ => None,
        })
        .collect()
}

/// The pulse times of the last move, in ns.
fn pulse_times(bus: &impl Bus) -> Vec<u64> {
    bus.record()
        .runs
        .iter()
        .flat_map(|r| {
            let n = u64::from(r.count.saturating_sub(1)).max(1);
            (0..u64::from(r.count)).map(move |i| r.start.as_nanos() + r.span.as_nanos() * i / n)
        })
        .collect()
}

#[test]
fn a_move_on_the_twin_is_the_models_move_to_the_timers_tick() {
    // Section 3-2, through the board code, the PIO model and the chip.
    let ops = accel_move(1000);
    let mut emu = EmuBus::new(Straps::default(), ModelConfig::default()).expect("model");
    let want = run(&mut emu, &ops);
    let mut b = twin();
    let got = run(&mut b, &ops);
    assert_eq!(b.fault(), None);
    assert!(!b.capture_lost());
    // The same status and pulse summary.
    assert!(
        matches!(got[0], Reply::ResetDone { .. }),
        "reset: {:?}",
        got[0]
    );
    let summary = |r: &Reply| match r {
        Reply::Pulses { summary, .. } => (summary.count, summary.cw, summary.ccw),
        other => panic!("not a pulse summary: {other:?}"),
    };
    assert_eq!(summary(&got[13]), summary(&want[13]));
    assert_eq!(summary(&got[13]).0, 1000);
    // Every interval as the model's, to two timer ticks (26.7 ns) and the
    // cycles between the bus write and the chip taking it.
    let (t, e) = (pulse_times(&b), pulse_times(&emu));
    assert_eq!(t.len(), e.len());
    let offset = t[0] as i64 - e[0] as i64;
    for (i, (a, m)) in t.iter().zip(&e).enumerate() {
        let err = *a as i64 - *m as i64 - offset;
        assert!(
            err.abs() <= 27,
            "pulse {i}: {a} ns on the twin, {m} ns in the model"
        );
    }
    let hw = b.hal();
    assert_eq!(hw.chip.contention, 0, "nobody drove against the shifter");
    assert_eq!(hw.chip.floating, 0, "no buffered line floated");
    for blk in &hw.world.blocks {
        assert_eq!(
            blk.fdebug() >> pioregs::fdebug::TXOVER & 0xF,
            0,
            "no step lost"
        );
    }
}

#[test]
fn the_board_code_never_writes_a_full_fifo_whatever_the_cpus_pace() {
    // Defect 4: every step written only when the TX FIFO has room, with
    // the CPU at random paces.
    for seed in 1..6u64 {
        let mut b = crate::board::Board::new(
            Twin::new(Straps::default(), ModelConfig::default())
                .expect("boots")
                .with_gaps(seed, 40 * seed),
            BusTiming::DEFAULT,
            Straps::default(),
        );
        let ops = accel_move(20);
        let got = run(&mut b, &ops);
        assert!(matches!(got[13], Reply::Pulses { summary, .. } if summary.count == 20));
        let hw = b.hal();
        assert_eq!(
            hw.world.blocks[0].fdebug() >> pioregs::fdebug::TXOVER & 1,
            0
        );
        assert_eq!(hw.chip.contention, 0, "seed {seed}");
    }
}

#[test]
fn a_stuck_bus_player_is_a_hardware_fault_within_its_deadline() {
    // Defect 7: a state machine that never finishes a cycle.
    let mut b = twin();
    b.run(Op::Reset);
    b.hal_mut().stop_bus_player();
    let before = b.hal().world.cycle;
    b.run(Op::ReadStatus);
    let waited = b.hal().world.cycle - before;
    let fault = b.fault().expect("a hardware fault").to_string();
    assert!(fault.contains("bus player"), "{fault}");
    assert!(
        waited < 2 * SYSCLK_HZ as u64 / 1000,
        "gave up within 2 ms: {waited} cycles"
    );
}

#[test]
fn a_minute_of_idle_records_no_phantom_edge() {
    // Defect 3: the counters pass X = 0 (every 2^32 ticks, 57.3 s) with no
    // edge recorded. 61 s of virtual time.
    let mut b = twin();
    b.run(Op::Reset);
    b.run(Op::Delay(Duration::from_secs(61)));
    b.run(Op::ReadStatus);
    assert!(b.record().runs.is_empty(), "{:?}", b.record().runs);
    assert!(
        b.record().pins.iter().all(|p| !matches!(
            p.pin,
            ppmc_core::protocol::Pin::Int
                | ppmc_core::protocol::Pin::Hold
                | ppmc_core::protocol::Pin::Aux
        )),
        "{:?}",
        b.record().pins
    );
    assert!(!b.capture_lost());
    // The counters did pass zero.
    assert!(b.hal().world.cycle > 2 * (1u64 << 32));
}

#[test]
fn an_overrun_is_reported_and_the_next_capture_is_on_time() {
    // Defect 8: a CPU that does not drain the capture while 1,000 pulses
    // come 42 us apart: the POUT counter stalls on its full FIFO.
    let mut b = twin();
    b.hal_mut().idle_step = 150 * 20_000; // looks every 20 ms
    let mut ops = accel_move(1000);
    ops.insert(12, Op::Delay(Duration::from_millis(100)));
    run(&mut b, &ops);
    assert!(b.capture_lost(), "the overrun is reported");
    assert!(b.overruns >= 1);
    // Then the next capture, drained as usual, is on time.
    b.hal_mut().idle_step = 2 * CPU_CYCLES;
    let ops = accel_move(1000);
    run(&mut b, &ops);
    assert!(!b.capture_lost());
    let mut emu = EmuBus::new(Straps::default(), ModelConfig::default()).expect("model");
    run(&mut emu, &ops);
    let (t, e) = (pulse_times(&b), pulse_times(&emu));
    assert_eq!(t.len(), 1000);
    // The model's bus cycles take no time; the twin's, and its status
    // polling for IBF between the command's bytes, some microseconds each:
    // a stalled counter would put it milliseconds off.
    let offset = t[0] as i64 - e[0] as i64;
    assert!(
        offset.abs() < 50_000,
        "first pulse {offset} ns off the model's"
    );
    for (a, m) in t.iter().zip(&e) {
        assert!((*a as i64 - *m as i64 - offset).abs() <= 27);
    }
}

/// The image before issue 28, kept to show the model catches its defects.
mod before {
    use crate::programs::{jmp_x_next, push_edge};
    use pio::{Assembler, JmpCondition, MovDestination, MovOperation, MovSource, Program};

    /// PIO1 held both counters: 13 + 23 words. `mov x, ~null`, then a low
    /// loop, the edge code, and a high loop; `both` also pushes falls.
    fn counter(both: bool) -> Program<32> {
        let mut a = Assembler::<32>::new();
        let (mut wrap_target, mut wrap_source) = (a.label(), a.label());
        let (mut low, mut rise, mut high, mut still_high) =
            (a.label(), a.label(), a.label(), a.label());
        a.mov(MovDestination::X, MovOperation::Invert, MovSource::NULL);
        a.bind(&mut wrap_target);
        a.bind(&mut low);
        a.jmp(JmpCondition::PinHigh, &mut rise);
        a.jmp(JmpCondition::XDecNonZero, &mut low);
        a.bind(&mut rise);
        jmp_x_next(&mut a);
        push_edge(&mut a, both.then_some(1));
        a.jmp(JmpCondition::XDecNonZero, &mut high);
        a.bind(&mut high);
        a.jmp(JmpCondition::PinHigh, &mut still_high);
        if both {
            let mut fall = a.label();
            a.jmp(JmpCondition::XDecNonZero, &mut fall);
            a.bind(&mut still_high);
            a.jmp(JmpCondition::XDecNonZero, &mut high);
            a.bind(&mut fall);
            push_edge(&mut a, Some(0));
            a.jmp(JmpCondition::XDecNonZero, &mut low);
        } else {
            a.jmp(JmpCondition::XDecNonZero, &mut low);
            a.bind(&mut still_high);
            a.jmp(JmpCondition::XDecNonZero, &mut high);
        }
        a.bind(&mut wrap_source);
        a.assemble_with_wrap(wrap_source, wrap_target)
    }

    pub fn rising() -> Program<32> {
        counter(false)
    }

    pub fn both() -> Program<32> {
        counter(true)
    }
}

#[test]
fn defect_1_two_counters_do_not_fit_one_block_and_the_layout_does() {
    let mut w = World::new();
    let (r, b) = (before::rising(), before::both());
    w.blocks[1].load(&r.code, 0).expect("13 words fit");
    // embassy-rp's load_program would place it after the first: 13 + 23.
    let err = w.blocks[1].load(&b.code, r.code.len() as u8);
    assert!(err.is_err(), "36 words in a 32-word block");
    let mut w = World::new();
    for (i, p) in programs::layout().iter().enumerate() {
        w.blocks[i]
            .load(p.words(), 0)
            .expect("one program per block fits");
        assert!(w.blocks[i].words_used() <= 32);
    }
    // The self-test's generator after the bus player in PIO0.
    let gen = programs::relocate(programs::test_gen(), programs::test_gen_origin());
    w.blocks[0]
        .load(gen.words(), programs::test_gen_origin())
        .expect("the bus player and the generator share PIO0");
    assert_eq!(w.blocks[0].words_used(), 21);
}

/// Pulses on GPIO 32 for a counter configured by `regs`: words pushed.
fn count_pulses_on_pout(regs: &pioregs::SmRegs, words: &[u16]) -> usize {
    let mut w = World::with_program(1, 16, words, 0, regs);
    let mut pushed = 0;
    let mut outside = Inputs(|c: u64, _, _| {
        let high = c % 200 > 100;
        (u64::from(high) << pins::POUT, 1 << pins::POUT | 1 << 16)
    });
    for _ in 0..2_000 {
        w.step(&mut outside);
        while w.pull(1, 0).is_some() {
            pushed += 1;
        }
    }
    pushed
}

#[test]
fn defect_2_the_jmp_pin_is_relative_to_gpiobase() {
    let p = programs::edge_counter(true);
    let ours = pioregs::pout_counter(&p, false);
    assert_eq!(
        count_pulses_on_pout(&ours, p.words()),
        10,
        "ten pulses on GPIO 32"
    );
    // embassy-rp 0.10 writes the GPIO number raw into the 5-bit field:
    // 32 & 31 = 0, which with GPIOBASE 16 is GPIO 16.
    let mut embassy = ours;
    embassy.execctrl &= !(0x1F << pioregs::execctrl::JMP_PIN);
    embassy.execctrl |= (pins::POUT & 0x1F) << pioregs::execctrl::JMP_PIN;
    assert_eq!(
        count_pulses_on_pout(&embassy, p.words()),
        0,
        "it watched GPIO 16"
    );
}

/// Words pushed by a counter started with X at `x`, no edge at all, over
/// `cycles`.
fn idle_pushes(words: &[u16], regs: &pioregs::SmRegs, x: u32, cycles: u64) -> usize {
    let mut regs = *regs;
    regs.x = x;
    let mut w = World::with_program(1, 16, words, 0, &regs);
    // X as a long run leaves it (`set x` takes 5 bits only).
    w.blocks[1].sm[0].set_x(x);
    let mut n = 0;
    // Every input driven low: no edge at all (an undriven one would float).
    let mut outside = Inputs(|_, _, _| (0, 0xFFFF_FFFF << 16));
    for _ in 0..cycles {
        w.step(&mut outside);
        while w.pull(1, 0).is_some() {
            n += 1;
        }
    }
    n
}

#[test]
fn defect_3_passing_x_zero_pushes_nothing() {
    let p = programs::edge_counter(true);
    let regs = pioregs::pout_counter(&p, false);
    assert_eq!(idle_pushes(p.words(), &regs, 20, 200), 0);
    let b = programs::edge_counter(false);
    let regs_b = pioregs::pin_counters(&b, [false; 3])[0];
    assert_eq!(idle_pushes(b.words(), &regs_b, 20, 200), 0);
    // The old program, started in its low loop, falls into its edge code.
    let old = before::rising();
    let mut old_regs = regs;
    old_regs.execctrl = regs.execctrl & !(0x1F << 7 | 0x1F << 12)
        | u32::from(old.wrap.source) << 12
        | u32::from(old.wrap.target) << 7;
    old_regs.start = 1;
    assert!(
        idle_pushes(&old.code, &old_regs, 20, 200) > 0,
        "a phantom edge"
    );
}

#[test]
fn defect_4_writing_a_cycle_without_looking_loses_steps() {
    // The image pushed every step of a cycle without looking at TXFULL; a
    // read right after a write finds the FIFO (4 deep) busy.
    let p = programs::bus_player();
    let mut w = World::with_program(0, 0, p.words(), 0, &pioregs::bus_player(&p));
    let t = BusTiming::DEFAULT;
    let mut outside = Inputs(|_, _, _| (0, 0));
    for c in [
        crate::bus_cycle::Cycle::Write { a0: true, byte: 1 },
        crate::bus_cycle::Cycle::Read { a0: true },
    ] {
        for s in t.steps(c, SYSCLK_HZ).expect("fits").words() {
            w.blocks[0].txf_write(0, *s);
        }
        w.step(&mut outside);
    }
    assert_ne!(
        w.blocks[0].fdebug() >> pioregs::fdebug::TXOVER & 1,
        0,
        "steps were lost (FDEBUG.TXOVER)"
    );
}

#[test]
fn a_write_is_stamped_at_wr_rising_and_a_read_at_rd_falling() {
    // Section 3-1: the chip takes a byte on WR*'s rising edge and answers
    // a read from RD*'s falling edge. The board code stamps each cycle at
    // that moment, predicted from the steps it wrote, within a tick (two
    // cycles) of where the chip saw it: also when the CPU is slow between
    // steps and the player waits for them.
    for gaps in [None, Some((0x9E37_79B9_7F4A_7C15, 400))] {
        let mut hw = Twin::new(Straps::default(), ModelConfig::default()).expect("boots");
        if let Some((seed, max)) = gaps {
            hw = hw.with_gaps(seed, max);
        }
        let mut b = crate::board::Board::new(hw, BusTiming::DEFAULT, Straps::default());
        b.run(Op::Reset);
        let tick = Duration::from_nanos(1_000_000_000 / crate::timebase::timer_hz(SYSCLK_HZ));
        for i in 0..200u32 {
            let (reply, seen) = if i % 3 == 0 {
                let r = b.run(Op::ReadStatus);
                (r, b.hal().chip.last_read)
            } else {
                let r = b.run(Op::WriteData {
                    byte: i as u8,
                    wait_ibf: None,
                });
                (r, b.hal().chip.last_write)
            };
            let at = match reply {
                Reply::Written { at, .. } | Reply::Status { at, .. } => at,
                other => panic!("{other:?}"),
            };
            let chip = b.time_of_cycle(seen);
            let off = at.as_nanos().abs_diff(chip.as_nanos());
            assert!(
                off <= tick.as_nanos(),
                "op {i} (gaps {gaps:?}): stamped {at}, the chip saw it at {chip}"
            );
        }
    }
}

#[test]
fn a_delay_counts_from_the_last_ops_moment_and_the_next_op_acts_on_time() {
    // A script's delay is the time from one op's moment to the next's
    // (`Bus::next_op`): after the pulse `AwaitPulses` waited for, the
    // command is written (WR* rising) `d` later, as on the reference model,
    // to a tick; an input changes within the last pass of a spin on the
    // clock and a GPIO write. Not late by the capture's delay or the
    // write's own bus cycles (a microsecond, before issue 28's twin).
    let d = Duration::from_nanos(25_600);
    for write in [false, true] {
        let mut b = twin();
        let mut ops = accel_move(5_000);
        ops.truncate(ops.len() - 3);
        run_as_engine(&mut b, &ops);
        let trigger = if write {
            Op::WriteCommand {
                byte: 0x08,
                wait_ibf: Some(Duration::from_millis(1)),
            }
        } else {
            Op::SetInput {
                input: ppmc_core::protocol::Input::L3,
                asserted: true,
            }
        };
        // Twice: the second delay knows how long the op took the first time.
        for n in [100, 200] {
            let replies = run_as_engine(
                &mut b,
                &[
                    Op::AwaitPulses {
                        count: n,
                        timeout: Duration::from_secs(1),
                    },
                    Op::Delay(d),
                    trigger,
                ],
            );
            let pulse = match replies[0] {
                Reply::PulsesReached { at } => at,
                ref r => panic!("{r:?}"),
            };
            let acted = match replies[2] {
                Reply::Written { at, .. } => b.time_of_cycle(b.hal().chip.last_write).max(at),
                Reply::InputSet { at } => at,
                ref r => panic!("{r:?}"),
            };
            let late = acted.as_nanos() as i64 - (pulse + d).as_nanos() as i64;
            let within = if write { 27 } else { 150 };
            assert!(
                (0..=within).contains(&late),
                "write {write}, pulse {n}: acted {late} ns off ({pulse} + {d} vs {acted})"
            );
        }
    }
}

#[test]
fn a_wait_for_a_pulse_already_past_ends_when_it_starts() {
    // A reply is stamped when its op ended (`Reply`); a wait for a pulse
    // that came before the wait began ends at once, as the reference
    // model's does (`EmuBus`), not back at the pulse: the bridge's clock
    // never goes back between replies (the host takes a clock that went
    // back for a bridge restarted behind its port). Found by the
    // unmodified image on rp2350-emu, whose CPU took longer over a decel
    // stop than pulses 300 to 330 took (e7_second_decel_stop), where the
    // twin is quick.
    let mut b = twin();
    let mut ops = accel_move(5_000);
    ops.truncate(ops.len() - 2);
    ops.extend([
        Op::Delay(Duration::from_millis(20)),
        Op::ReadPulses,
        Op::AwaitPulses {
            count: 10,
            timeout: Duration::from_secs(1),
        },
    ]);
    let replies = run_as_engine(&mut b, &ops);
    let n = replies.len();
    let before = match replies[n - 2] {
        Reply::Pulses { at, summary } => {
            assert!(summary.count > 10, "pulse 10 already past: {summary:?}");
            at
        }
        ref r => panic!("{r:?}"),
    };
    let reached = match replies[n - 1] {
        Reply::PulsesReached { at } => at,
        ref r => panic!("{r:?}"),
    };
    assert!(
        reached >= before,
        "the wait ended at {reached}, before the op ahead of it ({before})"
    );
    assert!(
        reached.as_nanos() - before.as_nanos() < 20_000,
        "the wait ended at {reached}, long after it began ({before})"
    );
}

#[test]
fn the_pulses_counted_as_they_come_are_the_records_count() {
    // `Board::move_pulses` counts the last move's runs as they close, so
    // that a wait for a pulse does not count a ramp's runs (one a pulse)
    // again after every drain; it must agree with the record's own count
    // through a move, at its end, and after a chip reset and a new move.
    let mut b = twin();
    let mut ops = accel_move(2_000);
    ops.truncate(ops.len() - 2);
    for n in [1, 100, 700, 1_500] {
        ops.push(Op::AwaitPulses {
            count: n,
            timeout: Duration::from_secs(1),
        });
    }
    ops.push(Op::AwaitStatus {
        mask: Status::BUSY,
        value: 0,
        timeout: Duration::from_secs(2),
    });
    let mut checked = 0;
    for round in 0..2 {
        for i in 0..ops.len() {
            b.next_op(ops.get(i + 1).copied());
            b.run(ops[i]);
            let counted = b.move_pulses();
            assert_eq!(
                counted,
                b.record().last_move_pulses().count,
                "round {round}, after op {i} ({:?})",
                ops[i]
            );
            checked += u64::from(counted > 0);
        }
        assert_eq!(b.move_pulses(), 2_000, "round {round}");
        // A chip reset starts the record again: the count with it.
        b.next_op(None);
        b.run(Op::Reset);
        assert_eq!(b.move_pulses(), 0);
    }
    // After each wait and at each move's end, in both rounds (a wait
    // that found its pulse among words not drained counts nothing new).
    assert!(checked >= 6, "counted through the moves: {checked}");
}

#[test]
fn a_pulse_found_among_words_not_drained_has_the_records_time() {
    // A wait for a pulse looks for it among the POUT words not drained
    // yet: the time it answers is the one the record gives that pulse
    // once drained, for pulses at any point of a move.
    let mut b = twin();
    let mut ops = accel_move(2_000);
    ops.truncate(ops.len() - 2);
    let targets = [1u64, 2, 150, 700, 1_999];
    for n in targets {
        ops.push(Op::AwaitPulses {
            count: n,
            timeout: Duration::from_secs(1),
        });
    }
    ops.push(Op::AwaitStatus {
        mask: Status::BUSY,
        value: 0,
        timeout: Duration::from_secs(2),
    });
    let replies = run_as_engine(&mut b, &ops);
    use ppmc_core::time::Instant;
    let pulses: Vec<Instant> = b.record().pulses().map(|(t, _)| t).collect();
    assert_eq!(pulses.len(), 2_000);
    let reached: Vec<Instant> = replies
        .iter()
        .filter_map(|r| match r {
            Reply::PulsesReached { at } => Some(*at),
            _ => None,
        })
        .collect();
    let want: Vec<Instant> = targets.iter().map(|n| pulses[*n as usize - 1]).collect();
    assert_eq!(reached, want);
}

#[test]
fn steps_are_not_pin_changes_however_often_the_outputs_are_sampled() {
    // Status reads back to back through a move, by a CPU as quick as the
    // RP2350's (a cycle a hardware access: the image on rp2350-emu) drain
    // the capture between a pulse and the phase change it makes, or see
    // the change before the pulse's word is in its ring. Each change is
    // still that pulse's step, not a pin change of its own (each would be
    // a capture record: the 22,000-step triangle overran the capture).
    for cpu in [12, 4, 1] {
        let mut b = twin();
        b.hal_mut().cpu_cycles = cpu;
        let mut ops = accel_move(400);
        ops.truncate(ops.len() - 2);
        ops.extend(std::iter::repeat_n(Op::ReadStatus, 6_000));
        ops.push(Op::AwaitStatus {
            mask: Status::BUSY,
            value: 0,
            timeout: Duration::from_secs(2),
        });
        run_as_engine(&mut b, &ops);
        assert_eq!(b.record().last_move_pulses().count, 400);
        let phases = b
            .record()
            .pins
            .iter()
            .filter(|p| p.pin == ppmc_core::protocol::capture::Pin::Phases)
            .count();
        assert!(
            phases <= 2,
            "{cpu} cycles an access: {phases} steps recorded as pin changes"
        );
    }
}

#[test]
fn regular_pin_samples_stay_on_their_grid() {
    // `ReadPins, Delay(step)` pairs: each sample is read where its delay
    // aimed and stamped there, so that the bridge sends them as one
    // SAMPLES entry, as the reference model's are.
    let mut b = twin();
    let mut ops = accel_move(50);
    ops.truncate(7);
    // 250 ns apart, as the stop-switching scenarios sample (Section 3-5-1).
    let step = Duration::from_nanos(250);
    for _ in 0..40 {
        ops.extend([Op::ReadPins, Op::Delay(step)]);
    }
    let replies = run_as_engine(&mut b, &ops);
    let times = pin_read_times(&replies);
    assert_eq!(times.len(), 40);
    // Every step is `step` in the bridge's ticks (19 of 13.3 ns).
    let timer = b.timer();
    let ticks: Vec<u64> = times.iter().map(|t| timer.to_ticks(*t)).collect();
    for w in ticks.windows(2) {
        assert_eq!(w[1] - w[0], timer.to_ticks(step.as_nanos()), "{times:?}");
    }
}

#[test]
fn the_capture_keeps_up_at_the_chips_fastest_pulse_rate() {
    // 96 kpps (Section 3-2's speed limit at SysClk 40 MHz is 100 kpps)
    // while the board code polls status: every pulse captured, and the
    // POUT counter's FIFO never more than half full when drained.
    let m = capture_margin().expect("runs");
    assert_eq!(m.pulses, 5_000, "{m:?}");
    assert!(!m.lost, "{m:?}");
    assert!(m.fullest <= m.depth / 2, "{m:?}");
    assert!(m.margin() > 2.0, "{m:?}, margin {:.1}", m.margin());
}

#[test]
fn pins_sampled_every_250_ns_through_a_fast_move_lose_no_pulse() {
    // A tight run of pin samples drains the capture only when it must (a
    // look every 8 samples): at 96 kpps, every pulse is still captured.
    let (straps, mut ops) = fastest_move();
    ops.push(Op::AwaitPulses {
        count: 1_000,
        timeout: Duration::from_secs(1),
    });
    for _ in 0..4_000 {
        ops.extend([Op::ReadPins, Op::Delay(Duration::from_nanos(250))]);
    }
    ops.push(Op::AwaitStatus {
        mask: Status::BUSY,
        value: 0,
        timeout: Duration::from_secs(2),
    });
    let mut b = board(straps, ModelConfig::default()).expect("boots");
    run_as_engine(&mut b, &ops);
    assert!(!b.capture_lost());
    assert_eq!(b.record().last_move_pulses().count, 5_000);
}

fn self_test_plan(count: u32, high_ns: u64, low_ns: u64, bursts: u16) -> SelfTestPlan {
    SelfTestPlan {
        count,
        high: Duration::from_nanos(high_ns),
        low: Duration::from_nanos(low_ns),
        bursts,
        gap: Duration::from_micros(50),
    }
}

/// INT*'s changes in the record, in ns, with their values.
fn int_changes(bus: &impl Bus) -> Vec<(u64, u8)> {
    bus.record()
        .pins
        .iter()
        .filter(|p| p.pin == ppmc_core::protocol::Pin::Int)
        .map(|p| (p.at.as_nanos(), p.value))
        .collect()
}

#[test]
fn the_self_test_generator_is_captured_on_pout_and_int_where_the_board_code_said() {
    // Issue 28, item 7: TEST_GEN through 1 kOhm onto the capture inputs of
    // POUT and INT*, with CAPTURE_OE* high (the chip's outputs cut off).
    // Two bursts of 100 pulses at 100 kpps, the chip's fastest rate.
    let mut b = twin();
    let plan = self_test_plan(100, 5_000, 5_000, 2);
    let reply = b.self_test(&plan).expect("the board has a generator");
    assert_eq!(reply.starts.len(), 2);
    assert_eq!(
        (reply.high.as_nanos(), reply.low.as_nanos()),
        (5_000, 5_000)
    );
    assert!(!b.capture_lost());
    let period = 10_000;
    let want: Vec<u64> = reply
        .starts
        .iter()
        .flat_map(|s| (0..100).map(move |k| s.as_nanos() + k * period))
        .collect();
    let got = pulse_times(&b);
    assert_eq!(got.len(), want.len(), "every pulse captured, no other");
    let offsets: Vec<i64> = got
        .iter()
        .zip(&want)
        .map(|(g, w)| *g as i64 - *w as i64)
        .collect();
    let lo = offsets.iter().min().expect("pulses");
    let hi = offsets.iter().max().expect("pulses");
    // The counters see an edge after the 2-cycle synchroniser and a pass of
    // their loop: a few cycles late, the same few every time.
    assert!(
        (0..=60).contains(lo) && hi - lo <= 14,
        "offsets {lo}..{hi} ns"
    );
    // INT* follows TEST_GEN (asserted, 1, while it is low): a rise
    // releases it, a fall asserts it, each at its predicted time.
    let int = int_changes(&b);
    let window = |t: u64| t >= want[0] - 100 && t <= want[want.len() - 1] + period;
    let int: Vec<(u64, u8)> = int.into_iter().filter(|(t, _)| window(*t)).collect();
    assert_eq!(int.len(), 400, "both edges of every pulse");
    for (i, (t, v)) in int.iter().enumerate() {
        let rise = want[i / 2];
        let (edge, value) = if i % 2 == 0 {
            (rise, 0)
        } else {
            (rise + 5_000, 1)
        };
        assert_eq!(*v, value, "change {i}");
        let d = *t as i64 - edge as i64;
        assert!((0..=60).contains(&d), "change {i}: {d} ns from its edge");
    }
    // The chip has its outputs back: a move after it is captured as ever.
    let replies = run(&mut b, &accel_move(100));
    assert!(matches!(replies.last(), Some(Reply::Pulses { summary, .. }) if summary.count == 100));
}

#[test]
fn a_self_test_beyond_the_captures_limit_is_reported_and_the_next_is_on_time() {
    // 2,000 pulses 240 ns apart (4.2 MHz, as `ppmc selftest` makes them):
    // INT*'s counter pushes two words a pulse, faster than the CPU drains
    // its ring, and 4,000 changes are more than the capture holds. The
    // capture must say it lost some, never hand over a short one.
    let mut b = twin();
    let fast = self_test_plan(2_000, 120, 120, 1);
    b.self_test(&fast).expect("runs");
    let held = b.record().runs.len() + b.record().pins.len();
    assert!(
        b.capture_lost() || held > crate::limits::CAPTURE_RECORDS as usize,
        "an overrun: lost {}, {held} records",
        b.capture_lost()
    );
    let most = crate::limits::CAPTURE_RECORDS as usize + crate::limits::OP_RECORDS;
    assert!(
        held <= most,
        "{held} records: the board code stops at {most}"
    );
    // The next self-test starts afresh and is on time.
    let slow = self_test_plan(20, 10_000, 40_000, 1);
    let reply = b.self_test(&slow).expect("runs");
    assert!(!b.capture_lost());
    let got = pulse_times(&b);
    assert_eq!(got.len(), 20);
    let d = got[0] as i64 - reply.starts[0].as_nanos() as i64;
    assert!((0..=60).contains(&d), "first pulse {d} ns from its start");
}

#[test]
fn a_self_test_the_generator_cannot_make_is_refused_with_its_limits() {
    let mut b = twin();
    let e = b
        .self_test(&self_test_plan(10, 5, 5, 1))
        .expect_err("too short");
    assert!(e.contains("at least"), "{e}");
}

#[test]
fn changes_shorter_than_the_both_edge_counters_path_are_missed_and_the_selftests_are_not() {
    // A limit of the edge counters, not of the drain: after an edge a
    // program runs its push path before it looks at the pin again. 100
    // pulses 18 cycles high and low (120 ns, the self-test's fastest) are
    // all seen on POUT and INT*; 8 cycles (53 ns) are all seen on POUT,
    // whose path is shorter, but not on INT*, and nothing says so (the
    // self-test's host side counts them: `ppmc selftest`).
    let mut b = twin();
    b.self_test(&self_test_plan(100, 120, 120, 1))
        .expect("runs");
    assert!(!b.capture_lost());
    assert_eq!(pulse_times(&b).len(), 100);
    assert_eq!(int_changes(&b).len(), 200);
    b.self_test(&self_test_plan(100, 53, 53, 1)).expect("runs");
    assert!(!b.capture_lost());
    assert_eq!(pulse_times(&b).len(), 100);
    let seen = int_changes(&b).len();
    assert!(seen < 200, "{seen} of 200 INT* changes 8 cycles apart");
}

/// The phase outputs' changes (S1..S5, energized) of a record, in order.
fn phase_changes(r: &ppmc_core::protocol::OutputRecord) -> Vec<(u8, u64)> {
    use ppmc_core::protocol::Pin;
    r.pins
        .iter()
        .filter(|e| e.pin == Pin::Phases)
        .map(|e| (e.value, e.at.as_nanos()))
        .collect()
}

#[test]
fn sampled_changes_and_polled_waits_are_within_what_hello_declares() {
    // docs/bridge-protocol.md section 4: HELLO_REPLY's `sampled` and
    // `polled` uncertainty. The board code stamps a change of S1..S5
    // halfway between its last sight of the old levels and its first of
    // the new, and a wait's end halfway through its loop's last pass; under
    // the loads that stretch those (a tight run of pin samples, delays, a
    // move awaited by polling), each bracket stays within what the board
    // declares, and each change of the phases lies within the declared
    // `sampled` of the chip model's own moment for it: turned on by an
    // initialization (Section 3-2), off by a software reset (3-5-4).
    let wait = Some(Duration::from_millis(10));
    let mut ops = std::vec![Op::Reset];
    let init = |ops: &mut Vec<Op>| {
        ops.push(Op::WriteCommand {
            byte: 0x02,
            wait_ibf: wait,
        });
        for byte in [100, 20, 100, 0] {
            ops.push(Op::WriteData {
                byte,
                wait_ibf: wait,
            });
        }
    };
    init(&mut ops);
    for _ in 0..2_000 {
        ops.extend([Op::ReadPins, Op::Delay(Duration::from_nanos(250))]);
    }
    ops.push(Op::Delay(Duration::from_millis(2)));
    // A CCW move of 100 steps, awaited by polling.
    ops.push(Op::WriteCommand {
        byte: 0x4B,
        wait_ibf: wait,
    });
    for byte in [99, 0, 0] {
        ops.push(Op::WriteData {
            byte,
            wait_ibf: wait,
        });
    }
    ops.push(Op::AwaitStatus {
        mask: Status::BUSY,
        value: 0,
        timeout: Duration::from_secs(2),
    });
    // Excitation off (a software reset), sampled in a tight run.
    ops.push(Op::WriteCommand {
        byte: 0xC0,
        wait_ibf: wait,
    });
    for _ in 0..1_000 {
        ops.extend([Op::ReadPins, Op::Delay(Duration::from_nanos(250))]);
    }
    ops.push(Op::Delay(Duration::from_millis(1)));
    init(&mut ops);
    ops.push(Op::Delay(Duration::from_millis(1)));
    let mut b = twin();
    run_as_engine(&mut b, &ops);
    assert_eq!(b.fault(), None);
    let u = crate::board::Board::uncertainty(&b);
    let got = phase_changes(b.record());
    let want = phase_changes(b.hal().chip.model().record());
    assert_eq!(
        got.iter().map(|c| c.0).collect::<Vec<_>>(),
        want.iter().map(|c| c.0).collect::<Vec<_>>(),
        "on, off, on: as the model"
    );
    assert_eq!(got.len(), 3, "{got:?}");
    // The model's clock and the record's both start at the chip's reset,
    // within a tick of the timer.
    let tick = b.timer().to_nanos_up(1);
    for (g, w) in got.iter().zip(&want) {
        let err = g.1.abs_diff(w.1);
        assert!(
            err <= u.sampled.as_nanos() + tick,
            "phases {} at {} ns on the twin, {} ns in the model: {err} ns off, declared {}",
            g.0,
            g.1,
            w.1,
            u.sampled
        );
    }
    assert!(
        b.longest_bracket() <= u.sampled.saturating_mul(2),
        "a sampled change stamped in a bracket of {} (declared: within {})",
        b.longest_bracket(),
        u.sampled
    );
    assert!(
        b.longest_pass() <= u.polled.saturating_mul(2),
        "a wait's loop took {} a pass (declared: within {})",
        b.longest_pass(),
        u.polled
    );
}

/// Issue 43, defect 6 (RP2350 datasheet 11.4.6.2, PUSH): a `push noblock`
/// to a full RX FIFO goes on at once, the FIFO unchanged and the ISR
/// cleared, and sets FDEBUG.RXSTALL, as a blocking push or an autopush to
/// a full FIFO does, to say a word was lost.
#[test]
fn defect_6_a_push_noblock_to_a_full_rx_fifo_sets_rxstall() {
    use ::pio::{Instruction, InstructionOperands, SideSet};
    let push_noblock = Instruction {
        operands: InstructionOperands::PUSH {
            if_full: false,
            block: false,
        },
        delay: 0,
        side_set: None,
    }
    .encode(SideSet::default());
    // One instruction, wrapping onto itself; no join: four RX entries.
    let regs = pioregs::SmRegs {
        clkdiv: pioregs::CLKDIV_1,
        execctrl: 0,
        shiftctrl: 0,
        pinctrl: 0,
        start: 0,
        x: 0,
        side: None,
    };
    let mut w = World::with_program(1, 0, &[push_noblock], 0, &regs);
    let mut outside = Inputs(|_, _, _| (0, 0));
    let rxstall = |w: &World| w.blocks[1].fdebug() >> pioregs::fdebug::RXSTALL & 1;
    for _ in 0..4 {
        w.step(&mut outside);
    }
    assert_eq!(w.blocks[1].rx_level(0), 4, "four pushes fill the FIFO");
    assert_eq!(rxstall(&w), 0, "no word lost yet");
    w.step(&mut outside);
    assert_eq!(w.blocks[1].rx_level(0), 4, "the FIFO unchanged");
    assert_eq!(rxstall(&w), 1, "the lost word is flagged");
    assert_eq!(w.blocks[1].sm[0].pc(), 0, "and the program went on");
}

/// Each ring's channel is running, and where its count says it writes next
/// is where it does: the board code reads every word where the DMA put it.
fn channels_in_place(b: &mut TwinBoard) -> std::vec::Vec<std::string::String> {
    use crate::dma::{counter_channel, ctrl, reg, DmaRegs};
    let d = &mut TwinDma(&mut b.hal_mut().world);
    let mut wrong = Vec::new();
    for c in Counter::ALL {
        let ch = counter_channel(c, ring_addr(c.index()));
        let ctl = d.read(reg::ch(ch.channel, reg::CTRL_TRIG));
        if ctl & ctrl::BUSY == 0 || ctl & ctrl::EN == 0 || ctl & ctrl::AHB_ERROR != 0 {
            wrong.push(std::format!("{c:?}: CTRL {ctl:#010x}, not running"));
        }
        // Where the board code reads the next word, against where the
        // model's DMA writes it.
        let by_count = ch.write_index(d);
        let by_addr = (d.read(reg::ch(ch.channel, reg::WRITE_ADDR)) - ch.ring) as usize / 4;
        if by_count != by_addr {
            wrong.push(std::format!(
                "{c:?}: its count says it writes word {by_count} next, WRITE_ADDR word {by_addr}"
            ));
        }
    }
    wrong
}

#[test]
fn defect_1_a_channel_a_bus_error_halted_is_re_armed_and_the_others_keep_their_place() {
    // RP2350 datasheet 12.6.7: a bus error halts the channel, which the DMA
    // refuses to restart until software writes 1 to its error flag; 12.6.3:
    // a running channel ignores a trigger; 12.6.2: WRITE_ADDR is live.
    // A short move: the rule is the same for every length.
    let ops = accel_move(200);
    let mut b = twin();
    run(&mut b, &ops);
    assert!(!b.capture_lost());
    assert_eq!(channels_in_place(&mut b), Vec::<std::string::String>::new());
    // POUT's channel meets a bus error writing the next move's first word.
    b.hal_mut()
        .world
        .dma
        .inject(Counter::Pout.index(), pio::BusError::Write);
    run(&mut b, &ops);
    assert!(
        b.capture_lost(),
        "the halted channel's words are lost, and said so"
    );
    // Re-armed: every channel runs, each where the board code reads it.
    assert_eq!(channels_in_place(&mut b), Vec::<std::string::String>::new());
    // The next move is captured whole, as the model has it.
    run(&mut b, &ops);
    assert!(!b.capture_lost(), "the capture after the re-arm is whole");
    let mut emu = EmuBus::new(Straps::default(), ModelConfig::default()).expect("model");
    run(&mut emu, &ops);
    let (t, e) = (pulse_times(&b), pulse_times(&emu));
    assert_eq!(t.len(), 200);
    let offset = t[0] as i64 - e[0] as i64;
    for (a, m) in t.iter().zip(&e) {
        assert!((*a as i64 - *m as i64 - offset).abs() <= 27);
    }
    let values = |v: Vec<(u64, u8)>| v.into_iter().map(|(_, x)| x).collect::<Vec<_>>();
    assert_eq!(values(int_changes(&b)), values(int_changes(&emu)));
}

#[test]
fn the_twins_dma_follows_the_datasheets_trigger_error_and_abort_rules() {
    use crate::dma::{counter_channel, ctrl, reg, DmaRegs, Stuck};
    let mut t = Twin::new(Straps::default(), ModelConfig::default()).expect("boots");
    let ch = counter_channel(Counter::Int, ring_addr(Counter::Int.index()));
    let n = ch.channel;
    let d = &mut TwinDma(&mut t.world);
    let running = |d: &mut TwinDma| d.read(reg::ch(n, reg::CTRL_TRIG)) & ctrl::BUSY != 0;
    assert!(running(d), "started at boot");
    // 12.6.7.1: a bus error halts it; a trigger does not restart it while
    // its error flag is set (what the image's old re-arm relied on).
    d.0.dma.inject(n, pio::BusError::Read);
    d.0.dma.ch[n].busy = true;
    d.0.blocks[block::PINS].sm[0].pushed += 1; // a DREQ: one transfer
    d.0.dma.step(&mut d.0.blocks);
    let c = d.read(reg::ch(n, reg::CTRL_TRIG));
    assert_eq!(
        c & (ctrl::READ_ERROR | ctrl::AHB_ERROR | ctrl::BUSY),
        ctrl::READ_ERROR | ctrl::AHB_ERROR
    );
    ch.program(d);
    assert!(!running(d), "a trigger with READ_ERROR set is refused");
    // RP2350-E5: aborted with EN set, a TRIGGER_SELF channel starts again.
    d.write(reg::ch(n, reg::AL1_CTRL), ch.ctrl() | ctrl::READ_ERROR);
    d.write(reg::ch(n, reg::CTRL_TRIG), ch.ctrl());
    assert!(running(d));
    d.write(reg::CHAN_ABORT, 1 << n);
    assert!(running(d), "the abort's completion triggered it again");
    // The re-arm clears EN first: it stops, and starts afresh.
    assert_eq!(ch.rearm(d), Ok::<(), Stuck>(()));
    assert!(running(d));
    assert_eq!(d.read(reg::ch(n, reg::WRITE_ADDR)), ch.ring);
}

#[test]
fn defect_6_b_an_undriven_pad_with_no_pull_floats() {
    // RP2350 datasheet, the pads (a pad that nothing drives and neither
    // pull holds is left floating) and erratum RP2350-E9 (such an input
    // drifts): HOLD's capture input with the 74LVC245s off and no pull-up
    // must not read one level for ever, as a bus hold would keep it.
    let mut w = World::new();
    let mut nothing = Inputs(|_, _, _| (0u64, 0u64));
    let mut levels = std::collections::BTreeSet::new();
    for _ in 0..64 {
        let until = w.cycle + 20_000;
        w.run_until(until, &mut nothing);
        levels.insert(w.pads() >> pins::HOLD & 1);
    }
    assert_eq!(
        levels.len(),
        2,
        "HOLD's pad, undriven and unpulled, kept one level for 1.28 M cycles"
    );
}

#[test]
fn a_pull_holds_an_undriven_pad_and_the_self_test_pulls_what_it_leaves_undriven() {
    // The pads' pulls (PADS_BANK0 PUE/PDE): an undriven pad reads its
    // pull, and the board code pulls up every capture input the self-test
    // leaves undriven (pins::SELF_TEST_PULLED), as the image does.
    let mut w = World::new();
    w.pull_up |= 1 << pins::HOLD;
    w.pull_down |= 1 << pins::AUX;
    let mut nothing = Inputs(|_, _, _| (0u64, 0u64));
    for _ in 0..16 {
        let until = w.cycle + 20_000;
        w.run_until(until, &mut nothing);
        assert_eq!(w.pads() >> pins::HOLD & 1, 1, "pulled up");
        assert_eq!(w.pads() >> pins::AUX & 1, 0, "pulled down");
    }
    let mut b = twin();
    let hw = b.hal_mut();
    hw.gen_connect(true);
    for g in pins::SELF_TEST_PULLED {
        assert_eq!(
            hw.world.pull_up >> g & 1,
            1,
            "GPIO {g} pulled up in the self-test"
        );
    }
    hw.gen_connect(false);
    assert_eq!(hw.world.pull_up, 0, "and released after it");
}

#[test]
fn a_re_armed_channel_moves_the_words_its_fifo_still_holds() {
    // RP2350 datasheet 12.6.7.3: a faulting read is suppressed, so its word
    // stays in the FIFO, yet it took its DREQ credit when it was issued
    // (12.6.4.2). The re-arm must start the DREQ handshake afresh
    // (DBG_CTDREQ), or the words the FIFO holds wait for the next push.
    use crate::dma::{counter_channel, DmaRegs};
    let mut t = Twin::new(Straps::default(), ModelConfig::default()).expect("boots");
    let c = Counter::Int;
    let (b, s) = pioregs::counter_sm(c);
    let ch = counter_channel(c, ring_addr(c.index()));
    t.world.dma.inject(ch.channel, pio::BusError::Read);
    t.world.blocks[b].push_rx(s, 0x1234_5678);
    t.world.dma.step(&mut t.world.blocks);
    assert_eq!(
        t.world.blocks[b].rx_level(s),
        1,
        "the faulting read took nothing"
    );
    ch.rearm(&mut TwinDma(&mut t.world)).expect("stops");
    for _ in 0..4 {
        t.world.dma.step(&mut t.world.blocks);
    }
    assert_eq!(
        t.world.blocks[b].rx_level(s),
        0,
        "the word still in the FIFO was moved after the re-arm"
    );
    assert_eq!(TwinDma(&mut t.world).ring_word(ch.channel, 0), 0x1234_5678);
}

/// An ABORT (`docs/bridge-protocol.md` section 5) that comes while the
/// board code waits out a long, quiet DELAY ends the wait within about a
/// millisecond of the twin's time, and what the engine does next (its
/// look at BUSY before an Immediate Stop) acts then, not at the delay's
/// end: the board code idles in short stretches while an abort line is
/// installed, and a delay cut short aims nothing at its old end.
#[test]
fn an_abort_in_a_quiet_delay_ends_it_and_the_next_op_acts_at_once() {
    use ppmc_core::bridge::abort_line::AbortLine;
    use ppmc_core::bridge::engine::BridgeEngine;
    use ppmc_core::bridge::frame::{self, FrameDecoder};
    use ppmc_core::bridge::wire::{BridgeErrorCode, Request, Response};
    use std::sync::atomic::Ordering;
    let b = twin();
    let timer = b.timer();
    let progress = b.hal().progress.clone();
    let line = AbortLine::new();
    let mut engine = BridgeEngine::new(b, 1, true, "twin").with_abort(line.clone());
    // One second of the twin's time into the delay (150 MHz), the host's
    // ABORT arrives, naming the batch (sequence 1).
    // It says how far the twin had got once the line was up: on a busy
    // machine the thread comes late, and the twin runs on meanwhile.
    let raiser = std::thread::spawn(move || {
        while progress.load(Ordering::Relaxed) < 150_000_000 {
            std::thread::sleep(std::time::Duration::from_micros(200));
        }
        line.raise(1);
        progress.load(Ordering::Relaxed)
    });
    let batch = Request::Batch(std::vec![
        Op::Reset,
        Op::Delay(Duration::from_secs(30)),
        Op::ReadStatus,
    ]);
    let out = engine.on_bytes(&frame::encode(&batch.encode(1, timer)));
    let raised = raiser.join().expect("the raiser") * 1_000 / 150;
    let mut d = FrameDecoder::new();
    d.extend(&out);
    let payload = d.decode().expect("a frame").expect("a whole one");
    match Response::decode(&payload, timer).expect("decodes").1 {
        Response::Error {
            code: BridgeErrorCode::Aborted,
            detail,
        } => assert_eq!(detail, "stopped by ABORT after 2 ops"),
        other => panic!("not ABORTED: {other:?}"),
    }
    // Ended where the abort came, by the twin's clock (the twin's cycles
    // at 150 MHz, in ns), not at the delay's end 29 s on.
    let now = engine.bus().now().as_nanos();
    assert!(
        now >= 1_000_000_000 && now <= raised + 100_000_000,
        "the wait and the look after it end where the abort came ({raised} ns): {now} ns"
    );
}

#[test]
fn a_status_read_right_after_a_write_sees_the_byte_waiting() {
    // Section 3-1-1: IBF is 1 from a write until the chip takes the byte
    // (within microseconds: 6 us on the model, notes N11). A status read
    // next in the batch is played behind the write, however slow the
    // board code between ops: at 40 cycles a hardware access the ops
    // between had put the read past the chip's taking of the byte (the
    // image on rp2350-emu: 20 us), and IBF read 0
    // (`s3_1_1_ibf_clears_when_the_chip_takes_a_byte`).
    for cpu in [12, 40] {
        let mut b = twin();
        b.hal_mut().cpu_cycles = cpu;
        let ops = [
            Op::Reset,
            Op::WriteCommand {
                byte: 0x02,
                wait_ibf: None,
            },
            Op::ReadStatus,
            Op::ReadStatus,
        ];
        let replies = run_as_engine(&mut b, &ops);
        let (Reply::Written { at: wrote, .. }, Reply::Status { at: read, status }) =
            (replies[1], replies[2])
        else {
            panic!("{cpu} cycles an access: replies {replies:?}");
        };
        assert!(
            status.ibf(),
            "{cpu} cycles an access: IBF 0 at {read}, {} after the write",
            read.saturating_since(wrote)
        );
        assert!(
            read.saturating_since(wrote) < Duration::from_micros(2),
            "{cpu} cycles an access: read {} after the write",
            read.saturating_since(wrote)
        );
        // The read after it is an op of its own, and stamped after it.
        assert!(replies[3].at() > read, "{replies:?}");
    }
}

#[test]
fn a_run_of_pin_samples_keeps_its_grid_however_slow_the_ops() {
    // The stop-switching scenarios (Section 3-5-1) sample the outputs 250
    // ns apart: SAMPLE ops of the bridge protocol, each up to 512
    // `(ReadPins, Delay)` pairs. Op by op, at 24 cycles a hardware access,
    // the engine and the board code put each read microseconds off its
    // grid (the image on rp2350-emu: 10 us a pair, and a reply of 34 KB
    // for a buffer of 12). As one run (`Board::sample_run`), every read is
    // on the grid, and the run's replies are the ops' replies.
    use ppmc_core::bridge::engine::BridgeEngine;
    use ppmc_core::bridge::frame::{self, FrameDecoder};
    use ppmc_core::bridge::wire::{parse_fragment, Request, Response};
    let step = Duration::from_nanos(250);
    for cpu in [12, 24] {
        let mut b = twin();
        b.hal_mut().cpu_cycles = cpu;
        let timer = b.timer();
        let mut engine = BridgeEngine::new(b, 1, true, "twin").with_timer(timer);
        let mut ops = std::vec![Op::Reset, Op::Delay(Duration::from_micros(50))];
        // Five SAMPLE ops on the wire, one run on the board.
        ops.extend((0..2_086).flat_map(|_| [Op::ReadPins, Op::Delay(step)]));
        ops.push(Op::ReadStatus);
        let out = engine.on_bytes(&frame::encode(&Request::Batch(ops).encode(1, timer)));
        let mut d = FrameDecoder::new();
        d.extend(&out);
        let mut payload = Vec::new();
        while let Some(f) = d.decode().expect("a valid frame") {
            match parse_fragment(&f) {
                Some((_, _, _, data)) => payload.extend_from_slice(data),
                None => payload = f,
            }
        }
        let Response::Batch(replies) = Response::decode(&payload, timer).expect("decodes").1 else {
            panic!("{cpu} cycles an access: not a batch reply");
        };
        assert_eq!(replies.len(), 2 + 2 * 2_086 + 1, "{cpu} cycles an access");
        let reads = pin_read_times(&replies);
        assert_eq!(reads.len(), 2_086);
        let off: Vec<u64> = reads
            .windows(2)
            .map(|w| w[1] - w[0])
            .filter(|d| !(250..=255).contains(d))
            .collect();
        assert!(
            off.is_empty(),
            "{cpu} cycles an access: {} of 2,085 gaps off the 250 ns grid, e.g. {:?} ns",
            off.len(),
            &off[..off.len().min(5)]
        );
        // The status read after the run comes after its last delay.
        let last = replies.len() - 1;
        assert!(
            replies[last].at() > replies[last - 1].at(),
            "{:?}",
            &replies[last - 2..]
        );
    }
}

#[test]
fn a_status_read_ahead_for_an_abandoned_op_is_not_the_next_reads() {
    // The status read played behind a write is for the batch's next op
    // alone. An ABORT (or a full capture) abandons the batch there, and
    // the engine's own look at BUSY must read the chip as it is then,
    // not the status from before the chip took the byte (Section 3-1-1:
    // IBF 1; the engine would have taken an early BUSY 0 for a stopped
    // motor, and left a move running).
    for abandon in [false, true] {
        let mut b = twin();
        run_as_engine(&mut b, &[Op::Reset]);
        b.next_op(Some(Op::ReadStatus));
        b.run(Op::WriteCommand {
            byte: 0x02,
            wait_ibf: None,
        });
        // 20 us pass: the chip takes the byte after 6 (notes N11).
        let until = b.hal().cycles() + 20 * 150;
        while b.hal().cycles() < until {
            b.hal_mut().idle(until);
        }
        if abandon {
            b.abandon();
        }
        b.next_op(None);
        let Reply::Status { status, .. } = b.run(Op::ReadStatus) else {
            panic!("not a status reply");
        };
        assert_eq!(status.ibf(), !abandon, "abandoned: {abandon}");
    }
}

#[test]
fn an_await_ends_where_the_capture_stamps_the_flags_change() {
    // Section 3-3: BUSY rises when a move starts and falls when it ends.
    // A wait for it and the capture's BUSY change come from the same pair
    // of status reads, stamped halfway between them: they are one moment.
    // The wait's end was its length added to the op's start, a clock read
    // taken before the wait's own (the deadline worked out between): on
    // the image on rp2350-emu 1.3 us early, 2 us before the chip's change
    // (HELLO says 1.5 us for `polled`), found by comparing the image's
    // trace with the twin's (`ppmc compare`). At 40 cycles an access, as
    // on the image.
    for cpu in [12, 40] {
        let mut b = twin();
        b.hal_mut().cpu_cycles = cpu;
        let ops = accel_move(100);
        let replies = run_as_engine(&mut b, &ops);
        let busy: Vec<(u64, u8)> = b
            .record()
            .pins
            .iter()
            .filter(|p| p.pin == ppmc_core::protocol::Pin::Busy)
            .map(|p| (p.at.as_nanos(), p.value))
            .collect();
        let awaited: Vec<u64> = replies
            .iter()
            .filter_map(|r| match r {
                Reply::Awaited { at, waited, .. } if *waited > Duration::ZERO => {
                    Some(at.as_nanos())
                }
                _ => None,
            })
            .collect();
        let rise = busy.iter().find(|(_, v)| *v == 1).expect("BUSY rose").0;
        let fall = busy.iter().find(|(_, v)| *v == 0).expect("BUSY fell").0;
        assert!(
            awaited.contains(&rise),
            "{cpu} cycles: BUSY rose at {rise}, waits ended at {awaited:?}"
        );
        assert!(
            awaited.contains(&fall),
            "{cpu} cycles: BUSY fell at {fall}, waits ended at {awaited:?}"
        );
    }
}

#[test]
fn an_aimed_write_lands_at_its_moment_however_slow_the_board_code() {
    // Section 3-6's latency probes (Table 3-3) write a Decelerating Stop
    // at a moment after a pulse, within 0.4 us. The aimed cycle starts
    // with an anchor step, and the CPU works out the wait step after it
    // from when the player took the anchor: when the CPU took longer than
    // the anchor lasted, the player waited for it and the write came late
    // (on the image on rp2350-emu, 1.1 us; here, from 40 cycles a
    // hardware access on: 213 ns at 40, 480 at 60).
    for cpu in [12u64, 24, 40, 60, 100] {
        let mut b = twin();
        b.hal_mut().cpu_cycles = cpu;
        let mut ops = init_and_move(20, Duration::from_millis(200), 0x43, 5_000);
        ops.extend([
            Op::AwaitStatus {
                mask: Status::BUSY,
                value: Status::BUSY,
                timeout: Duration::from_millis(1),
            },
            Op::AwaitPulses {
                count: 500,
                timeout: Duration::from_secs(1),
            },
            Op::Delay(Duration::from_nanos(42_000 - 17_400)),
            Op::WriteCommand {
                byte: 0x41,
                wait_ibf: Some(Duration::from_millis(10)),
            },
        ]);
        let replies = run_as_engine(&mut b, &ops);
        let n = replies.len();
        let (Reply::Delayed { at: aim }, Reply::Written { at, .. }) =
            (replies[n - 2], replies[n - 1])
        else {
            panic!("{cpu} cycles an access: {:?}", &replies[n - 3..]);
        };
        assert_eq!(
            at,
            aim,
            "{cpu} cycles an access: written {} after its moment",
            at.saturating_since(aim)
        );
    }
}

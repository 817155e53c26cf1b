//! Moves (Section 3-3): starting them, stops, inputs during a move, the
//! pulse train, and the outputs that follow (INT*, HOLD, stop switching,
//! the phase pattern).

use super::*;

impl Chip {
    // ----- moves (Section 3-3) --------------------------------------------

    pub(super) fn start_move(&mut self, cmd: MoveCommand, params: [u8; 4], base: Instant) {
        let kind = cmd.kind;
        let total = match kind {
            MoveKind::SingleStep => 1,
            MoveKind::AccelDecel => {
                PulseCount::from_bytes([params[0], params[1], params[2]]).steps()
            }
            MoveKind::Constant => PulseCount::from_bytes([params[1], params[2], params[3]]).steps(),
            _ => PulseCount::MAX.steps(),
        };
        // The speed index of a move of N pulses stays below N / 2 + 1.
        if let Some((ramp, _)) = self.setup.as_mut().and_then(|s| s.ramp.as_mut()) {
            if kind.ramped() {
                ramp.cover((total / 2).saturating_add(1));
            }
        }
        let Some(setup) = self.setup.clone() else {
            self.set_error(ErrorCode::NotInitialized);
            return;
        };
        let tclock = self.straps.tclock(setup.clock);
        let (profile, first_pout) = match (kind, &setup.ramp) {
            (MoveKind::AccelDecel | MoveKind::ContinuousHigh, Some((ramp, cruise))) => {
                let pa = u32::from(setup.data.pa);
                let mut first = self.cfg.accel_first_pout;
                if total < 2 * pa {
                    // Triangular drive: the deceleration point takes longer to
                    // find the more steps there are (Table 3-3, notes N17).
                    let extra = self
                        .cfg
                        .accel_first_pout_triangle_max
                        .saturating_sub(first)
                        .scale(u64::from(total), 2 * u64::from(PA_MAX));
                    first += extra;
                }
                (
                    Profile::Ramped {
                        ramp: ramp.clone(),
                        cruise: *cruise,
                    },
                    Some(first),
                )
            }
            (MoveKind::SingleStep, _) => (
                Profile::Constant {
                    interval: Duration::ZERO,
                },
                tclock.map(|_| self.cfg.single_step_pout),
            ),
            (MoveKind::Constant | MoveKind::ContinuousConstant | MoveKind::OriginSearch, _) => {
                let rate = params[0];
                let interval =
                    tclock.map_or(Duration::MAX, |t| self.straps.pulse_interval(rate, t));
                (
                    Profile::Constant { interval },
                    tclock.map(|_| self.cfg.constant_first_pout),
                )
            }
            // A ramped move without a clock never pulses.
            _ => (
                Profile::Constant {
                    interval: Duration::MAX,
                },
                None,
            ),
        };
        let first_pulse = first_pout.map(|d| base + self.fw(d));
        self.motion_seq += 1;
        let id = self.motion_seq;
        let motion = Motion::new(
            id,
            kind,
            cmd.flags.direction,
            cmd.pout,
            cmd.flags.interrupt,
            base,
            total,
            first_pulse,
            profile,
        );
        self.record.moves.push(MoveStart {
            // The final byte's write, which a bridge sees (N47); the move
            // itself runs from `base`, when the firmware took the byte.
            at: self.taken_written,
            kind,
            dir: cmd.flags.direction,
            pout: cmd.pout,
            steps: total,
            first_run: self.record.runs.len(),
            phase_index: self.phase_index,
            winding: if cmd.pout { None } else { self.winding },
        });
        self.motion = Some(motion);
        let rise = base + self.fw_cfg.busy_rise;
        self.proc_free_at = self.proc_free_at.max(rise);
        self.schedule(rise, Timer::BusyRise { id });
    }

    pub(super) fn stop_command_immediate(&mut self, base: Instant) {
        self.halt(StopCause::StopCommand, base);
    }

    pub(super) fn stop_command_decel(&mut self, base: Instant) {
        let Some(m) = self.motion.as_ref() else {
            return;
        };
        if !m.kind.ramped() || self.cfg.faults.decel_stop_immediate {
            // Constant-speed moves have no deceleration: stop at once (N13).
            self.halt(StopCause::StopCommand, base);
            return;
        }
        if !m.pulses_left() {
            // Past its last pulse (or halted): the stop changes nothing,
            // error 7 included, since no deceleration is pending or
            // running any more (notes N28, N49).
            return;
        }
        if m.decelerating() || m.decel_requested {
            self.set_error(ErrorCode::DecelStopDuringDecel);
            return;
        }
        let id = m.id;
        if let Some(m) = self.motion.as_mut() {
            m.decel_requested = true;
        }
        self.schedule(
            base + self.fw_cfg.decel_stop,
            Timer::DecelStart {
                id,
                cause: StopCause::StopCommand,
            },
        );
    }

    /// Reacts to an input that was just asserted while a move is under way.
    /// Before the first pulse, inputs are sampled instead (see
    /// [`Self::check_inputs_before_first_pulse`]).
    pub(super) fn react_to_input(&mut self, input: Input) {
        let Some(m) = self.motion.as_ref() else {
            return;
        };
        if !m.pulses_left() || m.emitted == 0 {
            return;
        }
        let now = self.now;
        let (dir, kind, pout) = (m.dir, m.kind, m.pout);
        if input == Input::Alm {
            self.halt(StopCause::Alarm, now);
        } else if input == Input::limit_for(dir) {
            self.halt(StopCause::Limit, now);
        } else if input == Input::Cnp && kind == MoveKind::OriginSearch {
            self.halt(StopCause::Completed, now);
        } else if input == Input::high_speed_limit_for(dir) && kind.ramped() {
            self.high_speed_limit(pout);
        }
    }

    /// L3/L4 for the direction of a ramped move: decelerate (Sections 3-3-4,
    /// 3-3-7), except during acceleration in POUT mode.
    pub(super) fn high_speed_limit(&mut self, pout: bool) {
        let Some(m) = self.motion.as_ref() else {
            return;
        };
        if m.decelerating() || m.decel_requested {
            return;
        }
        let at_speed = m.at_high_speed();
        if pout && !at_speed {
            // Checked again on reaching high speed.
            return;
        }
        let latency = if at_speed {
            self.fw_cfg.hs_limit_cruise
        } else {
            self.fw_cfg.hs_limit_accel
        };
        let id = m.id;
        if let Some(m) = self.motion.as_mut() {
            m.decel_requested = true;
        }
        let at = self.now + latency;
        self.schedule(
            at,
            Timer::DecelStart {
                id,
                cause: StopCause::HighSpeedLimit,
            },
        );
    }

    /// Cuts pulse output now. `trigger` is when the cause arose (the stop
    /// command write, or the input edge), from which Table 3-3's abnormal
    /// termination time is counted.
    pub(super) fn halt(&mut self, cause: StopCause, trigger: Instant) {
        let now = self.now;
        let Some(m) = self.motion.as_mut() else {
            return;
        };
        if !m.pulses_left() {
            // Already past its last pulse: the move completes normally.
            return;
        }
        m.halted = true;
        m.cause = cause;
        let id = m.id;
        let end = if m.kind == MoveKind::SingleStep {
            m.base + self.straps.firmware_time(self.cfg.single_step_done)
        } else if m.kind.ramped() && cause != StopCause::Completed {
            trigger + self.straps.firmware_time(self.cfg.remaining_calc)
        } else {
            now + self.straps.firmware_time(self.cfg.interrupt_delay)
        };
        self.schedule(end.max(now), Timer::Terminate { id });
        // Pulse output is over, and with it the starvation of notes N7: a
        // byte the speed limit held back is taken now (notes N49).
        self.serve_again();
    }

    pub(super) fn check_inputs_before_first_pulse(&mut self) {
        let Some(m) = self.motion.as_ref() else {
            return;
        };
        let (dir, kind, pout) = (m.dir, m.kind, m.pout);
        let now = self.now;
        let inputs = self.inputs;
        if inputs.contains(Input::Alm) {
            self.halt(StopCause::Alarm, now);
        } else if inputs.contains(Input::limit_for(dir)) {
            self.halt(StopCause::Limit, now);
        } else if kind == MoveKind::OriginSearch && inputs.contains(Input::Cnp) {
            self.halt(StopCause::Completed, now);
        } else if kind.ramped()
            && !pout
            && !m.decel_requested
            && inputs.contains(Input::high_speed_limit_for(dir))
        {
            // Detected before the first pulse: decelerate from standstill,
            // which leaves the one pulse already being timed. A
            // deceleration already requested (a Decelerating Stop waiting
            // for its latency) makes the limit change nothing, as during
            // the move (notes N27, N49).
            if let Some(m) = self.motion.as_mut() {
                if m.begin_decel() {
                    m.cause = StopCause::HighSpeedLimit;
                }
            }
        }
    }

    /// Whether the move is in POUT mode with its high-speed limit asserted
    /// and not yet acted on: it looks at the limit after every pulse until
    /// high speed is reached (Section 3-3-4, notes N26).
    pub(super) fn pout_hs_check(m: &Motion, inputs: InputSet) -> bool {
        m.pout
            && m.kind.ramped()
            && !m.decel_requested
            && inputs.contains(Input::high_speed_limit_for(m.dir))
    }

    /// The pulses the move will output next without any decision in
    /// between: `(first, interval, count)`. A whole constant-period stretch
    /// (on the ramp, the pulses whose speed index stays in one step of the
    /// rate grid), or one pulse where the model must look again after it
    /// (the first pulse, a firmware served again). Both [`Self::poll_at`]
    /// and [`Self::emit_pulses`] use it, so waiting never skips a decision.
    pub(super) fn next_stretch(&self) -> Option<(Instant, Stretch)> {
        let m = self.motion.as_ref().filter(|m| m.pulses_left())?;
        let mut s = m.stretch();
        // The first pulse samples the inputs (notes N27). A firmware
        // starved by the speed limit is served again after the first pulse
        // whose period is within it (N7): that pulse ends the stretch. A
        // pending POUT high-speed-limit check looks after every pulse for
        // high speed, which a ramp stretch reaches at its last pulse if at
        // all (its indices are below the cruise's): only off the ramp does
        // it take the pulses one at a time.
        let serves_again = self.pick_starved && s.interval >= self.straps.min_interval(m.pout);
        let hs_check = !s.on_ramp && Self::pout_hs_check(m, self.inputs);
        if m.emitted == 0 || hs_check || serves_again {
            s.count = s.count.min(1);
        }
        Some((m.next_pulse?, s))
    }

    /// Emits the next pulses due at or before `horizon`: a whole
    /// constant-period stretch in one step, or the ramp stretches up to
    /// the next decision.
    pub(super) fn emit_pulses(&mut self, horizon: Instant) {
        let Some(m) = self.motion.as_ref() else {
            return;
        };
        if m.emitted == 0 {
            self.check_inputs_before_first_pulse();
        }
        let Some(m) = self.motion.as_ref() else {
            return;
        };
        let pout_hs_check = Self::pout_hs_check(m, self.inputs);
        // Past the first pulse, with no POUT high-speed-limit check pending
        // and no byte held back by the speed limit, nothing is decided
        // between two ramp stretches.
        let walk = m.emitted > 0 && !self.pick_starved && !pout_hs_check;
        let Some(next) = self.next_stretch() else {
            return;
        };
        let Some((first, stretch)) = (if walk {
            self.walk_ramp(next, horizon)
        } else {
            Some(next)
        }) else {
            return;
        };
        let Some(m) = self.motion.as_mut() else {
            return;
        };
        let Stretch {
            interval,
            count: stretch,
            on_ramp,
        } = stretch;
        let whole = first + interval.saturating_mul(u64::from(stretch.saturating_sub(1)));
        let fit = if stretch <= 1 || interval == Duration::ZERO || whole <= horizon {
            stretch
        } else {
            let span = horizon.saturating_since(first).as_nanos() / interval.as_nanos();
            u32::try_from(span.saturating_add(1))
                .unwrap_or(u32::MAX)
                .min(stretch)
        };
        let new_move = m.emitted == 0;
        let dir = m.dir;
        let steps_phases = !m.pout;
        let last = m.put_out(first, interval, fit);
        let done = m.emitted >= m.end;
        // Only a POUT move with its high-speed limit asserted asks.
        let hs_limit_now = pout_hs_check && !done && m.at_high_speed();
        let (id, kind, base) = (m.id, m.kind, m.base);
        // Fault: the final pulse of the move never reaches the wire.
        let on_wire = if done && self.cfg.faults.drop_last_pulse {
            fit - 1
        } else {
            fit
        };
        // A ramp's pulses are recorded as one at a time, as they always
        // were: the stretch is how the model runs, not what it records.
        if on_ramp {
            self.record
                .push_pulses_singly(first, interval, on_wire, dir, new_move);
        } else {
            self.record
                .push_pulses(first, interval, on_wire, dir, new_move);
        }
        if steps_phases {
            if let Some(w) = self.winding {
                // Fault: the first step of each move never reaches the phases.
                let skipped = u64::from(new_move && self.cfg.faults.phase_step_skipped);
                let steps = u64::from(fit) - skipped;
                self.phase_index = w.advance(self.phase_index, dir, steps);
            }
        }
        self.now = last;
        if hs_limit_now {
            self.high_speed_limit(true);
        }
        if done {
            let (end, free) = if kind == MoveKind::SingleStep {
                let done = base + self.fw_cfg.single_step_done;
                (done, done)
            } else {
                (
                    last + self.fw_cfg.interrupt_delay,
                    last + self.fw_cfg.next_command,
                )
            };
            self.schedule(end, Timer::Terminate { id });
            // From the final POUT the firmware is busy until it accepts the
            // next command (Table 3-3, notes N12): a byte written after the
            // last pulse waits, it is not taken before BUSY falls.
            self.proc_free_at = self.proc_free_at.max(free);
        }
        if self.pick_starved && !self.starved() {
            self.serve_again();
        }
    }

    /// Puts out ramp stretches one after another from `next` (the next
    /// stretch, first pulse and all), as [`Self::emit_pulses`] would one
    /// call at a time, while they lie whole by `horizon` and short of the
    /// move's last pulse (where the move ends); the caller has checked that
    /// nothing else is to be decided between them. The stretch after the
    /// walked ones, for the caller to put out, if it is due by `horizon`.
    fn walk_ramp(
        &mut self,
        next: (Instant, Stretch),
        horizon: Instant,
    ) -> Option<(Instant, Stretch)> {
        let Some(m) = self.motion.as_mut() else {
            return Some(next);
        };
        let start = m.emitted;
        let (mut first, mut s) = next;
        let rest = loop {
            let last = first + s.interval.saturating_mul(u64::from(s.count - 1));
            if !s.on_ramp || last > horizon || m.end - m.emitted <= s.count {
                break Some((first, s));
            }
            // Pulses remain after the stretch, so a next one is planned.
            m.put_out(first, s.interval, s.count);
            self.record
                .push_pulses_singly(first, s.interval, s.count, m.dir, false);
            self.now = last;
            match m.next_pulse {
                Some(at) if at <= horizon => first = at,
                _ => break None,
            }
            s = m.stretch();
        };
        let walked = m.emitted - start;
        if !m.pout {
            if let Some(w) = self.winding {
                self.phase_index = w.advance(self.phase_index, m.dir, u64::from(walked));
            }
        }
        rest
    }

    // ----- outputs --------------------------------------------------------

    pub(super) fn set_int(&mut self, asserted: bool) {
        if self.int != asserted {
            self.int = asserted;
            self.record.pin(self.now, Pin::Int, u8::from(asserted));
        }
    }

    pub(super) fn set_hold(&mut self, on: bool) {
        if self.hold != on {
            self.hold = on;
            self.record.pin(self.now, Pin::Hold, u8::from(on));
        }
    }

    pub(super) fn start_switching_if_enabled(&mut self) {
        let enabled = self.setup.as_ref().is_some_and(|s| s.stop_switching);
        if enabled && self.phases_on && !self.initializing {
            self.set_switching(Some(self.now));
        }
    }

    pub(super) fn set_switching(&mut self, since: Option<Instant>) {
        if self.switching_since.is_some() != since.is_some() {
            self.record
                .pin(self.now, Pin::Switching, u8::from(since.is_some()));
        }
        self.switching_since = since;
    }

    /// Records the phases set outside stepping (an initialization's, an
    /// excitation OFF's) where they differ from `was`, the pattern before:
    /// a re-initialization keeps the winding and its step (3-2-1 (3), note
    /// N15), and a pin that does not move makes no change to record.
    pub(super) fn record_phases_from(&mut self, was: u8) {
        let p = self.energized_pattern();
        if p != was {
            self.record.pin(self.now, Pin::Phases, p);
        }
    }

    /// Energized phases ignoring stop switching.
    pub(super) fn energized_pattern(&self) -> u8 {
        match (self.phases_on, self.out_winding) {
            (true, Some(w)) => w.pattern(self.phase_index),
            _ => 0,
        }
    }

    /// Stop switching's chopping now, if it chops.
    fn chop(&self) -> Option<Chop> {
        self.switching_since.map(|since| Chop {
            since,
            on: self.switch_on,
            off: self.switch_off,
        })
    }

    /// Energized phases at `t`, with stop switching chopping them.
    pub(super) fn energized(&self, t: Instant) -> u8 {
        Chop::energized(self.chop(), self.energized_pattern(), t)
    }

    /// The first time after `t` at which stop switching turns the phases on
    /// or off ([`Chip::energized`]'s next edge), while it chops.
    pub(super) fn next_chop(&self, t: Instant) -> Option<Instant> {
        self.chop().map(|c| c.next_edge(t))
    }

    /// Pin levels of S1..S5 for an energized pattern (Section 3-2-1).
    pub(super) fn levels(&self, energized: u8) -> u8 {
        self.logic.levels(energized)
    }
}

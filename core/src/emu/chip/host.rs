//! The host interface (Section 3-1): bytes taken from the input buffer one
//! at a time, the command parser and its errors (Table 3-2), register
//! reads (Section 3-4), initialization (Section 3-2) and software reset
//! (Section 3-5-4).

use super::*;

impl Chip {
    // ----- host interface ------------------------------------------------

    pub(super) fn host_write(&mut self, byte: u8, kind: ByteKind) {
        if self.inbuf.is_some() {
            self.record.overwritten_bytes += 1;
        }
        self.inbuf = Some(InByte {
            byte,
            kind,
            written: self.now,
        });
        if !self.pick_starved {
            let at = (self.now + self.fw_cfg.byte_pickup).max(self.proc_free_at);
            self.schedule_pick(at);
        }
    }

    pub(super) fn schedule_pick(&mut self, at: Instant) {
        if let Some(seq) = self.pick_timer.take() {
            self.timers.retain(|(_, s, _)| *s != seq);
        }
        self.pick_timer = Some(self.schedule(at, Timer::Pick));
    }

    /// The firmware serves the host again after the speed limit held it
    /// back (notes N7): the waiting byte is taken when the firmware is free,
    /// and never sooner than the pickup time after its own write.
    pub(super) fn serve_again(&mut self) {
        if !self.pick_starved {
            return;
        }
        self.pick_starved = false;
        let Some(inb) = self.inbuf else { return };
        let at = self
            .now
            .max(self.proc_free_at)
            .max(inb.written + self.fw_cfg.byte_pickup);
        self.schedule_pick(at);
    }

    /// The firmware cannot serve the host while pulsing faster than the
    /// speed limit (Section 3-2-2, notes N7).
    pub(super) fn starved(&self) -> bool {
        self.motion.as_ref().is_some_and(|m| {
            m.current_interval()
                .is_some_and(|i| i < self.straps.min_interval(m.pout))
        })
    }

    pub(super) fn pick(&mut self) {
        self.pick_timer = None;
        let Some(inb) = self.inbuf else { return };
        if self.now < self.proc_free_at {
            let at = self.proc_free_at;
            self.schedule_pick(at);
            return;
        }
        if self.starved() {
            self.pick_starved = true;
            return;
        }
        self.inbuf = None;
        self.taken_written = inb.written;
        let base = self.now - self.fw_cfg.byte_pickup;
        match inb.kind {
            ByteKind::Command => self.on_command(Command::decode(inb.byte), base),
            ByteKind::Data => self.on_data(inb.byte, base),
        }
    }

    pub(super) fn set_error(&mut self, e: ErrorCode) {
        self.field = StatusField::Error(e);
        self.expect = Expect::Command;
    }

    pub(super) fn on_command(&mut self, cmd: Command, base: Instant) {
        // A new command abandons an unfinished one and unread output.
        self.expect = Expect::Command;
        self.field = StatusField::ParamsRemaining(0);
        self.out_pending.clear();
        self.obf = false;
        self.timers.retain(|(_, _, t)| *t != Timer::ObfReady);

        let busy = self.busy;
        match cmd {
            Command::Undefined(_) => self.set_error(ErrorCode::UndefinedCommand),
            Command::ImmediateStop(_) | Command::DecelStop(_) if !busy => {
                self.set_error(ErrorCode::UndefinedCommand)
            }
            Command::ImmediateStop(_) => self.stop_command_immediate(base),
            Command::DecelStop(_) => self.stop_command_decel(base),
            Command::SoftwareReset(_) if busy && self.cfg.faults.reset_quirk_missing => {}
            Command::SoftwareReset(_) | Command::AuxOn(_) if busy => {
                self.schedule(base + self.fw_cfg.aux_switch, Timer::Aux(true));
            }
            Command::AuxOn(_) => {
                self.schedule(base + self.fw_cfg.aux_switch, Timer::Aux(true));
            }
            Command::AuxOff(_) => {
                self.schedule(base + self.fw_cfg.aux_switch, Timer::Aux(false));
            }
            Command::SoftwareReset(_) => self.software_reset(base),
            Command::AuxOutput => self.expect_params(cmd),
            _ if busy => self.set_error(ErrorCode::NotAllowedWhileBusy),
            Command::Move(_) if !self.initialized() => self.set_error(ErrorCode::NotInitialized),
            Command::Move(m) if m.kind.param_count() == 0 => self.start_move(m, [0; 4], base),
            Command::Init(_) | Command::Move(_) | Command::SwitchingParams => {
                self.expect_params(cmd)
            }
            Command::Read(r) => self.load_register(r, base),
        }
    }

    pub(super) fn expect_params(&mut self, cmd: Command) {
        let need = cmd.param_count();
        self.field = StatusField::ParamsRemaining(need);
        self.expect = Expect::Params {
            cmd,
            buf: [0; 4],
            got: 0,
            need,
        };
    }

    pub(super) fn on_data(&mut self, byte: u8, base: Instant) {
        let Expect::Params {
            cmd,
            mut buf,
            mut got,
            need,
        } = self.expect
        else {
            self.set_error(if self.busy {
                ErrorCode::DataWhileBusy
            } else {
                ErrorCode::TooManyParameters
            });
            return;
        };
        if self.busy && cmd != Command::AuxOutput {
            self.set_error(ErrorCode::DataWhileBusy);
            return;
        }
        buf[usize::from(got)] = byte;
        got += 1;
        let due = if self.cfg.faults.params_not_counted && got < need {
            need
        } else {
            need - got
        };
        self.field = StatusField::ParamsRemaining(due);
        if got < need {
            self.expect = Expect::Params {
                cmd,
                buf,
                got,
                need,
            };
            return;
        }
        self.expect = Expect::Command;
        match cmd {
            Command::Init(c) => self.initialize(c, InitData::from_bytes(buf), base),
            Command::Move(m) => self.start_move(m, buf, base),
            Command::SwitchingParams => {
                self.switch_on = self.straps.switching_on_time(buf[0]);
                self.switch_off = self.straps.switching_off_time(buf[1]);
            }
            Command::AuxOutput => {
                let bits = buf[0] & 0x0F;
                self.schedule(base + self.fw_cfg.aux_output, Timer::Auxo(bits));
            }
            _ => {}
        }
    }

    pub(super) fn load_register(&mut self, reg: Register, base: Instant) {
        // One byte, or the remaining pulses' three (Section 3-4).
        let (bytes, len) = match reg {
            Register::FinishStatus => {
                let value = self.finish.0;
                if !self.cfg.faults.finish_flag_sticky {
                    self.finish = self.finish.without_polling();
                }
                self.set_int(false);
                ([value, 0, 0], 1)
            }
            Register::InputSignals => ([InputStatus::from_inputs(self.inputs).0, 0, 0], 1),
            Register::OutputSignals => {
                let levels = self.levels(self.energized(self.now));
                ([OutputStatus::new(self.dir, self.hold, levels).0, 0, 0], 1)
            }
            Register::RemainingPulses => {
                let value = if self.cfg.faults.remaining_off_by_one {
                    self.remaining
                } else {
                    self.remaining.saturating_sub(1)
                };
                let [lo, mid, hi, _] = value.to_le_bytes();
                ([lo, mid, hi], 3)
            }
            Register::AuxInputs => ([AuxInputStatus::from_inputs(self.inputs).0, 0, 0], 1),
        };
        self.out_pending.extend(&bytes[..len]);
        self.schedule(base + self.fw_cfg.obf_ready, Timer::ObfReady);
    }

    // ----- initialization and reset (Sections 3-2, 3-5-4) ----------------

    pub(super) fn initialize(&mut self, cmd: InitCommand, data: InitData, base: Instant) {
        let rates_ok = 0 < data.rh && data.rh < data.rl && data.rl < 255;
        if !rates_ok || data.pa < PA_MIN {
            self.set_error(ErrorCode::BadRateData);
            return;
        }
        if data.pa > PA_MAX {
            self.set_error(ErrorCode::AccelPulsesTooMany);
            return;
        }
        if self.winding.is_none() {
            // Type, excitation and logic are frozen until software reset.
            self.winding = Some(Winding {
                motor: cmd.motor,
                excitation: cmd.excitation,
            });
            if self.logic != cmd.logic {
                self.logic = cmd.logic;
                self.logic_since = self.now;
            }
            self.phase_index = 0;
            self.out_winding = self.winding;
        }
        let ramp = self.straps.tclock(cmd.clock).map(|tclock| {
            let accel = AccelRamp::new(
                self.cfg.accel_curve,
                &self.straps,
                tclock,
                data.rl,
                data.rh,
                data.pa,
            );
            (
                self.ramp_of(accel),
                self.straps.pulse_interval(data.rh, tclock),
            )
        });
        self.setup = Some(Setup {
            clock: cmd.clock,
            stop_switching: cmd.stop_switching,
            data,
            ramp,
        });
        self.config_epoch += 1;
        let epoch = self.config_epoch;
        // No stop switching while an initialization is processed
        // (3-2-1 (3), notes N39).
        self.set_switching(None);
        self.initializing = true;
        let span = self
            .cfg
            .init_time_max
            .saturating_sub(self.cfg.init_time_min);
        let init_time = self.cfg.init_time_min
            + span.scale(u64::from(data.pa - PA_MIN), u64::from(PA_MAX - PA_MIN));
        let done = base + self.fw(init_time);
        self.proc_free_at = self.proc_free_at.max(done);
        self.schedule(
            base + self.fw_cfg.init_outputs,
            Timer::InitOutputs { epoch },
        );
        self.schedule(done, Timer::InitDone { epoch });
    }

    pub(super) fn software_reset(&mut self, base: Instant) {
        self.winding_reset();
        self.config_epoch += 1;
        let epoch = self.config_epoch;
        self.schedule(
            base + self.fw_cfg.excitation_off,
            Timer::ExcitationOff { epoch },
        );
    }

    pub(super) fn winding_reset(&mut self) {
        self.winding = None;
        self.setup = None;
    }
}

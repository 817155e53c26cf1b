//! The host interface as the plain model's firmware serves it: a byte
//! taken from the input buffer, the command parser and its errors (Table
//! 3-2), initialization (Section 3-2), software reset (3-5-4), AUX
//! (3-5-2, 3-5-3), stop switching parameters (3-5-1) and register reads
//! (3-4).

use super::{div_round, Event, PlainChip, Setup, Winding, MOTOR_PHASES};
use crate::plain_model::commands::{decode, params, Cmd, Op};
use crate::protocol::Input;
use crate::time::Duration;

impl PlainChip {
    // ---- the firmware taking bytes ----

    pub(super) fn take(&mut self) {
        let Some((byte, command, _)) = self.inbuf.take() else {
            self.take_at = None;
            return;
        };
        self.take_at = None;
        // Firmware times run from when the byte would have been written
        // had the firmware been idle (notes N12).
        let base = self.now - self.fw(self.cfg.byte_pickup);
        if command {
            self.command(byte, base);
        } else {
            self.data(byte, base);
        }
        // A byte written while this one was being worked on waits for the
        // firmware.
        if self.inbuf.is_some() && self.take_at.is_none() {
            let pickup = self.fw(self.cfg.byte_pickup);
            self.take_at = Some((self.now + pickup).max(self.free_at));
        }
    }

    pub(super) fn error(&mut self, n: u8) {
        self.field = 0x80 | (n << 4);
    }

    fn command(&mut self, byte: u8, base: u64) {
        let cmd = decode(byte);
        // A new command drops an unfinished one (N35) and unread output
        // (N34).
        self.pending = None;
        self.out.clear();
        self.obf = false;
        self.events.retain(|(_, _, e)| *e != Event::ObfReady);
        self.field = 0;
        if self.busy && self.mv.is_some() {
            // Pulsing: only stops and AUX (3-1-1 (3), 3-5-3, 3-5-4).
            match cmd {
                Cmd::Move {
                    op: Op::ImmediateStop,
                    ..
                } => self.immediate_stop(base),
                Cmd::Move {
                    op: Op::DecelStop, ..
                } => self.decel_stop(base),
                Cmd::AuxOn | Cmd::SoftReset => self.aux_switch(true, base),
                Cmd::AuxOff => self.aux_switch(false, base),
                Cmd::AuxOutput => self.expect(cmd),
                Cmd::Undefined => self.error(0),
                _ => self.error(1),
            }
            return;
        }
        match cmd {
            Cmd::Undefined => self.error(0),
            Cmd::Move {
                op: Op::ImmediateStop | Op::DecelStop,
                ..
            } => self.error(0),
            Cmd::Move { .. } if self.setup.is_none() => self.error(2),
            Cmd::Move {
                op: Op::SingleStep | Op::ContinuousHigh,
                ..
            } => self.start(cmd, &[], base),
            Cmd::Read(code) => self.read_register(code, base),
            Cmd::AuxOn => self.aux_switch(true, base),
            Cmd::AuxOff => self.aux_switch(false, base),
            Cmd::SoftReset => self.software_reset(base),
            _ => self.expect(cmd),
        }
    }

    fn expect(&mut self, cmd: Cmd) {
        self.field = params(cmd) << 4;
        self.pending = Some((cmd, Vec::new()));
    }

    fn data(&mut self, byte: u8, base: u64) {
        let Some((cmd, mut bytes)) = self.pending.take() else {
            self.error(if self.busy { 6 } else { 3 });
            return;
        };
        if self.busy && self.mv.is_some() && cmd != Cmd::AuxOutput {
            self.error(6);
            return;
        }
        bytes.push(byte);
        let left = params(cmd) - bytes.len() as u8;
        self.field = left << 4;
        if left > 0 {
            self.pending = Some((cmd, bytes));
            return;
        }
        match cmd {
            Cmd::Init(code) => self.initialize(code, &bytes, base),
            Cmd::Move { .. } => self.start(cmd, &bytes, base),
            Cmd::Switching => {
                let (on, off) = if self.straps.vsel_high {
                    (27_000, 33_000)
                } else {
                    (25_000, 28_750)
                };
                let ton = u64::from(bytes[0]) * 3_000 + on;
                let toff = u64::from(bytes[1]) * 3_000 + off;
                self.ton = self.fw(Duration::from_nanos(ton));
                self.toff = self.fw(Duration::from_nanos(toff));
            }
            Cmd::AuxOutput => {
                // The pins change 14 us later; the firmware is free
                // meanwhile (notes N49).
                let at = base + self.fw(self.cfg.aux_output);
                self.schedule(at, Event::Auxo(bytes[0] & 0x0F));
            }
            _ => {}
        }
    }

    // ---- initialization (3-2) and software reset (3-5-4) ----

    fn initialize(&mut self, code: u8, d: &[u8], base: u64) {
        let (rl, rh) = (d[0], d[1]);
        let pa = u32::from(u16::from_le_bytes([d[2], d[3]]));
        // 255 > RL > RH > 0, then 4 <= PA <= 11,220 (notes N5).
        if !(rh > 0 && rh < rl && rl < 255) {
            self.error(5);
            return;
        }
        if pa < 4 {
            self.error(5);
            return;
        }
        if pa > 11_220 {
            self.error(4);
            return;
        }
        self.setup = Some(Setup {
            rl,
            rh,
            pa,
            external: code & 0x10 != 0,
            switching: code & 0x20 != 0,
        });
        let first = self.winding.is_none();
        if first {
            let w = Winding {
                phases: MOTOR_PHASES[usize::from(code & 0x03)],
                half: code & 0x04 != 0,
                positive: code & 0x08 != 0,
            };
            self.winding = Some(w);
            self.shown = Some(w);
            self.positive = w.positive;
            self.step = 0;
        }
        // Switching stops while the initialization is processed, and
        // starts again when it completes (3-2-1 (3), notes N39).
        self.set_switching(false);
        self.initializing = true;
        self.epoch += 1;
        let epoch = self.epoch;
        self.schedule(
            base + self.fw(self.cfg.init_outputs),
            Event::PhasesSet { epoch },
        );
        // 16.5 ms at PA = 4 to 162.8 ms at PA = 11,220, linear (N21).
        let min = self.cfg.init_time_min.as_nanos();
        let max = self.cfg.init_time_max.as_nanos();
        let t = div_round(u128::from(max - min) * u128::from(pa - 4), 11_220 - 4) + min;
        let done = base + self.fw(Duration::from_nanos(t));
        self.schedule(done, Event::InitDone { epoch });
        self.free_at = self.free_at.max(done);
    }

    fn software_reset(&mut self, base: u64) {
        self.setup = None;
        self.winding = None;
        self.epoch += 1;
        let epoch = self.epoch;
        // The phases go off 18 us later; the firmware is free meanwhile
        // (notes N49).
        let at = base + self.fw(self.cfg.excitation_off);
        self.schedule(at, Event::ExcitationOff { epoch });
    }

    fn aux_switch(&mut self, on: bool, base: u64) {
        let at = base + self.fw(self.cfg.aux_switch);
        self.schedule(at, Event::Aux(on));
    }

    // ---- register reads (3-4) ----

    fn read_register(&mut self, code: u8, base: u64) {
        let bytes: Vec<u8> = match code {
            0x80 => {
                // The read clears the polling flag and releases INT* when
                // the firmware fetches the register (N30).
                let value = self.finish;
                self.finish &= 0x7F;
                self.set_int(false);
                vec![value]
            }
            0x81 => {
                let mut v = 0x3Fu8;
                for (bit, input) in [
                    Input::L4,
                    Input::L3,
                    Input::L2,
                    Input::L1,
                    Input::Alm,
                    Input::Cnp,
                ]
                .into_iter()
                .enumerate()
                {
                    if self.asserted(input) {
                        v &= !(1 << bit);
                    }
                }
                vec![v]
            }
            0x82 => {
                let levels = self.levels(self.phases_now());
                vec![levels << 3 | u8::from(self.hold) << 2 | u8::from(self.ccw) << 1]
            }
            0x83 => {
                let r = self.remaining.saturating_sub(1);
                vec![r as u8, (r >> 8) as u8, (r >> 16) as u8]
            }
            _ => {
                let mut v = 0x0Fu8;
                for (bit, input) in [Input::Auxi0, Input::Auxi1, Input::Auxi2, Input::Auxi3]
                    .into_iter()
                    .enumerate()
                {
                    if self.asserted(input) {
                        v &= !(1 << bit);
                    }
                }
                vec![v]
            }
        };
        self.out = bytes.into();
        let at = base + self.fw(self.cfg.obf_ready);
        self.schedule(at, Event::ObfReady);
    }

    pub(super) fn load_output(&mut self) {
        let Some(b) = self.out.pop_front() else {
            return;
        };
        self.latch = b;
        self.obf = true;
    }
}

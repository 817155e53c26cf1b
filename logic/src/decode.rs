//! The chip's bus in a capture, decoded: CS*, RD*, WR*, A0 and D0-D7 into
//! timed register accesses (Table 3-1: a write with A0 high is the command
//! register, low the data register; a read with A0 high is the status
//! register, low the data register).
//!
//! A strobe is CS* and RD* (or WR*) low together; it ends when either goes
//! high, and the data are what the lines held in its last sample, as a
//! latch at the strobe's rising edge takes them. A strobe shorter than
//! the glitch filter is dropped and counted. The decoder keeps the
//! narrowest strobe it saw: one lasting a single sample means the capture
//! samples too slowly to trust (a strobe may fall between two samples and
//! be lost), and [`Summary::rate_problem`] says what rate it needs.

use super::map::BusChannels;
use super::source::{Change, LogicInfo};
use ppmc_core::time::Duration;
use std::fmt;

/// Which register a bus access reached (Table 3-1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    WriteCommand,
    WriteData,
    ReadStatus,
    ReadData,
}

/// One register access as the capture shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Transaction {
    pub access: Access,
    /// The byte on D0-D7 in the strobe's last sample.
    pub byte: u8,
    /// Data lines that were unknown (a VCD `x`) then: the byte's bits there
    /// mean nothing.
    pub unknown: u8,
    /// When the strobe began and ended, in picoseconds of the capture.
    pub start_ps: u64,
    pub end_ps: u64,
}

impl fmt::Display for Transaction {
    /// In the bus console's language (`docs/console.md`): a write as a
    /// raw write (`wc! 0x43`), since the host that wrote it did not
    /// necessarily wait for IBF; a read with the byte read as a comment.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = self.byte;
        match self.access {
            Access::WriteCommand => write!(f, "wc! 0x{b:02X}"),
            Access::WriteData => write!(f, "wd! 0x{b:02X}"),
            Access::ReadStatus => write!(f, "rs  # 0x{b:02X}"),
            Access::ReadData => write!(f, "rd! # 0x{b:02X}"),
        }?;
        if self.unknown != 0 {
            write!(f, " (lines unknown: 0x{:02X})", self.unknown)?;
        }
        Ok(())
    }
}

/// What the decoder saw besides the transactions.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Summary {
    pub transactions: u64,
    /// Strobes shorter than the glitch filter, dropped.
    pub glitches: u64,
    /// Times RD* and WR* were low together with CS*: a bus fight.
    pub conflicts: u64,
    /// When the first of them began, in picoseconds.
    pub first_conflict_ps: Option<u64>,
    /// The narrowest strobe decoded, in picoseconds.
    pub narrowest_ps: Option<u64>,
    /// Strobes that lasted one sample or less.
    pub one_sample: u64,
}

impl Summary {
    /// Why the capture contradicts its map, if RD* and WR* were ever low
    /// together with CS*: no host drives both strobes of one access (a
    /// probe on the wrong line, or a host that fights the bus).
    pub fn strobe_problem(&self) -> Option<String> {
        let at = self.first_conflict_ps?;
        Some(format!(
            "RD* and WR* were low together with CS* {} time{}, the first at {}: no access drives both strobes (a probe on the wrong line, a map that names RD or WR wrongly, or a host that fights the bus)",
            self.conflicts,
            if self.conflicts == 1 { "" } else { "s" },
            ppmc_core::time::Instant::from_nanos(at / 1000)
        ))
    }

    /// Why the capture's sample rate is too low for its strobes, if it is:
    /// a strobe seen in a single sample may as well have fallen between
    /// two and been lost; two samples a strobe are the least to trust.
    pub fn rate_problem(&self, info: &LogicInfo) -> Option<String> {
        if self.one_sample == 0 {
            return None;
        }
        let rate = info.rate_hz();
        let needs = rate.saturating_mul(2);
        Some(format!(
            "{} bus strobes lasted a single sample at {}: the capture samples too slowly for this bus and may have lost strobes; it needs at least {} (two samples a strobe), more if the strobes are shorter than {}",
            self.one_sample,
            hz(rate),
            hz(needs),
            Duration::from_nanos(info.resolution_ps / 1000)
        ))
    }
}

/// A rate in words: `24 MHz`, `100 kHz`.
fn hz(rate: u64) -> String {
    match rate {
        r if r >= 1_000_000 && r % 1_000 == 0 => format!("{} MHz", r as f64 / 1e6),
        r if r >= 1_000 => format!("{} kHz", r as f64 / 1e3),
        r => format!("{r} Hz"),
    }
}

/// A strobe under way.
#[derive(Debug, Clone, Copy)]
struct Strobe {
    write: bool,
    start_ps: u64,
}

/// Decodes the bus from a capture's changes, one at a time.
#[derive(Debug, Clone)]
pub struct BusDecoder {
    bus: BusChannels,
    glitch_ps: u64,
    resolution_ps: u64,
    /// The levels before the change being read.
    prev: Option<Change>,
    strobe: Option<Strobe>,
    summary: Summary,
}

/// The default glitch filter: strobes shorter than this are noise.
pub const GLITCH_PS: u64 = 20_000;

impl BusDecoder {
    /// A decoder of the bus on `bus`'s channels of a capture with `info`;
    /// strobes shorter than `glitch_ps` are dropped.
    pub fn new(bus: BusChannels, info: &LogicInfo, glitch_ps: u64) -> BusDecoder {
        BusDecoder {
            bus,
            glitch_ps,
            resolution_ps: info.resolution_ps.max(1),
            prev: None,
            strobe: None,
            summary: Summary::default(),
        }
    }

    /// Takes the next change; the access a strobe ending there made.
    pub fn push(&mut self, c: Change) -> Option<Transaction> {
        let b = self.bus;
        let low = |c: &Change, ch: usize| !c.high(ch);
        let (cs, rd, wr) = (low(&c, b.cs), low(&c, b.rd), low(&c, b.wr));
        if cs && rd && wr {
            let fighting = self
                .prev
                .is_none_or(|p| !(low(&p, b.cs) && low(&p, b.rd) && low(&p, b.wr)));
            if fighting {
                self.summary.conflicts += 1;
                self.summary.first_conflict_ps.get_or_insert(c.time_ps);
            }
        }
        let mut done = None;
        // A strobe ends when its line or CS* goes high.
        if let (Some(s), Some(p)) = (self.strobe, self.prev) {
            let still = cs && if s.write { wr } else { rd };
            if !still {
                self.strobe = None;
                done = self.finish(s, &p, c.time_ps);
            }
        }
        if self.strobe.is_none() && cs && (rd != wr) {
            let began = self
                .prev
                .is_none_or(|p| !(low(&p, b.cs) && low(&p, if wr { b.wr } else { b.rd })));
            if began {
                self.strobe = Some(Strobe {
                    write: wr,
                    start_ps: c.time_ps,
                });
            }
        }
        self.prev = Some(c);
        done
    }

    /// The access of strobe `s`, which ended at `end_ps`, the lines having
    /// held `last` in its last sample.
    fn finish(&mut self, s: Strobe, last: &Change, end_ps: u64) -> Option<Transaction> {
        let width = end_ps.saturating_sub(s.start_ps);
        if width < self.glitch_ps {
            self.summary.glitches += 1;
            return None;
        }
        if width <= self.resolution_ps {
            self.summary.one_sample += 1;
        }
        self.summary.narrowest_ps = Some(self.summary.narrowest_ps.map_or(width, |n| n.min(width)));
        let (mut byte, mut unknown) = (0u8, 0u8);
        for (i, ch) in self.bus.d.iter().enumerate() {
            if last.high(*ch) {
                byte |= 1 << i;
            }
            if *ch < 64 && last.unknown >> ch & 1 == 1 {
                unknown |= 1 << i;
            }
        }
        let a0 = last.high(self.bus.a0);
        let access = match (s.write, a0) {
            (true, true) => Access::WriteCommand,
            (true, false) => Access::WriteData,
            (false, true) => Access::ReadStatus,
            (false, false) => Access::ReadData,
        };
        self.summary.transactions += 1;
        Some(Transaction {
            access,
            byte,
            unknown,
            start_ps: s.start_ps,
            end_ps,
        })
    }

    /// What it saw so far.
    pub fn summary(&self) -> Summary {
        self.summary
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Channels: CS 0, RD 1, WR 2, A0 3, D0-D7 4-11.
    fn bus() -> BusChannels {
        BusChannels {
            cs: 0,
            rd: 1,
            wr: 2,
            a0: 3,
            d: [4, 5, 6, 7, 8, 9, 10, 11],
        }
    }

    fn info(resolution_ps: u64) -> LogicInfo {
        LogicInfo {
            channels: (0..12).map(|i| format!("c{i}")).collect(),
            resolution_ps,
            sample_rate_hz: None,
            format: "test".into(),
        }
    }

    /// Idle: CS, RD, WR high.
    const IDLE: u64 = 0b111;

    /// The changes of one access at `t` ns, the strobe `width` ns.
    fn cycle(t: u64, write: bool, a0: bool, byte: u8, width: u64) -> Vec<Change> {
        let a = if a0 { 1 << 3 } else { 0 };
        let d = u64::from(byte) << 4;
        let strobe = if write { 0b100 } else { 0b010 };
        let at = |ns: u64, levels: u64| Change {
            time_ps: ns * 1000,
            levels,
            unknown: 0,
        };
        vec![
            at(t, (IDLE & !1) | a | d),
            at(t + 10, (IDLE & !1 & !strobe) | a | d),
            at(t + 10 + width, (IDLE & !1) | a),
            at(t + 20 + width, IDLE),
        ]
    }

    fn decode(changes: &[Change], resolution_ps: u64) -> (Vec<Transaction>, Summary) {
        let mut d = BusDecoder::new(bus(), &info(resolution_ps), GLITCH_PS);
        let mut out: Vec<Transaction> = Vec::new();
        out.extend(d.push(Change {
            time_ps: 0,
            levels: IDLE,
            unknown: 0,
        }));
        for c in changes {
            out.extend(d.push(*c));
        }
        (out, d.summary())
    }

    /// Table 3-1: A0 and the strobe choose the register.
    #[test]
    fn each_register_of_table_3_1_is_told_apart() {
        let mut ch = cycle(100, true, true, 0x43, 100);
        ch.extend(cycle(400, true, false, 0x07, 100));
        ch.extend(cycle(700, false, true, 0x81, 100));
        ch.extend(cycle(1000, false, false, 0x5A, 100));
        let (t, s) = decode(&ch, 1000);
        let got: Vec<(Access, u8)> = t.iter().map(|t| (t.access, t.byte)).collect();
        assert_eq!(
            got,
            [
                (Access::WriteCommand, 0x43),
                (Access::WriteData, 0x07),
                (Access::ReadStatus, 0x81),
                (Access::ReadData, 0x5A)
            ]
        );
        assert_eq!((t[0].start_ps, t[0].end_ps), (110_000, 210_000));
        assert_eq!((s.transactions, s.glitches, s.one_sample), (4, 0, 0));
        assert_eq!(t[0].to_string(), "wc! 0x43");
        assert_eq!(t[2].to_string(), "rs  # 0x81");
    }

    #[test]
    fn a_glitch_is_dropped_and_a_one_sample_strobe_says_the_rate_is_too_low() {
        let (t, s) = decode(&cycle(100, true, true, 0x43, 5), 1000);
        assert!(t.is_empty());
        assert_eq!(s.glitches, 1);
        // At 24 MHz a 100 ns strobe is two or three samples; a 40 ns one
        // is one.
        let slow = LogicInfo {
            sample_rate_hz: Some(24_000_000),
            ..info(41_667)
        };
        let mut d = BusDecoder::new(bus(), &slow, GLITCH_PS);
        d.push(Change {
            time_ps: 0,
            levels: IDLE,
            unknown: 0,
        });
        let strobe = |t0: u64| {
            [
                Change {
                    time_ps: t0,
                    levels: IDLE & !0b101,
                    unknown: 0,
                },
                Change {
                    time_ps: t0 + 41_667,
                    levels: IDLE,
                    unknown: 0,
                },
            ]
        };
        let n: usize = strobe(1_000_000)
            .into_iter()
            .filter_map(|c| d.push(c))
            .count();
        assert_eq!(n, 1);
        let why = d.summary().rate_problem(&slow).expect("too slow");
        assert!(why.contains("needs at least 48 MHz"), "{why}");
        assert_eq!(Summary::default().rate_problem(&slow), None);
    }

    #[test]
    fn cs_high_ends_a_strobe_and_a_fight_is_counted() {
        // WR low, then CS rises before WR: the write ends with CS.
        let at = |ns: u64, levels: u64| Change {
            time_ps: ns * 1000,
            levels,
            unknown: 0,
        };
        let ch = [
            at(100, 0b010 | 0x12 << 4),
            at(200, 0b011 | 0x12 << 4),
            at(210, IDLE),
            at(300, 0),
            at(400, IDLE),
        ];
        let (t, s) = decode(&ch, 1000);
        assert_eq!(t.len(), 1, "{t:?}");
        assert_eq!(
            (t[0].access, t[0].byte, t[0].end_ps),
            (Access::WriteData, 0x12, 200_000)
        );
        assert_eq!(s.conflicts, 1);
        let why = s
            .strobe_problem()
            .expect("a fight is the capture's problem");
        assert!(
            why.contains("RD* and WR* were low together with CS* 1 time, the first at 0.300us"),
            "{why}"
        );
        assert_eq!(Summary::default().strobe_problem(), None);
    }
}

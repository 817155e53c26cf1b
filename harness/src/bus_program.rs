//! Bus programs: the bus-op language ([`BusOp`]) that the invariant
//! oracle judges, the two models compare and a fuzz input encodes, and
//! the byte stream of a `bus_bytes` input, in the style of QEMU's generic
//! device fuzzer. Every fuzzing room speaks it, so it lives below them
//! all.
//!
//! An input is split at the separator `FUZZ` into ops; each op is an
//! opcode byte (taken modulo [`OPCODES`]) and up to two operand bytes
//! (missing ones read as 0, extra ones are ignored). Because ops are
//! delimited rather than fixed-width, a mutation inside one op, even one
//! that inserts or deletes bytes, leaves the ops after it intact.

use crate::backend::Op;
use crate::protocol::Input;
use crate::time::{Duration, Instant};
use crate::trace::{BusEvent, EventKind, Trace};
use std::fmt;

/// What separates ops in an input.
pub const SEPARATOR: &[u8; 4] = b"FUZZ";

/// Number of distinct opcodes; opcode bytes are taken modulo this.
pub const OPCODES: u8 = 8;

/// One bus-level operation of a fuzz input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BusOp {
    /// Write the command register (A = H).
    Command(u8),
    /// Write the data register (A = L).
    Data(u8),
    /// Read the status register.
    ReadStatus,
    /// Read the data register.
    ReadData,
    /// Drive an input pin (asserted = pulled low).
    Input { input: Input, asserted: bool },
    /// Let time pass.
    Advance(Duration),
}

impl BusOp {
    /// The target op it runs as: a raw write or read (no flowchart wait),
    /// an input driven, time let pass.
    pub fn op(self) -> Op {
        match self {
            BusOp::Command(byte) => Op::WriteCommand {
                byte,
                wait_ibf: None,
            },
            BusOp::Data(byte) => Op::WriteData {
                byte,
                wait_ibf: None,
            },
            BusOp::ReadStatus => Op::ReadStatus,
            BusOp::ReadData => Op::ReadData { wait_obf: None },
            BusOp::Input { input, asserted } => Op::SetInput { input, asserted },
            BusOp::Advance(d) => Op::Delay(d),
        }
    }

    /// Decodes one op from its bytes (without separator); `None` for an
    /// empty op.
    pub fn decode(bytes: &[u8]) -> Option<BusOp> {
        let (&op, rest) = bytes.split_first()?;
        let a = rest.first().copied().unwrap_or(0);
        let b = rest.get(1).copied().unwrap_or(0);
        let word = u64::from(u16::from_le_bytes([a, b]));
        Some(match op % OPCODES {
            0 => BusOp::Command(a),
            1 => BusOp::Data(a),
            2 => BusOp::ReadStatus,
            3 => BusOp::ReadData,
            4 => BusOp::Input {
                input: Input::ALL[usize::from(a) % Input::ALL.len()],
                asserted: b & 1 == 1,
            },
            5 => BusOp::Advance(Duration::from_micros(word)),
            6 => BusOp::Advance(Duration::from_millis(word)),
            _ => BusOp::Advance(Duration::from_millis(word.saturating_mul(10))),
        })
    }

    /// The op's bytes (without separator), such that `decode` gives it
    /// back (advances are rounded to the coarsest unit that holds them).
    pub fn encode(self) -> Vec<u8> {
        match self {
            BusOp::Command(b) => vec![0, b],
            BusOp::Data(b) => vec![1, b],
            BusOp::ReadStatus => vec![2],
            BusOp::ReadData => vec![3],
            BusOp::Input { input, asserted } => vec![4, input.index(), u8::from(asserted)],
            BusOp::Advance(d) => {
                let ns = d.as_nanos();
                let max = u64::from(u16::MAX);
                let (code, n) = if ns % 10_000_000 == 0 && ns / 10_000_000 <= max {
                    (7, ns / 10_000_000)
                } else if ns % 1_000_000 == 0 && ns / 1_000_000 <= max {
                    (6, ns / 1_000_000)
                } else {
                    (5, ns / 1_000)
                };
                let [a, b] = (n.min(max) as u16).to_le_bytes();
                vec![code, a, b]
            }
        }
    }
}

impl fmt::Display for BusOp {
    /// The op in the console language (`docs/console.md`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BusOp::Command(b) => write!(f, "wc! 0x{b:02X}"),
            BusOp::Data(b) => write!(f, "wd! 0x{b:02X}"),
            BusOp::ReadStatus => f.write_str("rs"),
            BusOp::ReadData => f.write_str("rd!"),
            BusOp::Input { input, asserted } => {
                write!(
                    f,
                    "set {} {}",
                    input.name(),
                    if *asserted { "on" } else { "off" }
                )
            }
            BusOp::Advance(d) => write!(f, "wait {}us", d.as_nanos() / 1_000),
        }
    }
}

/// Applies one op to a chip on its board; the byte a read returned.
pub fn apply(chip: &mut crate::emu::Board, op: BusOp) -> Option<u8> {
    match op {
        BusOp::Command(b) => chip.write_command(b),
        BusOp::Data(b) => chip.write_data(b),
        BusOp::ReadStatus => return Some(chip.read_status().0),
        BusOp::ReadData => return Some(chip.read_data()),
        BusOp::Input { input, asserted } => chip.set_input(input, asserted),
        BusOp::Advance(d) => chip.advance_to(chip.now() + d),
    }
    None
}

/// Advances that add up to `d` (to the microsecond), each one that
/// [`BusOp::encode`] holds exactly.
pub fn advances(d: Duration) -> Vec<BusOp> {
    let max = u64::from(u16::MAX);
    let mut us = d.as_nanos() / 1_000;
    let mut out = Vec::new();
    for unit in [10_000u64, 1_000, 1] {
        while us >= unit {
            let n = (us / unit).min(max);
            out.push(BusOp::Advance(Duration::from_micros(n * unit)));
            us -= n * unit;
        }
    }
    out
}

/// The bus operations of a trace (a scenario's run) as fuzz ops, with the
/// time between them: a valid command sequence to seed the corpus with.
/// Waits for a flag become the status read that ended them.
pub fn from_trace(trace: &Trace) -> Vec<BusOp> {
    let mut out = Vec::new();
    let mut last = Instant::ZERO;
    for e in &trace.events {
        let EventKind::Bus(b) = &e.kind else {
            continue;
        };
        let op = match b {
            BusEvent::WriteCommand { byte, .. } => BusOp::Command(*byte),
            BusEvent::WriteData { byte, .. } => BusOp::Data(*byte),
            BusEvent::ReadStatus(_) | BusEvent::Await { .. } | BusEvent::WriteTimedOut { .. } => {
                BusOp::ReadStatus
            }
            BusEvent::ReadData { .. } | BusEvent::ReadTimedOut => BusOp::ReadData,
            BusEvent::SetInput { input, asserted } => BusOp::Input {
                input: *input,
                asserted: *asserted,
            },
            BusEvent::AwaitPulses { .. } | BusEvent::Reset => continue,
        };
        out.extend(advances(e.at.saturating_since(last)));
        last = e.at;
        out.push(op);
    }
    out
}

/// Splits an input into its ops.
pub fn decode(data: &[u8]) -> Vec<BusOp> {
    ops(data).collect()
}

/// The ops of an input, one at a time, as [`decode`] gives them.
pub fn ops(data: &[u8]) -> Ops<'_> {
    Ops {
        data,
        start: 0,
        base: 0,
        fs: 0,
        done: false,
    }
}

/// The iterator of [`ops`]. It runs on every fuzz input, in a build that
/// counts every branch taken, so it reads the input eight bytes at a time:
/// a word with no `F` holds no separator start, and only an `F` is
/// compared with the separator. (No byte of "FUZZ" after the first is an
/// `F`, so separators never overlap and every match is a cut.)
#[derive(Debug, Clone)]
pub struct Ops<'a> {
    data: &'a [u8],
    /// Where the op being scanned starts.
    start: usize,
    /// Where the next word to scan starts.
    base: usize,
    /// The candidate `F`s of the word before `base`, each as its top bit.
    fs: u64,
    /// The last op (after the last separator) has been given.
    done: bool,
}

impl Iterator for Ops<'_> {
    type Item = BusOp;

    #[inline]
    fn next(&mut self) -> Option<BusOp> {
        const WORD: u32 = u32::from_le_bytes(*SEPARATOR);
        const ONES: u64 = u64::from_le_bytes([1; 8]);
        const FS: u64 = ONES * SEPARATOR[0] as u64;
        let data = self.data;
        loop {
            while self.fs != 0 {
                let i = self.base - 8 + self.fs.trailing_zeros() as usize / 8;
                self.fs &= self.fs - 1;
                let cut = matches!(data.get(i..i + 4), Some(&[a, b, c, d]) if u32::from_le_bytes([a, b, c, d]) == WORD);
                if cut {
                    let op = BusOp::decode(data.get(self.start..i).unwrap_or_default());
                    self.start = i + SEPARATOR.len();
                    if op.is_some() {
                        return op;
                    }
                }
            }
            if self.base >= data.len() {
                break;
            }
            // The next eight bytes (the last word padded with zeros), and
            // the bytes equal to F in it, each as its top bit: the SWAR
            // test for a zero byte, which may also flag a byte just above
            // a true one; the comparison with the separator rejects it.
            let word = match data.get(self.base..self.base + 8) {
                Some(bytes) => <[u8; 8]>::try_from(bytes).unwrap_or_default(),
                None => {
                    let mut word = [0u8; 8];
                    let tail = &data[self.base..];
                    word[..tail.len()].copy_from_slice(tail);
                    word
                }
            };
            let x = u64::from_le_bytes(word) ^ FS;
            self.fs = x.wrapping_sub(ONES) & !x & (ONES << 7);
            self.base += 8;
        }
        if self.done {
            return None;
        }
        self.done = true;
        BusOp::decode(data.get(self.start..).unwrap_or_default())
    }
}

/// Joins ops into an input that decodes to them.
pub fn encode(ops: &[BusOp]) -> Vec<u8> {
    let mut out = Vec::new();
    for (i, op) in ops.iter().enumerate() {
        if i > 0 {
            out.extend_from_slice(SEPARATOR);
        }
        out.extend(op.encode());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ops_round_trip_through_bytes() {
        let ops = vec![
            BusOp::Command(0x06),
            BusOp::Data(100),
            BusOp::ReadStatus,
            BusOp::ReadData,
            BusOp::Input {
                input: Input::Cnp,
                asserted: true,
            },
            BusOp::Advance(Duration::from_micros(250)),
            BusOp::Advance(Duration::from_millis(200)),
            BusOp::Advance(Duration::from_secs(30)),
        ];
        assert_eq!(decode(&encode(&ops)), ops);
        let odd = Duration::from_micros(1_234_567_891);
        let parts = advances(odd);
        let total: u64 = parts
            .iter()
            .map(|p| match p {
                BusOp::Advance(d) => d.as_nanos(),
                _ => 0,
            })
            .sum();
        assert_eq!(total, odd.as_nanos());
        assert_eq!(decode(&encode(&parts)), parts);
    }

    #[test]
    fn a_mutation_in_one_op_leaves_the_others() {
        let ops = vec![BusOp::Command(0x06), BusOp::Data(100), BusOp::ReadStatus];
        let mut bytes = encode(&ops);
        // Insert a byte into the first op: it changes, the rest do not.
        bytes.insert(1, 0x55);
        let got = decode(&bytes);
        assert_eq!(got.len(), 3);
        assert_eq!(&got[1..], &ops[1..]);
    }

    proptest::proptest! {
        /// The one-pass decoder splits as cutting the input at every
        /// separator, left to right, would.
        #[test]
        fn decoding_splits_at_every_separator(
            parts in proptest::collection::vec(
                proptest::collection::vec(proptest::sample::select(b"FUZG\x00\x05".to_vec()), 0..12),
                0..6,
            ),
        ) {
            let data = parts.join(&b"FUZZ"[..]);
            let mut want = Vec::new();
            let mut rest = &data[..];
            loop {
                match rest.windows(4).position(|w| w == SEPARATOR) {
                    Some(i) => {
                        want.extend(BusOp::decode(&rest[..i]));
                        rest = &rest[i + 4..];
                    }
                    None => {
                        want.extend(BusOp::decode(rest));
                        break;
                    }
                }
            }
            proptest::prop_assert_eq!(decode(&data), want);
        }
    }

    #[test]
    fn empty_ops_and_short_operands_decode() {
        assert_eq!(decode(b""), vec![]);
        assert_eq!(decode(b"FUZZFUZZ"), vec![]);
        assert_eq!(decode(&[0]), vec![BusOp::Command(0)]);
    }
}

//! The bus console language: one operation per line, `#` comments, `;`
//! between operations on one line. Documented in `docs/console.md`.
//!
//! [`parse_script`] turns text into [`Stmt`]s (and is what fuzz reproducers
//! are printed in: `Stmt`'s `Display` writes the canonical form back);
//! [`run`] executes statements on a [`Target`] and prints one line per
//! result.

use crate::backend::{Op, Reply, Target, TargetError, Uncertainty};
pub use crate::protocol::Flag;
use crate::protocol::{Direction, Input, Status};
use crate::time::{Duration, Instant};
use crate::trace::BusEvent;
use std::fmt;
use std::io::{self, Write};

/// One console operation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stmt {
    /// `wc <byte>` (flowchart: wait for IBF = 0 first) or `wc! <byte>`.
    WriteCommand { byte: u8, wait: bool },
    /// `wd <byte>` or `wd! <byte>`.
    WriteData { byte: u8, wait: bool },
    /// `rs`.
    ReadStatus,
    /// `rd` (wait for OBF = 1 first) or `rd!`.
    ReadData { wait: bool },
    /// `wait <duration>`: from the moment of the statement before.
    Wait(Duration),
    /// `wait at <time>`: until the target's clock reads `time` (since the
    /// last reset), so that the next statement acts then.
    WaitAt(Instant),
    /// `await <flag>=<0|1> [<timeout>]`.
    Await {
        flag: Flag,
        value: bool,
        timeout: Option<Duration>,
    },
    /// `await pulse=<n> [<timeout>]`: until the most recent move has put
    /// out its `n`-th pulse, so that the next statement acts right after
    /// it, on the target's own clock.
    AwaitPulse {
        count: u64,
        timeout: Option<Duration>,
    },
    /// `set <input> <on|off>`.
    Set { input: Input, asserted: bool },
    /// `pins`.
    Pins,
    /// `pulses`.
    Pulses,
    /// `now`.
    Now,
}

/// A statement and the 1-based line it came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Line {
    pub line: usize,
    pub stmt: Stmt,
}

/// A script that does not parse: `line N: <what is wrong>`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct ScriptError {
    pub line: usize,
    pub message: String,
}

const OPS: &str = "wc, wc!, wd, wd!, rs, rd, rd!, wait, await, set, pins, pulses, now";

/// Why a console argument is not a byte.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ByteError {
    /// Not a number in any of the accepted forms.
    #[error("`{0}` is not a byte (write 0xNN, decimal or 0bNNNNNNNN)")]
    NotANumber(String),
    /// A number above 255.
    #[error("`{0}` is out of range for a byte (0..=255)")]
    OutOfRange(String),
}

/// Parses a byte written as `0xNN`, decimal or `0bNNNNNNNN`.
pub fn parse_byte(s: &str) -> Result<u8, ByteError> {
    let lower = s.to_ascii_lowercase();
    let (digits, radix) = if let Some(h) = lower.strip_prefix("0x") {
        (h, 16)
    } else if let Some(b) = lower.strip_prefix("0b") {
        (b, 2)
    } else {
        (lower.as_str(), 10)
    };
    let value = u32::from_str_radix(digits, radix).map_err(|_| ByteError::NotANumber(s.into()))?;
    u8::try_from(value).map_err(|_| ByteError::OutOfRange(s.into()))
}

fn parse_stmt(text: &str) -> Result<Stmt, String> {
    let mut words = text.split_whitespace();
    let op = words.next().unwrap_or_default().to_ascii_lowercase();
    let args: Vec<&str> = words.collect();
    let want = |n: usize, usage: &str| -> Result<(), String> {
        if args.len() == n {
            Ok(())
        } else {
            Err(format!("`{op}` takes {usage}, got `{}`", args.join(" ")))
        }
    };
    let byte_arg = |usage: &str| -> Result<u8, String> {
        want(1, usage)?;
        parse_byte(args[0]).map_err(|e| e.to_string())
    };
    let stmt = match op.as_str() {
        "wc" | "wc!" => Stmt::WriteCommand {
            byte: byte_arg("one byte")?,
            wait: op == "wc",
        },
        "wd" | "wd!" => Stmt::WriteData {
            byte: byte_arg("one byte")?,
            wait: op == "wd",
        },
        "rs" => {
            want(0, "no arguments")?;
            Stmt::ReadStatus
        }
        "rd" | "rd!" => {
            want(0, "no arguments")?;
            Stmt::ReadData { wait: op == "rd" }
        }
        "wait" => match args.as_slice() {
            ["at", t] => {
                let d: Duration = t.parse().map_err(|e| format!("{e}"))?;
                Stmt::WaitAt(Instant::ZERO + d)
            }
            _ => {
                want(
                    1,
                    "a duration such as 250us, or `at` and a time such as 1500us",
                )?;
                Stmt::Wait(args[0].parse().map_err(|e| format!("{e}"))?)
            }
        },
        "await" => {
            if args.is_empty() || args.len() > 2 {
                return Err(
                    "`await` takes <flag>=<0|1> [<timeout>], e.g. `await busy=0 2s`".into(),
                );
            }
            let (flag, value) = args[0]
                .split_once('=')
                .ok_or_else(|| format!("`{}` should be <flag>=<0|1>", args[0]))?;
            let timeout = match args.get(1) {
                Some(t) => Some(t.parse().map_err(|e| format!("{e}"))?),
                None => None,
            };
            if flag.eq_ignore_ascii_case("pulse") {
                let count = value
                    .parse::<u64>()
                    .ok()
                    .filter(|n| *n > 0)
                    .ok_or_else(|| format!("pulse number `{value}` should be 1 or more"))?;
                return Ok(Stmt::AwaitPulse { count, timeout });
            }
            let flag = Flag::from_name(&flag.to_ascii_lowercase()).ok_or_else(|| {
                format!("unknown flag `{flag}` (expected ibf, obf, busy, err or pulse)")
            })?;
            let value = match value {
                "0" => false,
                "1" => true,
                _ => return Err(format!("flag value `{value}` should be 0 or 1")),
            };
            Stmt::Await {
                flag,
                value,
                timeout,
            }
        }
        "set" => {
            want(2, "<input> <on|off>")?;
            let input = Input::from_name(&args[0].to_ascii_lowercase()).ok_or_else(|| {
                format!(
                    "unknown input `{}` (expected l1 l2 l3 l4 alm cnp auxi0 auxi1 auxi2 auxi3)",
                    args[0]
                )
            })?;
            let asserted = match args[1].to_ascii_lowercase().as_str() {
                "on" => true,
                "off" => false,
                other => return Err(format!("`{other}` should be on or off")),
            };
            Stmt::Set { input, asserted }
        }
        "pins" => {
            want(0, "no arguments")?;
            Stmt::Pins
        }
        "pulses" => {
            want(0, "no arguments")?;
            Stmt::Pulses
        }
        "now" => {
            want(0, "no arguments")?;
            Stmt::Now
        }
        other => return Err(format!("unknown op `{other}` (expected one of {OPS})")),
    };
    Ok(stmt)
}

/// Parses one line (which may hold several `;`-separated operations).
pub fn parse_line(text: &str, line: usize) -> Result<Vec<Line>, ScriptError> {
    let code = text.split('#').next().unwrap_or_default();
    code.split(';')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            parse_stmt(s)
                .map(|stmt| Line { line, stmt })
                .map_err(|message| ScriptError { line, message })
        })
        .collect()
}

/// Parses a whole script; the first bad line is the error.
pub fn parse_script(text: &str) -> Result<Vec<Line>, ScriptError> {
    let mut out = Vec::new();
    for (i, l) in text.lines().enumerate() {
        out.extend(parse_line(l, i + 1)?);
    }
    Ok(out)
}

impl fmt::Display for Stmt {
    /// The canonical script form, which [`parse_line`] reads back.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let bang = |wait: bool| if wait { "" } else { "!" };
        match *self {
            Stmt::WriteCommand { byte, wait } => write!(f, "wc{} 0x{byte:02X}", bang(wait)),
            Stmt::WriteData { byte, wait } => write!(f, "wd{} 0x{byte:02X}", bang(wait)),
            Stmt::ReadStatus => f.write_str("rs"),
            Stmt::ReadData { wait } => write!(f, "rd{}", bang(wait)),
            Stmt::Wait(d) => write!(f, "wait {}ns", d.as_nanos()),
            Stmt::WaitAt(t) => write!(f, "wait at {}ns", t.as_nanos()),
            Stmt::Await {
                flag,
                value,
                timeout,
            } => {
                write!(f, "await {}={}", flag.name(), u8::from(value))?;
                if let Some(t) = timeout {
                    write!(f, " {}ns", t.as_nanos())?;
                }
                Ok(())
            }
            Stmt::AwaitPulse { count, timeout } => {
                write!(f, "await pulse={count}")?;
                if let Some(t) = timeout {
                    write!(f, " {}ns", t.as_nanos())?;
                }
                Ok(())
            }
            Stmt::Set { input, asserted } => {
                write!(
                    f,
                    "set {} {}",
                    input.name(),
                    if asserted { "on" } else { "off" }
                )
            }
            Stmt::Pins => f.write_str("pins"),
            Stmt::Pulses => f.write_str("pulses"),
            Stmt::Now => f.write_str("now"),
        }
    }
}

/// Timeouts the console applies where a script gives none.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConsoleOptions {
    /// How long `wc` / `wd` wait for IBF = 0.
    pub ibf_timeout: Duration,
    /// How long `rd` waits for OBF = 1.
    pub obf_timeout: Duration,
    /// How long `await` waits without an explicit timeout.
    pub await_timeout: Duration,
}

impl Default for ConsoleOptions {
    fn default() -> Self {
        ConsoleOptions {
            ibf_timeout: Duration::from_secs(1),
            obf_timeout: Duration::from_secs(1),
            await_timeout: Duration::from_secs(1),
        }
    }
}

/// Why a console run stopped early.
#[derive(Debug, thiserror::Error)]
pub enum ConsoleError {
    /// The target failed (link, port): not a result of the script.
    #[error("line {line}: target failed: {source}")]
    Target {
        line: usize,
        #[source]
        source: TargetError,
    },
    /// Writing the output failed.
    #[error("writing output: {0}")]
    Io(#[from] io::Error),
    /// The target answered with a reply that does not fit the op.
    #[error("line {line}: target answered {reply} to `{stmt}`")]
    Protocol {
        line: usize,
        stmt: Stmt,
        reply: String,
    },
}

/// The target op a statement runs as.
pub fn to_op(stmt: Stmt, opts: &ConsoleOptions) -> Op {
    let wait_ibf = |wait: bool| wait.then_some(opts.ibf_timeout);
    match stmt {
        Stmt::WriteCommand { byte, wait } => Op::WriteCommand {
            byte,
            wait_ibf: wait_ibf(wait),
        },
        Stmt::WriteData { byte, wait } => Op::WriteData {
            byte,
            wait_ibf: wait_ibf(wait),
        },
        Stmt::ReadStatus => Op::ReadStatus,
        Stmt::ReadData { wait } => Op::ReadData {
            wait_obf: wait.then_some(opts.obf_timeout),
        },
        Stmt::Wait(d) => Op::Delay(d),
        // Its delay depends on the time of the statement before: [`run`]
        // works it out from that statement's reply.
        Stmt::WaitAt(_) => Op::Delay(Duration::ZERO),
        Stmt::Await {
            flag,
            value,
            timeout,
        } => Op::await_flag(flag, value, timeout.unwrap_or(opts.await_timeout)),
        Stmt::AwaitPulse { count, timeout } => Op::AwaitPulses {
            count,
            timeout: timeout.unwrap_or(opts.await_timeout),
        },
        Stmt::Set { input, asserted } => Op::SetInput { input, asserted },
        Stmt::Pins => Op::ReadPins,
        Stmt::Pulses => Op::ReadPulses,
        Stmt::Now => Op::Delay(Duration::ZERO),
    }
}

/// The bus transaction a statement's reply shows, as traces record it
/// (`None` for statements that touch no register or pin: `wait`, `pins`,
/// `pulses`, `now`).
pub fn bus_event(stmt: Stmt, reply: &Reply) -> Option<BusEvent> {
    BusEvent::of(&to_op(stmt, &ConsoleOptions::default()), reply)
}

fn opt_time<T: fmt::Display>(t: Option<T>) -> String {
    t.map_or_else(|| "-".to_string(), |t| t.to_string())
}

/// The output line for a statement's reply, or `None` for statements that
/// print nothing when they succeed (writes, `wait`, `set`).
pub fn format_reply(stmt: Stmt, reply: &Reply) -> Option<String> {
    let flag_bit = |status: Status, mask: u8| u8::from(status.0 & mask != 0);
    match (stmt, reply) {
        (Stmt::WriteCommand { byte, .. }, Reply::WriteTimedOut { status, .. }) => Some(format!(
            "wc 0x{byte:02X} timeout ibf={}",
            flag_bit(*status, Status::IBF)
        )),
        (Stmt::WriteData { byte, .. }, Reply::WriteTimedOut { status, .. }) => Some(format!(
            "wd 0x{byte:02X} timeout ibf={}",
            flag_bit(*status, Status::IBF)
        )),
        (Stmt::ReadStatus, Reply::Status { status, .. }) => Some(format!("rs 0x{:02X}", status.0)),
        (Stmt::ReadData { .. }, Reply::Data { byte, .. }) => Some(format!("rd 0x{byte:02X}")),
        (Stmt::ReadData { .. }, Reply::ReadTimedOut { status, .. }) => {
            Some(format!("rd timeout obf={}", flag_bit(*status, Status::OBF)))
        }
        (Stmt::Await { flag, value, .. }, Reply::Awaited { waited, .. }) => Some(format!(
            "await {}={} after {waited}",
            flag.name(),
            u8::from(value)
        )),
        (Stmt::Await { flag, value, .. }, Reply::AwaitTimedOut { .. }) => {
            Some(format!("await {}={} timeout", flag.name(), u8::from(value)))
        }
        (Stmt::AwaitPulse { count, .. }, Reply::PulsesReached { .. }) => {
            Some(format!("await pulse={count}"))
        }
        (Stmt::AwaitPulse { count, .. }, Reply::PulsesTimedOut { count: seen, .. }) => {
            Some(format!("await pulse={count} timeout after {seen} pulses"))
        }
        (Stmt::Pins, Reply::Pins { pins, .. }) => Some(format!(
            "pins int={} hold={} aux={} auxo=0b{:04b} s=0b{:05b} dir={}",
            u8::from(pins.int),
            u8::from(pins.hold),
            u8::from(pins.aux),
            pins.auxo,
            pins.phases,
            match pins.dir {
                Direction::Cw => "cw",
                Direction::Ccw => "ccw",
            }
        )),
        (Stmt::Pulses, Reply::Pulses { summary: s, .. }) => Some(format!(
            "pulses count={} cw={} ccw={} first={} last={} min={} max={}",
            s.count,
            s.cw,
            s.ccw,
            opt_time(s.first),
            opt_time(s.last),
            opt_time(s.min_interval),
            opt_time(s.max_interval)
        )),
        (Stmt::Now, Reply::Delayed { .. }) => Some("now".into()),
        (Stmt::WriteCommand { .. } | Stmt::WriteData { .. }, Reply::Written { .. })
        | (Stmt::Wait(_) | Stmt::WaitAt(_), Reply::Delayed { .. })
        | (Stmt::Set { .. }, Reply::InputSet { .. }) => None,
        _ => Some(format!("?? unexpected reply: {reply}")),
    }
}

/// How many statements go to the target in one batch.
pub const BATCH: usize = 256;

/// Whether a statement touches the bus or the pins: what `now` stamps.
fn is_access(stmt: Stmt) -> bool {
    !matches!(
        stmt,
        Stmt::Wait(_) | Stmt::WaitAt(_) | Stmt::Now | Stmt::Pulses | Stmt::AwaitPulse { .. }
    )
}

/// How sure the target is of the time a statement's reply carries: a
/// wait for a flag ends where the bridge's loop saw it change (`polled`),
/// a pulse waited for is a captured edge, the rest (a wait for a pulse
/// that gave up included) are an access's own stamp or the clock.
fn path(stmt: Stmt, reply: &Reply, u: &Uncertainty) -> Duration {
    match (stmt, reply) {
        (Stmt::Await { .. }, _) => u.polled,
        (Stmt::AwaitPulse { .. }, Reply::PulsesReached { .. }) => u.edge,
        _ => u.access,
    }
}

/// ` at <time>`, and ` ±<U>` where the target is not exact.
fn stamp(at: Instant, u: Duration) -> String {
    if u == Duration::ZERO {
        format!(" at {at}")
    } else {
        format!(" at {at} \u{b1}{u}")
    }
}

/// Runs `lines` on `target`, writing one line per result to `out`, each
/// with the target's time of it (` at <time>`, and its uncertainty where
/// the target has one). The statements go in batches, so a board costs
/// one round trip per batch; a `wait at` starts a batch of its own (its
/// delay counts from the time of the statement before), and a batch never
/// ends with a `now` that another statement follows (it shows that one's
/// time).
pub fn run(
    target: &mut dyn Target,
    lines: &[Line],
    opts: &ConsoleOptions,
    out: &mut dyn Write,
) -> Result<(), ConsoleError> {
    let u = target.uncertainty();
    // The time of the last statement run: where a `wait` counts from.
    let mut last: Option<Instant> = None;
    let mut i = 0;
    while i < lines.len() {
        let mut end = i + 1;
        while end < lines.len() && end - i < BATCH && !matches!(lines[end].stmt, Stmt::WaitAt(_)) {
            end += 1;
        }
        while end < lines.len()
            && end > i + 1
            && lines[end - 1].stmt == Stmt::Now
            && !matches!(lines[end].stmt, Stmt::WaitAt(_))
        {
            end -= 1;
        }
        let chunk = &lines[i..end];
        let line = chunk[0].line;
        let failed = |source| ConsoleError::Target { line, source };
        let mut ops: Vec<Op> = chunk.iter().map(|l| to_op(l.stmt, opts)).collect();
        if let Stmt::WaitAt(t) = chunk[0].stmt {
            let from = match last {
                Some(at) => at,
                None => clock(target).map_err(failed)?,
            };
            ops[0] = Op::Delay(t.saturating_since(from));
        }
        let replies = target.execute(&ops).map_err(failed)?;
        if replies.len() != ops.len() {
            return Err(failed(TargetError::new(
                crate::backend::TargetErrorKind::Other,
                format!(
                    "target answered {} of {} operations",
                    replies.len(),
                    ops.len()
                ),
            )));
        }
        for (k, (l, reply)) in chunk.iter().zip(&replies).enumerate() {
            // Where the wait ended, if not at its time (within the
            // target's uncertainty): the clock was past it already, or the
            // statement before ended at another time than its reply says.
            if let (Stmt::WaitAt(t), 0) = (l.stmt, k) {
                let at = reply.at();
                let off = if at > t + u.access {
                    Some(("late", at.saturating_since(t)))
                } else if at + u.access < t {
                    Some(("early", t.saturating_since(at)))
                } else {
                    None
                };
                if let Some((how, by)) = off {
                    writeln!(out, "wait at {t} {how} by {by}{}", stamp(at, u.access))?;
                }
                continue;
            }
            let Some(text) = format_reply(l.stmt, reply) else {
                continue;
            };
            if text.starts_with("??") {
                return Err(ConsoleError::Protocol {
                    line: l.line,
                    stmt: l.stmt,
                    reply: reply.to_string(),
                });
            }
            // `now` shows the time of the access that follows it.
            let (shown, by) = match (l.stmt, chunk.get(k + 1), replies.get(k + 1)) {
                (Stmt::Now, Some(next), Some(r)) if is_access(next.stmt) => (next.stmt, r),
                _ => (l.stmt, reply),
            };
            writeln!(out, "{text}{}", stamp(by.at(), path(shown, by, &u)))?;
        }
        last = replies.last().map(Reply::at).or(last);
        i = end;
    }
    Ok(())
}

/// The target's clock, where a `wait at` opens a script.
fn clock(target: &mut dyn Target) -> Result<Instant, TargetError> {
    let r = target.execute(&[Op::Delay(Duration::ZERO)])?;
    Ok(r.last().map_or(Instant::ZERO, Reply::at))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    #[case("0x43", 0x43)]
    #[case("0XfF", 0xFF)]
    #[case("100", 100)]
    #[case("0b11100111", 0xE7)]
    fn bytes_parse(#[case] text: &str, #[case] value: u8) {
        assert_eq!(parse_byte(text), Ok(value));
    }

    #[rstest]
    #[case("256", "out of range")]
    #[case("0x1G", "not a byte")]
    #[case("-1", "not a byte")]
    fn bad_bytes_say_why(#[case] text: &str, #[case] why: &str) {
        let err = parse_byte(text).expect_err("bad byte").to_string();
        assert!(err.contains(why), "{err}");
    }

    #[test]
    fn script_with_comments_and_semicolons() {
        let s = "# init\nwc 0x02 ; wd 100 # rate\n\nawait busy=0 2s\nset l1 on\nrd!\n";
        let lines = parse_script(s).expect("parses");
        let got: Vec<(usize, String)> =
            lines.iter().map(|l| (l.line, l.stmt.to_string())).collect();
        assert_eq!(
            got,
            vec![
                (2, "wc 0x02".to_string()),
                (2, "wd 0x64".to_string()),
                (4, "await busy=0 2000000000ns".to_string()),
                (5, "set l1 on".to_string()),
                (6, "rd!".to_string()),
            ]
        );
    }

    #[rstest]
    #[case("wc", 1, "takes one byte")]
    #[case("rs\nfoo 1", 2, "unknown op `foo`")]
    #[case("\n\nwait 10", 3, "needs a unit")]
    #[case("await busy=2", 1, "0 or 1")]
    #[case("await fast=1", 1, "unknown flag")]
    #[case("set l9 on", 1, "unknown input")]
    #[case("set l1 maybe", 1, "on or off")]
    #[case("wd 0x100", 1, "out of range")]
    fn bad_lines_name_the_line(#[case] script: &str, #[case] line: usize, #[case] why: &str) {
        let err = parse_script(script).expect_err("bad script");
        assert_eq!(err.line, line);
        assert!(
            err.to_string().starts_with(&format!("line {line}: ")),
            "{err}"
        );
        assert!(err.message.contains(why), "{err}");
    }

    proptest::proptest! {
        /// The canonical form of any statement parses back to it.
        #[test]
        fn canonical_form_round_trips(byte: u8, ns in 0u64..10_000_000_000, which in 0usize..10, flag in 0usize..4, b: bool, inp in 0usize..10) {
            let flags = [Flag::Ibf, Flag::Obf, Flag::Busy, Flag::Err];
            let stmt = match which {
                0 => Stmt::WriteCommand { byte, wait: b },
                1 => Stmt::WriteData { byte, wait: b },
                2 => Stmt::ReadStatus,
                3 => Stmt::ReadData { wait: b },
                4 => Stmt::Wait(Duration::from_nanos(ns)),
                5 if byte % 2 == 0 => Stmt::Await { flag: flags[flag], value: b, timeout: b.then_some(Duration::from_nanos(ns)) },
                5 => Stmt::AwaitPulse { count: 1 + ns, timeout: b.then_some(Duration::from_nanos(ns)) },
                6 => Stmt::Set { input: Input::ALL[inp], asserted: b },
                7 => Stmt::Pins,
                8 => Stmt::Pulses,
                _ => Stmt::Now,
            };
            let parsed = parse_line(&stmt.to_string(), 1).expect("canonical form parses");
            proptest::prop_assert_eq!(parsed, vec![Line { line: 1, stmt }]);
        }
    }
}

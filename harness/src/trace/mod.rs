//! Traces: what happened during one scenario, as text that diffs well.
//!
//! ```text
//! ppmc-trace 1
//! scenario s3_3_5_constant_speed_moves_n_steps
//! section 3-3-5
//! target emu
//! detail sysclk_hz 16000000
//! events
//! 0.000us reset
//! 200000.000us wc 0x44
//! 200012.000us move constant cw steps=100 pout=0 winding=4ph-2 phase=0
//! 200060.000us pin busy 1
//! 200206.000us pulses cw n=100 dt=102.000us
//! 200260.000us measure constant_first_pout 194.000us
//! end
//! ```
//!
//! One event per line, each stamped with the target's clock. Constant-rate
//! pulse runs are one `pulses` line; acceleration ramps are one line per
//! change of period. A run captured by a bridge whose timer is not locked to
//! the chip's clock is `pulses cw n=100 span=10098.031us jitter=0.016us`:
//! the last pulse `span` after the first, every pulse within `jitter` of the
//! straight line between them. The `end` line makes a truncated file detectable. A
//! golden file may start with insta's `---` front matter, which is skipped.
//! [`Trace::parse`] reads back exactly what [`Trace::render`] writes.

use crate::backend::{Op, Reply};
use crate::protocol::{
    Direction, Flag, Input, MoveKind, OutputRecord, Pin, PulseRun, StrapFieldError, Straps,
    Winding, STRAP_KEYS,
};
use crate::time::{Duration, Instant};
use std::fmt::{self, Write as _};

mod figures;
mod uncertainty;

pub use figures::figures;
use uncertainty::parse_uncertainty;
pub use uncertainty::{uncertainty_detail, uncertainty_entry, UNCERTAINTY};

/// The format version written in the first line.
pub const TRACE_VERSION: u32 = 1;

/// The detail a trace made from a logic-analyzer capture carries
/// (`ppmc judge --trace`): the pins it holds, by their names, `,` between.
/// A compare with such a trace looks at what a capture can say of the
/// chip ([`crate::compare`]).
pub const CAPTURE_PINS: &str = "capture_pins";

/// A complete trace of one scenario run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Trace {
    pub scenario: String,
    pub section: String,
    pub target: String,
    /// How the target's chip was strapped (`detail` lines, first).
    pub straps: Straps,
    /// Other target facts, `key value` (`detail` lines after the straps).
    pub details: Vec<(String, String)>,
    pub events: Vec<Event>,
}

/// One thing that happened at a point in the target's time.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Event {
    pub at: Instant,
    pub kind: EventKind,
}

impl Event {
    /// The pulse run of a `pulses` event.
    pub fn pulse_run(&self) -> Option<PulseRun> {
        match self.kind {
            EventKind::Pulses {
                dir,
                count,
                span,
                jitter,
            } => Some(PulseRun {
                start: self.at,
                count,
                dir,
                span,
                jitter,
            }),
            _ => None,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EventKind {
    Bus(BusEvent),
    /// A move started: its final byte was written at `at`.
    Move {
        kind: MoveKind,
        dir: Direction,
        pout: bool,
        steps: u32,
        winding: Option<Winding>,
        phase: u32,
    },
    /// `count` pulses in `dir`, the first at `at`, the last `span` later,
    /// each within `jitter` of its place on the line between them (zero
    /// for equally spaced pulses): a [`PulseRun`].
    Pulses {
        dir: Direction,
        count: u32,
        span: Duration,
        jitter: Duration,
    },
    Pin {
        pin: Pin,
        value: u8,
    },
    /// A measured latency; `name` is a Table 3-3 row or a scenario's own.
    /// A Table 3-3 measurement, and its uncertainty (±, the instrument's:
    /// written `±0.134us` after the value where it is not 0).
    Measure {
        name: String,
        value: Duration,
        u: Duration,
    },
}

/// A host-side bus transaction and what it observed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BusEvent {
    /// A command register write; `waited` is how long the flowchart waited
    /// for IBF = 0 first, `None` for a raw write (`wc!`).
    WriteCommand {
        byte: u8,
        waited: Option<Duration>,
    },
    /// A data register write, as [`BusEvent::WriteCommand`].
    WriteData {
        byte: u8,
        waited: Option<Duration>,
    },
    /// A flowchart write that gave up because IBF stayed 1.
    WriteTimedOut {
        command: bool,
        byte: u8,
    },
    ReadStatus(u8),
    /// A data register read; `waited` for OBF = 1, `None` for `rd!`.
    ReadData {
        byte: u8,
        waited: Option<Duration>,
    },
    ReadTimedOut,
    Await {
        flag: Flag,
        value: bool,
        /// `Some(waited)`, or `None` on timeout.
        waited: Option<Duration>,
        status: u8,
    },
    SetInput {
        input: Input,
        asserted: bool,
    },
    AwaitPulses {
        count: u64,
        reached: bool,
    },
    Reset,
}

impl BusEvent {
    /// The bus transaction an op's reply shows, as traces record it: the
    /// one place a target's vocabulary ([`Op`], [`Reply`]) becomes a
    /// trace's. A write or read waited (`waited: Some`) when its op asked
    /// to wait. `None` for an op that touches no register or input (a
    /// delay, a pin sample, a pulse summary), an await on anything but one
    /// status flag, or a reply that does not answer the op.
    pub fn of(op: &Op, reply: &Reply) -> Option<BusEvent> {
        Some(match (*op, *reply) {
            (Op::WriteCommand { byte, wait_ibf }, Reply::Written { waited, .. }) => {
                BusEvent::WriteCommand {
                    byte,
                    waited: wait_ibf.map(|_| waited),
                }
            }
            (Op::WriteData { byte, wait_ibf }, Reply::Written { waited, .. }) => {
                BusEvent::WriteData {
                    byte,
                    waited: wait_ibf.map(|_| waited),
                }
            }
            (Op::WriteCommand { byte, .. }, Reply::WriteTimedOut { .. }) => {
                BusEvent::WriteTimedOut {
                    command: true,
                    byte,
                }
            }
            (Op::WriteData { byte, .. }, Reply::WriteTimedOut { .. }) => BusEvent::WriteTimedOut {
                command: false,
                byte,
            },
            (Op::ReadStatus, Reply::Status { status, .. }) => BusEvent::ReadStatus(status.0),
            (Op::ReadData { wait_obf }, Reply::Data { byte, waited, .. }) => BusEvent::ReadData {
                byte,
                waited: wait_obf.map(|_| waited),
            },
            (Op::ReadData { .. }, Reply::ReadTimedOut { .. }) => BusEvent::ReadTimedOut,
            (Op::AwaitStatus { mask, value, .. }, Reply::Awaited { waited, status, .. }) => {
                BusEvent::Await {
                    flag: flag_of(mask)?,
                    value: value != 0,
                    waited: Some(waited),
                    status: status.0,
                }
            }
            (Op::AwaitStatus { mask, value, .. }, Reply::AwaitTimedOut { status, .. }) => {
                BusEvent::Await {
                    flag: flag_of(mask)?,
                    value: value != 0,
                    waited: None,
                    status: status.0,
                }
            }
            (Op::SetInput { input, asserted }, Reply::InputSet { .. }) => {
                BusEvent::SetInput { input, asserted }
            }
            (Op::AwaitPulses { count, .. }, Reply::PulsesReached { .. }) => BusEvent::AwaitPulses {
                count,
                reached: true,
            },
            (Op::AwaitPulses { count, .. }, Reply::PulsesTimedOut { .. }) => {
                BusEvent::AwaitPulses {
                    count,
                    reached: false,
                }
            }
            (Op::Reset, Reply::ResetDone { .. }) => BusEvent::Reset,
            _ => return None,
        })
    }
}

/// The one status flag `mask` selects ([`Op::await_flag`]).
fn flag_of(mask: u8) -> Option<Flag> {
    [Flag::Ibf, Flag::Obf, Flag::Busy, Flag::Err]
        .into_iter()
        .find(|f| f.mask() == mask)
}

/// A trace file that cannot be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct TraceError {
    pub line: usize,
    pub message: String,
}

impl Trace {
    /// A trace with no events yet: what ran, where, at which straps.
    pub fn new(
        scenario: &str,
        section: &str,
        target: &str,
        straps: Straps,
        details: Vec<(String, String)>,
    ) -> Trace {
        Trace {
            scenario: scenario.to_string(),
            section: section.to_string(),
            target: target.to_string(),
            straps,
            details,
            events: Vec::new(),
        }
    }

    /// This trace with the driver's bus events and the target's capture,
    /// merged in time order. At one instant: pin changes and pulses, then
    /// bus transactions, then move starts, then measurements.
    pub fn assemble(self, bus: Vec<Event>, capture: &OutputRecord, measures: Vec<Event>) -> Trace {
        let mut tagged: Vec<(Instant, u8, usize, EventKind)> = Vec::new();
        let mut seq = 0usize;
        let mut push = |at: Instant, rank: u8, kind: EventKind, v: &mut Vec<_>| {
            v.push((at, rank, seq, kind));
            seq += 1;
        };
        for p in &capture.pins {
            push(
                p.at,
                0,
                EventKind::Pin {
                    pin: p.pin,
                    value: p.value,
                },
                &mut tagged,
            );
        }
        for r in &capture.runs {
            push(
                r.start,
                0,
                EventKind::Pulses {
                    dir: r.dir,
                    count: r.count,
                    span: r.span,
                    jitter: r.jitter,
                },
                &mut tagged,
            );
        }
        for e in bus {
            push(e.at, 1, e.kind, &mut tagged);
        }
        for m in &capture.moves {
            push(
                m.at,
                2,
                EventKind::Move {
                    kind: m.kind,
                    dir: m.dir,
                    pout: m.pout,
                    steps: m.steps,
                    winding: m.winding,
                    phase: m.phase_index,
                },
                &mut tagged,
            );
        }
        for e in measures {
            push(e.at, 3, e.kind, &mut tagged);
        }
        tagged.sort_by_key(|(at, rank, seq, _)| (*at, *rank, *seq));
        Trace {
            events: tagged
                .into_iter()
                .map(|(at, _, _, kind)| Event { at, kind })
                .collect(),
            ..self
        }
    }

    /// The canonical text form.
    pub fn render(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "ppmc-trace {TRACE_VERSION}");
        let _ = writeln!(s, "scenario {}", self.scenario);
        let _ = writeln!(s, "section {}", self.section);
        let _ = writeln!(s, "target {}", self.target);
        for (k, v) in self.straps.fields() {
            let _ = writeln!(s, "detail {k} {v}");
        }
        for (k, v) in &self.details {
            let _ = writeln!(s, "detail {k} {v}");
        }
        s.push_str("events\n");
        for e in &self.events {
            let _ = writeln!(s, "{} {}", e.at, e.kind);
        }
        s.push_str("end\n");
        s
    }

    /// Parses the text form. Errors name the line (1-based, counting any
    /// front matter) and what is wrong.
    pub fn parse(text: &str) -> Result<Trace, TraceError> {
        // A trace is plain text: a control character (a stray CR, a NUL)
        // is corruption, and would not survive a render (found by the
        // `trace_text` fuzz target). `lines()` already takes CRLF endings.
        for (i, l) in text.lines().enumerate() {
            if let Some(c) = l.chars().find(|c| c.is_control()) {
                return Err(err(
                    i + 1,
                    format!(
                        "control character U+{:04X} in the trace (a trace is plain text)",
                        u32::from(c)
                    ),
                ));
            }
        }
        let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l)).peekable();
        // insta front matter: `---` ... `---`.
        if lines.peek().is_some_and(|(_, l)| l.trim() == "---") {
            lines.next();
            loop {
                match lines.next() {
                    Some((_, l)) if l.trim() == "---" => break,
                    Some(_) => {}
                    None => return Err(err(0, "front matter `---` is never closed")),
                }
            }
        }
        let mut next = |what: &str| -> Result<(usize, &str), TraceError> {
            lines
                .next()
                .ok_or_else(|| err(0, format!("file ends before {what} (truncated?)")))
        };
        let (n, l) = next("the `ppmc-trace` header")?;
        let version = l.strip_prefix("ppmc-trace ").ok_or_else(|| {
            err(
                n,
                "not a ppmc trace: first line must be `ppmc-trace <version>`",
            )
        })?;
        if version.trim() != TRACE_VERSION.to_string() {
            return Err(err(
                n,
                format!(
                    "trace format version {} is not supported (this ppmc reads version {TRACE_VERSION})",
                    version.trim()
                ),
            ));
        }
        let mut field = |key: &str| -> Result<String, TraceError> {
            let (n, l) = next(key)?;
            l.strip_prefix(key)
                .and_then(|r| r.strip_prefix(' '))
                .map(str::to_string)
                .ok_or_else(|| err(n, format!("expected `{key} <value>`, found `{l}`")))
        };
        let scenario = field("scenario")?;
        let section = field("section")?;
        let target = field("target")?;
        let mut straps = Vec::new();
        let mut details = Vec::new();
        let mut parsed_straps = None;
        let mut events = Vec::new();
        let mut in_events = false;
        let mut ended = false;
        for (n, l) in lines {
            if ended {
                if l.trim().is_empty() {
                    continue;
                }
                return Err(err(n, "text after `end`"));
            }
            if !in_events {
                if l == "events" {
                    in_events = true;
                    // The straps come before the events, every one of them;
                    // an error names the strap's line (a missing one, this).
                    parsed_straps = Some(
                        Straps::from_fields(straps.iter().map(|&(k, v, _)| (k, v))).map_err(
                            |e| {
                                let key = match &e {
                                    StrapFieldError::Repeated(k)
                                    | StrapFieldError::BadValue { key: k, .. } => Some(*k),
                                    _ => None,
                                };
                                let line = straps
                                    .iter()
                                    .rev()
                                    .find(|(k, _, _)| Some(*k) == key)
                                    .map_or(n, |&(_, _, at)| at);
                                err(line, format!("{e} in the `detail` lines"))
                            },
                        )?,
                    );
                } else if let Some(rest) = l.strip_prefix("detail ") {
                    let (k, v) = rest
                        .split_once(' ')
                        .ok_or_else(|| err(n, "expected `detail <key> <value>`"))?;
                    if STRAP_KEYS.contains(&k) {
                        straps.push((k, v, n));
                    } else {
                        if k == UNCERTAINTY {
                            parse_uncertainty(v).map_err(|e| err(n, e))?;
                        }
                        details.push((k.to_string(), v.to_string()));
                    }
                } else {
                    return Err(err(
                        n,
                        format!("expected `detail` or `events`, found `{l}`"),
                    ));
                }
                continue;
            }
            if l == "end" {
                ended = true;
                continue;
            }
            events.push(parse_event(l).map_err(|m| err(n, m))?);
        }
        if !ended {
            return Err(err(
                text.lines().count(),
                "no `end` line: the trace is truncated",
            ));
        }
        let Some(straps) = parsed_straps else {
            return Err(err(text.lines().count(), "no `events` line"));
        };
        Ok(Trace {
            scenario,
            section,
            target,
            straps,
            details,
            events,
        })
    }
}

fn err(line: usize, message: impl Into<String>) -> TraceError {
    TraceError {
        line,
        message: message.into(),
    }
}

fn parse_time(s: &str) -> Result<Duration, String> {
    s.parse::<Duration>()
        .map_err(|e| format!("bad time `{s}`: {e}"))
}

fn parse_hex(s: &str) -> Result<u8, String> {
    s.strip_prefix("0x")
        .and_then(|h| u8::from_str_radix(h, 16).ok())
        .ok_or_else(|| format!("expected a byte as 0xNN, found `{s}`"))
}

fn parse_dir(s: &str) -> Result<Direction, String> {
    match s {
        "cw" => Ok(Direction::Cw),
        "ccw" => Ok(Direction::Ccw),
        _ => Err(format!("expected cw or ccw, found `{s}`")),
    }
}

fn kv<'a>(word: Option<&'a str>, key: &str) -> Result<&'a str, String> {
    word.and_then(|w| w.strip_prefix(key))
        .and_then(|w| w.strip_prefix('='))
        .ok_or_else(|| format!("expected `{key}=...`"))
}

fn parse_num<T: std::str::FromStr>(s: &str, what: &str) -> Result<T, String> {
    s.parse().map_err(|_| format!("bad {what} `{s}`"))
}

fn move_kind(name: &str) -> Option<MoveKind> {
    MoveKind::ALL.into_iter().find(|k| k.name() == name)
}

fn parse_event(line: &str) -> Result<Event, String> {
    let mut w = line.split_whitespace();
    let at = Instant::from_nanos(parse_time(w.next().ok_or("empty event line")?)?.as_nanos());
    let key = w.next().ok_or("missing event name")?;
    let kind = match key {
        "wc" | "wd" | "wc!" | "wd!" => {
            let byte = parse_hex(w.next().ok_or("missing byte")?)?;
            let waited = if key.ends_with('!') {
                None
            } else {
                Some(parse_time(kv(w.next(), "waited")?)?)
            };
            EventKind::Bus(if key.starts_with("wc") {
                BusEvent::WriteCommand { byte, waited }
            } else {
                BusEvent::WriteData { byte, waited }
            })
        }
        "wc-timeout" | "wd-timeout" => EventKind::Bus(BusEvent::WriteTimedOut {
            command: key == "wc-timeout",
            byte: parse_hex(w.next().ok_or("missing byte")?)?,
        }),
        "rs" => EventKind::Bus(BusEvent::ReadStatus(parse_hex(
            w.next().ok_or("missing byte")?,
        )?)),
        "rd" | "rd!" => {
            let byte = parse_hex(w.next().ok_or("missing byte")?)?;
            let waited = if key == "rd!" {
                None
            } else {
                Some(parse_time(kv(w.next(), "waited")?)?)
            };
            EventKind::Bus(BusEvent::ReadData { byte, waited })
        }
        "rd-timeout" => EventKind::Bus(BusEvent::ReadTimedOut),
        "await" => {
            let cond = w.next().ok_or("missing <flag>=<0|1>")?;
            let (f, v) = cond.split_once('=').ok_or("expected <flag>=<0|1>")?;
            let flag = Flag::from_name(f).ok_or_else(|| format!("unknown flag `{f}`"))?;
            let value = match v {
                "0" => false,
                "1" => true,
                _ => return Err(format!("flag value `{v}` should be 0 or 1")),
            };
            let waited = match w.next() {
                Some("after") => Some(parse_time(w.next().ok_or("missing wait time")?)?),
                Some("timeout") => None,
                _ => return Err("expected `after <time>` or `timeout`".into()),
            };
            let status = parse_hex(kv(w.next(), "status")?)?;
            EventKind::Bus(BusEvent::Await {
                flag,
                value,
                waited,
                status,
            })
        }
        "set" => {
            let name = w.next().ok_or("missing input")?;
            let input = Input::from_name(name).ok_or_else(|| format!("unknown input `{name}`"))?;
            let asserted = match w.next() {
                Some("on") => true,
                Some("off") => false,
                _ => return Err("expected on or off".into()),
            };
            EventKind::Bus(BusEvent::SetInput { input, asserted })
        }
        "await-pulses" => {
            let count = parse_num(w.next().ok_or("missing count")?, "pulse count")?;
            let reached = match w.next() {
                Some("reached") => true,
                Some("timeout") => false,
                _ => return Err("expected reached or timeout".into()),
            };
            EventKind::Bus(BusEvent::AwaitPulses { count, reached })
        }
        "reset" => EventKind::Bus(BusEvent::Reset),
        "move" => {
            let name = w.next().ok_or("missing move kind")?;
            let kind = move_kind(name).ok_or_else(|| format!("unknown move `{name}`"))?;
            let dir = parse_dir(w.next().ok_or("missing direction")?)?;
            let steps = parse_num(kv(w.next(), "steps")?, "step count")?;
            let pout = match kv(w.next(), "pout")? {
                "0" => false,
                "1" => true,
                other => return Err(format!("pout should be 0 or 1, found `{other}`")),
            };
            let winding = match kv(w.next(), "winding")? {
                "none" => None,
                name => Some(
                    Winding::from_name(name).ok_or_else(|| format!("unknown winding `{name}`"))?,
                ),
            };
            let phase = parse_num(kv(w.next(), "phase")?, "phase index")?;
            EventKind::Move {
                kind,
                dir,
                pout,
                steps,
                winding,
                phase,
            }
        }
        "pulses" => {
            let dir = parse_dir(w.next().ok_or("missing direction")?)?;
            let count: u32 = parse_num(kv(w.next(), "n")?, "pulse count")?;
            if count == 0 {
                return Err("a pulse run has at least one pulse".into());
            }
            // `dt=` for equally spaced pulses, `span= jitter=` otherwise.
            let (key, value) = w
                .next()
                .and_then(|t| t.split_once('='))
                .ok_or("expected `dt=` or `span=`")?;
            let (span, jitter) = match key {
                "dt" => {
                    let dt = parse_time(value)?;
                    (dt.saturating_mul(u64::from(count - 1)), Duration::ZERO)
                }
                "span" => (parse_time(value)?, parse_time(kv(w.next(), "jitter")?)?),
                _ => return Err(format!("expected `dt=` or `span=`, found `{key}=`")),
            };
            if count == 1 && span != Duration::ZERO {
                return Err("a single pulse spans no time".into());
            }
            EventKind::Pulses {
                dir,
                count,
                span,
                jitter,
            }
        }
        "pin" => {
            let name = w.next().ok_or("missing pin")?;
            let pin = Pin::from_name(name).ok_or_else(|| format!("unknown pin `{name}`"))?;
            let text = w.next().ok_or("missing value")?;
            let value = match text.strip_prefix("0b") {
                Some(bits) => {
                    u8::from_str_radix(bits, 2).map_err(|_| format!("bad pin value `{text}`"))?
                }
                None => parse_num(text, "pin value")?,
            };
            EventKind::Pin { pin, value }
        }
        "measure" => {
            let name = w.next().ok_or("missing measurement name")?.to_string();
            let value = parse_time(w.next().ok_or("missing value")?)?;
            let u = match w.next() {
                Some(t) => match t.strip_prefix('±') {
                    Some(u) => parse_time(u)?,
                    None => {
                        return Err(format!(
                            "unexpected `{t}`: a measurement's uncertainty is written `±0.134us`"
                        ))
                    }
                },
                None => Duration::ZERO,
            };
            EventKind::Measure { name, value, u }
        }
        other => return Err(format!("unknown event `{other}`")),
    };
    if let Some(extra) = w.next() {
        return Err(format!("unexpected `{extra}` at the end of the line"));
    }
    Ok(Event { at, kind })
}

impl fmt::Display for EventKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EventKind::Bus(b) => write!(f, "{b}"),
            EventKind::Move {
                kind,
                dir,
                pout,
                steps,
                winding,
                phase,
            } => write!(
                f,
                "move {} {} steps={steps} pout={} winding={} phase={phase}",
                kind.name(),
                dir.name(),
                u8::from(*pout),
                winding.map_or("none", Winding::name)
            ),
            EventKind::Pulses {
                dir,
                count,
                span,
                jitter,
            } => {
                let run = PulseRun {
                    start: Instant::ZERO,
                    count: *count,
                    dir: *dir,
                    span: *span,
                    jitter: *jitter,
                };
                if run.is_exact() {
                    write!(f, "pulses {} n={count} dt={}", dir.name(), run.interval())
                } else {
                    write!(
                        f,
                        "pulses {} n={count} span={span} jitter={jitter}",
                        dir.name()
                    )
                }
            }
            EventKind::Pin { pin, value } => match pin {
                Pin::Phases => write!(f, "pin {} 0b{value:05b}", pin.name()),
                Pin::Auxo => write!(f, "pin {} 0b{value:04b}", pin.name()),
                _ => write!(f, "pin {} {value}", pin.name()),
            },
            EventKind::Measure { name, value, u } if *u == Duration::ZERO => {
                write!(f, "measure {name} {value}")
            }
            EventKind::Measure { name, value, u } => write!(f, "measure {name} {value} ±{u}"),
        }
    }
}

/// `wc 0x44 waited=6.000us`, or `wc! 0x44` for an op that did not wait.
fn write_op(
    f: &mut fmt::Formatter<'_>,
    op: &str,
    byte: u8,
    waited: Option<Duration>,
) -> fmt::Result {
    match waited {
        Some(w) => write!(f, "{op} 0x{byte:02X} waited={w}"),
        None => write!(f, "{op}! 0x{byte:02X}"),
    }
}

impl fmt::Display for BusEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            BusEvent::WriteCommand { byte, waited } => write_op(f, "wc", byte, waited),
            BusEvent::WriteData { byte, waited } => write_op(f, "wd", byte, waited),
            BusEvent::WriteTimedOut { command, byte } => {
                write!(
                    f,
                    "{}-timeout 0x{byte:02X}",
                    if command { "wc" } else { "wd" }
                )
            }
            BusEvent::ReadStatus(b) => write!(f, "rs 0x{b:02X}"),
            BusEvent::ReadData { byte, waited } => write_op(f, "rd", byte, waited),
            BusEvent::ReadTimedOut => f.write_str("rd-timeout"),
            BusEvent::Await {
                flag,
                value,
                waited,
                status,
            } => {
                write!(f, "await {}={} ", flag.name(), u8::from(value))?;
                match waited {
                    Some(d) => write!(f, "after {d}")?,
                    None => f.write_str("timeout")?,
                }
                write!(f, " status=0x{status:02X}")
            }
            BusEvent::SetInput { input, asserted } => {
                write!(
                    f,
                    "set {} {}",
                    input.name(),
                    if asserted { "on" } else { "off" }
                )
            }
            BusEvent::AwaitPulses { count, reached } => write!(
                f,
                "await-pulses {count} {}",
                if reached { "reached" } else { "timeout" }
            ),
            BusEvent::Reset => f.write_str("reset"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bus::Uncertainty;

    const SAMPLE: &str = "ppmc-trace 1
scenario demo
section 3-3-5
target emu
detail sysclk_hz 16000000
detail csel low
detail vsel high
detail ext_clock_hz 250000
detail bridge_firmware ppmc-bridge-sim 0.1.0
events
0.000us reset
200000.000us wc 0x44 waited=0.000us
200006.000us wd! 0x32
200007.000us rd 0x83 waited=20.000us
200008.000us rd! 0x00
200012.000us await busy=1 after 54.000us status=0x04
200012.000us move constant cw steps=100 pout=0 winding=4ph-2 phase=0
200060.000us pin busy 1
200068.000us pin s 0b11000
200070.000us pin auxo 0b0101
200206.000us pulses cw n=100 dt=102.000us
200300.000us set l1 on
200300.000us await-pulses 5 reached
200400.000us rd-timeout
200500.000us wc-timeout 0x81
200600.000us move accel-decel ccw steps=16777216 pout=1 winding=none phase=3
200700.000us measure busy_rise 60.000us
end
";

    /// A run with a jitter bound (a bridge timer not locked to the chip)
    /// reads back as written; an exact one keeps its `dt=` form.
    #[test]
    fn pulse_runs_with_a_jitter_bound_round_trip() {
        let line = "1218.000us pulses ccw n=16777216 span=637533448.001us jitter=0.018us";
        let e = parse_event(line).expect("parses");
        let run = e.pulse_run().expect("a run");
        assert_eq!(run.count, 16_777_216);
        assert_eq!(run.span, Duration::from_nanos(637_533_448_001));
        assert_eq!(run.jitter, Duration::from_nanos(18));
        assert_eq!(format!("{} {}", e.at, e.kind), line);
        // Equally spaced pulses are written with `dt=` whichever way they
        // were read.
        let exact =
            parse_event("5.000us pulses cw n=3 span=4.000us jitter=0.000us").expect("parses");
        assert_eq!(exact.kind.to_string(), "pulses cw n=3 dt=2.000us");
        for bad in [
            "5.000us pulses cw n=3 span=4.000us",
            "5.000us pulses cw n=1 span=4.000us jitter=0.000us",
            "5.000us pulses cw n=3 width=4.000us jitter=0.000us",
        ] {
            assert!(parse_event(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn sample_round_trips_exactly() {
        let t = Trace::parse(SAMPLE).expect("parses");
        assert_eq!(t.render(), SAMPLE);
        assert_eq!(t.events.len(), 17);
    }

    #[test]
    fn insta_front_matter_is_skipped() {
        let with = format!("---\nsource: harness/tests/golden.rs\n---\n{SAMPLE}");
        assert_eq!(Trace::parse(&with), Trace::parse(SAMPLE));
    }

    #[test]
    fn errors_name_the_line() {
        let bad = SAMPLE.replace("pulses cw n=100", "pulses cw n=x");
        let e = Trace::parse(&bad).expect_err("bad count");
        assert_eq!(e.line, 21);
        assert!(e.message.contains("bad pulse count"), "{e}");

        let truncated = &SAMPLE[..SAMPLE.len() - 4];
        let e = Trace::parse(truncated).expect_err("no end");
        assert!(e.message.contains("truncated"), "{e}");

        let other = SAMPLE.replace("ppmc-trace 1", "ppmc-trace 7");
        let e = Trace::parse(&other).expect_err("version");
        assert_eq!(e.line, 1);
        assert!(e.message.contains("version 7"), "{e}");

        // A strap that does not read is an error at its line, never a
        // default: a typo would otherwise judge the trace at other straps.
        let typo = SAMPLE.replace("detail csel low", "detail csel lwo");
        let e = Trace::parse(&typo).expect_err("bad strap");
        assert_eq!(e.line, 6);
        assert!(e.message.contains("strap `csel` cannot be `lwo`"), "{e}");
        let missing = SAMPLE.replace("detail vsel high\n", "");
        let e = Trace::parse(&missing).expect_err("missing strap");
        assert!(e.message.contains("strap `vsel` is missing"), "{e}");

        let e = Trace::parse("hello\n").expect_err("not a trace");
        assert!(e.message.contains("not a ppmc trace"), "{e}");

        // An instrument's uncertainty reads back as written, and a
        // measurement's `±`; a detail that does not read is an error at
        // its line, never an exact trace.
        let u = Uncertainty {
            edge: Duration::from_nanos(14),
            sampled: Duration::from_nanos(5000),
            access: Duration::from_nanos(134),
            polled: Duration::from_nanos(1000),
        };
        let line = format!("detail {UNCERTAINTY} {}\nevents\n", uncertainty_detail(&u));
        let unsure = SAMPLE.replacen("events\n", &line, 1);
        let t = Trace::parse(&unsure).expect("parses");
        assert_eq!(t.uncertainty(), u);
        assert_eq!(Trace::parse(&t.render()).expect("round trip"), t);
        assert_eq!(
            Trace::parse(SAMPLE).expect("parses").uncertainty(),
            Uncertainty::ZERO
        );
        let bad = unsure.replace("polled=1000ns", "polled=1us");
        let e = Trace::parse(&bad).expect_err("bad uncertainty");
        assert!(
            e.message.contains("bad `uncertainty` detail `polled=1us`"),
            "{e}"
        );
        let short = unsure.replace(" polled=1000ns", "");
        let e = Trace::parse(&short).expect_err("a path missing");
        assert!(e.message.contains("lacks a path"), "{e}");
        let m = parse_event("5.000us measure busy_rise 25.650us ±0.134us").expect("reads");
        assert_eq!(m.kind.to_string(), "measure busy_rise 25.650us ±0.134us");
        assert!(parse_event("5.000us measure busy_rise 25.650us 0.134us").is_err());

        // A stray CR inside a line (not a CRLF ending) is refused: it would
        // not survive a render. CRLF files parse as LF ones.
        let cr = SAMPLE.replace("target emu", "target emu\r\r");
        let e = Trace::parse(&cr).expect_err("control character");
        assert!(e.message.contains("U+000D"), "{e}");
        let crlf = SAMPLE.replace('\n', "\r\n");
        assert_eq!(Trace::parse(&crlf), Trace::parse(SAMPLE));

        let junk = format!("{SAMPLE}more\n");
        assert!(Trace::parse(&junk)
            .expect_err("after end")
            .message
            .contains("after `end`"));
    }

    proptest::proptest! {
        /// Any text either parses or gives an error; it never panics.
        #[test]
        fn arbitrary_text_never_panics(s in "\\PC*") {
            let _ = Trace::parse(&s);
        }

        /// Mutating one line of a valid trace never panics, and whatever
        /// parses renders back to a trace that parses to the same value.
        #[test]
        fn mutated_traces_round_trip_or_fail_cleanly(line in 0usize..20, junk in "[ -~]{0,30}") {
            let mut lines: Vec<&str> = SAMPLE.lines().collect();
            let i = line % lines.len();
            lines[i] = &junk;
            let text = lines.join("\n");
            if let Ok(t) = Trace::parse(&text) {
                proptest::prop_assert_eq!(Trace::parse(&t.render()), Ok(t));
            }
        }
    }
}

//! Comparing a trace with a golden trace, quantity by quantity.
//!
//! Events are aligned by their place in their own stream, never by absolute
//! time: the n-th bus transaction with the n-th, the n-th pulse with the
//! n-th, the n-th change of each pin with the n-th, the n-th measurement of
//! a name with the n-th. A move's pulses are timed from the anchor, the
//! write that started it (the `move` event), so a board whose clock runs a
//! little differently still lines up. A change the chip makes (an output
//! pin, a flag a wait saw) is timed from what made the chip make it, its
//! last input or its last pulse (`causes.rs`), never from a wait's start
//! or the reset: a bridge whose ops take longer than the golden's would
//! otherwise diverge for its own pace, not the chip's.
//!
//! Each quantity has its own rule:
//! - exactly: bus values (status bytes, read data, written bytes), error
//!   codes, await outcomes, move kind / direction / steps / winding / start
//!   phase (which fix the phase sequence), pulse count and direction, pin
//!   values;
//! - within a relative tolerance of the golden value: latencies (await
//!   times, a move's first pulse, pin changes relative to the anchor) and
//!   pulse intervals;
//! - within Table 3-3 (with its 1 % note): measurements that name a row.
//!
//! The report is the first divergence in time, with the quantity, golden
//! and got, and the allowed band. Each timing is as unsure as the
//! instruments that took the two traces say, and judged by the decision
//! rule (`rule.rs`): a timing within that uncertainty of its limit is no
//! divergence but MARGINAL ([`Graded`]).

mod causes;
mod rule;

pub use rule::{Graded, MarginalComparison};

use crate::protocol::{Pin, PulseRun, Straps, TimingId};
use crate::time::{Duration, Instant};
use crate::trace::{BusEvent, EventKind, Trace};
use causes::{
    busy_seen_by_reads, first_look, judge_change, wait_diverges, Anchor, Causes, PinSlack, Timing,
    Wait,
};
use rule::{First, Unsure};
use std::collections::BTreeMap;
use std::fmt;

/// How far a timing may move before it counts as a divergence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tolerances {
    /// Relative tolerance on latencies, in basis points (100 = 1 %).
    pub latency_bp: u64,
    /// Relative tolerance on pulse intervals, in basis points.
    pub interval_bp: u64,
    /// Absolute slack added to every timing band (timer resolution).
    pub floor: Duration,
}

impl Default for Tolerances {
    /// The datasheet's 1 % (Table 3-3 note) on latencies and intervals, and
    /// 100 ns of timer resolution.
    fn default() -> Self {
        Tolerances {
            latency_bp: 100,
            interval_bp: 100,
            floor: Duration::from_nanos(100),
        }
    }
}

impl Tolerances {
    fn band(&self, golden: Duration, bp: u64) -> (Duration, Duration) {
        self.band_widened(golden, bp, Duration::ZERO)
    }

    /// The band, widened by what the capture itself cannot tell apart (the
    /// jitter bounds of the pulse runs on either side).
    fn band_widened(&self, golden: Duration, bp: u64, capture: Duration) -> (Duration, Duration) {
        let slack = golden.scale(bp, 10_000) + self.floor + capture;
        (golden.saturating_sub(slack), golden + slack)
    }
}

/// The first place where a trace departs from its golden trace.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Divergence {
    /// When, on the compared trace's clock (the golden's where the compared
    /// trace has no such event).
    pub at: Instant,
    /// What differs: `pulse 42 interval`, `bus 7`, `pin busy change 2`, ...
    pub quantity: String,
    pub golden: String,
    pub got: String,
    /// What would have been accepted.
    pub allowed: String,
}

impl fmt::Display for Divergence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "at {}: {}: golden {}, got {} (allowed {})",
            self.at, self.quantity, self.golden, self.got, self.allowed
        )
    }
}

/// A run of pulses, with the anchor its move is timed from.
#[derive(Debug, Clone, Copy)]
struct Run {
    run: PulseRun,
    /// Time of the move's start.
    anchor: Instant,
    /// Whether the run's first pulse is the first of its move.
    first_of_move: bool,
}

impl Run {
    fn at(&self, i: u32) -> Instant {
        self.run.at(i)
    }

    /// How far the time of any one pulse may be from [`Run::at`].
    fn jitter(&self) -> Duration {
        self.run.jitter
    }

    /// How far any one interval of the run may be from the run's mean
    /// interval: twice the jitter, plus the nanosecond the mean is rounded
    /// by; nothing for an exact run.
    fn spread(&self) -> Duration {
        if self.run.is_exact() {
            Duration::ZERO
        } else {
            self.run.jitter.saturating_mul(2) + Duration::from_nanos(1)
        }
    }
}

/// The streams of a trace, each in order.
#[derive(Debug, Default)]
struct Streams {
    /// Each transaction: its time, itself, what a wait in it may be timed
    /// from ([`Anchor::causes`]).
    bus: Vec<(Instant, BusEvent, Causes)>,
    moves: Vec<(Instant, EventKind)>,
    pulses: Vec<Run>,
    /// Each change: its time, its value, what it may be timed from.
    pins: BTreeMap<Pin, Vec<(Instant, u8, Causes)>>,
    measures: BTreeMap<String, Vec<(Instant, Duration, Duration)>>,
    /// The anchor in force at the end.
    anchor: Anchor,
    /// The shortest wait for a flag in the trace: what a wait that found
    /// its flag on its first look costs this target (zero on the
    /// emulator, 2.4 us on the RP2350 image).
    first_look: Duration,
}

/// What of the traces a compare looks at: all of them, or, when one of
/// them is a logic-analyzer capture's (`ppmc judge --trace`, its
/// `capture_pins` detail), what a capture can say of the chip: the
/// register writes and data reads (not the host's status polling, which
/// is the host's and which a capture draws otherwise), the moves, the
/// pulses, and the pins the capture holds; not the driver's measurements.
#[derive(Debug, Clone, Default)]
struct View {
    /// The pins the capture holds, when one side is a capture's.
    capture: Option<Vec<Pin>>,
}

impl View {
    fn of(golden: &Trace, got: &Trace) -> View {
        let pins = [got, golden].into_iter().find_map(|t| {
            t.details
                .iter()
                .find(|(k, _)| k == crate::trace::CAPTURE_PINS)
                .map(|(_, v)| {
                    Pin::ALL
                        .into_iter()
                        .filter(|p| v.split(',').any(|n| n == p.name()))
                        .collect()
                })
        });
        View { capture: pins }
    }

    /// The bus event as this view compares it, if it does.
    fn bus(&self, b: BusEvent) -> Option<BusEvent> {
        if self.capture.is_none() {
            return Some(b);
        }
        match b {
            BusEvent::WriteCommand { byte, .. } => {
                Some(BusEvent::WriteCommand { byte, waited: None })
            }
            BusEvent::WriteData { byte, .. } => Some(BusEvent::WriteData { byte, waited: None }),
            BusEvent::ReadData { byte, .. } => Some(BusEvent::ReadData { byte, waited: None }),
            _ => None,
        }
    }

    fn pin(&self, pin: Pin) -> bool {
        self.capture.as_ref().is_none_or(|pins| pins.contains(&pin))
    }
}

fn streams(t: &Trace, anchor: Anchor, view: &View) -> Streams {
    let mut s = Streams::default();
    let mut anchor = anchor;
    let mut pending_first = false;
    for e in &t.events {
        match &e.kind {
            EventKind::Bus(b) => {
                let causes = anchor.causes(e.at);
                let waited = |w: &Option<Duration>| w.is_some_and(|w| w > Duration::ZERO);
                let input = match b {
                    BusEvent::Reset => {
                        // Inputs are counted on: a capture's view keeps
                        // no reset.
                        anchor = Anchor {
                            at: e.at,
                            inputs: anchor.inputs,
                            ..Anchor::default()
                        };
                        Some(("the chip's reset", false))
                    }
                    BusEvent::WriteCommand { waited: w, .. }
                    | BusEvent::WriteData { waited: w, .. } => {
                        Some(("the write before it", waited(w)))
                    }
                    BusEvent::ReadData { .. } => Some(("the data read before it", false)),
                    BusEvent::SetInput { .. } => Some(("the input's change before it", false)),
                    _ => None,
                };
                if let Some((name, strobe)) = input {
                    anchor.input(e.at, name, strobe, view.bus(*b).is_some());
                }
                let looked = match b {
                    BusEvent::WriteCommand { waited, .. }
                    | BusEvent::WriteData { waited, .. }
                    | BusEvent::ReadData { waited, .. } => waited.is_some(),
                    BusEvent::ReadStatus(_)
                    | BusEvent::Await { .. }
                    | BusEvent::WriteTimedOut { .. }
                    | BusEvent::ReadTimedOut
                    | BusEvent::Reset => true,
                    _ => false,
                };
                if looked {
                    anchor.looked = e.at;
                }
                if let Some(b) = view.bus(*b) {
                    s.bus.push((e.at, b, causes));
                }
            }
            k @ EventKind::Move { .. } => {
                anchor.at = e.at;
                pending_first = true;
                s.moves.push((e.at, k.clone()));
            }
            EventKind::Pulses { .. } => {
                if let Some(run) = e.pulse_run() {
                    anchor.run = Some(run);
                    s.pulses.push(Run {
                        run,
                        anchor: anchor.at,
                        first_of_move: pending_first,
                    });
                }
                pending_first = false;
            }
            EventKind::Pin { pin, value } if view.pin(*pin) => {
                s.pins
                    .entry(*pin)
                    .or_default()
                    .push((e.at, *value, anchor.causes(e.at)));
            }
            EventKind::Pin { .. } => {}
            EventKind::Measure { .. } if view.capture.is_some() => {}
            EventKind::Measure { name, value, u } => {
                s.measures
                    .entry(name.clone())
                    .or_default()
                    .push((e.at, *value, *u));
            }
        }
    }
    s.anchor = anchor;
    s.first_look = first_look(s.bus.iter().map(|(_, b, _)| b));
    s
}

/// Compares `got` with `golden`; `Ok(())` when every quantity is within
/// its rule, else the first divergence in time.
pub fn compare(golden: &Trace, got: &Trace, tol: &Tolerances) -> Result<(), Divergence> {
    compare_graded(golden, got, tol).map(|_| ())
}

/// [`compare`], and where it finds no divergence, the comparisons that
/// were MARGINAL (within the traces' uncertainty of a limit).
pub fn compare_graded(golden: &Trace, got: &Trace, tol: &Tolerances) -> Result<Graded, Divergence> {
    graded_from(golden, got, tol, &Resume::default()).map(|(_, g)| g)
}

/// What two traces compared equal up to a point where both were at rest
/// (no move in progress): how many of each stream's events, and the anchor
/// in force on each side. A compare of what came after, from there
/// ([`compare_from`]), judges and names every event as the compare of the
/// whole would, at a cost in what came after alone.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Resume {
    bus: usize,
    moves: usize,
    pulses: u64,
    pins: BTreeMap<Pin, usize>,
    measures: BTreeMap<String, usize>,
    /// The anchor in force (golden, got).
    anchors: (Anchor, Anchor),
}

impl Resume {
    /// Where a compare picks up after the streams `g` and `o`, compared
    /// equal from `self`.
    fn after(&self, g: &Streams, o: &Streams) -> Resume {
        let mut next = self.clone();
        next.bus += o.bus.len();
        next.moves += o.moves.len();
        next.pulses += o.pulses.iter().map(|r| u64::from(r.run.count)).sum::<u64>();
        for (pin, changes) in &o.pins {
            *next.pins.entry(*pin).or_default() += changes.len();
        }
        for (name, values) in &o.measures {
            *next.measures.entry(name.clone()).or_default() += values.len();
        }
        next.anchors = (g.anchor, o.anchor);
        next
    }
}

/// [`compare`] of traces that continue where `from` left off: event
/// numbers count from there, and times are taken from the anchors then in
/// force. When they agree, where a compare of what follows them picks up
/// (meaningful when both end at rest).
pub fn compare_from(
    golden: &Trace,
    got: &Trace,
    tol: &Tolerances,
    from: &Resume,
) -> Result<Resume, Divergence> {
    graded_from(golden, got, tol, from).map(|(r, _)| r)
}

fn graded_from(
    golden: &Trace,
    got: &Trace,
    tol: &Tolerances,
    from: &Resume,
) -> Result<(Resume, Graded), Divergence> {
    let view = View::of(golden, got);
    let g = streams(golden, from.anchors.0, &view);
    let o = streams(got, from.anchors.1, &view);
    let u = Unsure::of(golden, got);
    let mut first = First::default();
    compare_bus(&g, &o, tol, &u, from.bus, &mut first);
    compare_moves(&g, &o, from.moves, &mut first);
    compare_pulses(&g, &o, tol, &u, from.pulses, &mut first);
    compare_pins(&g, &o, tol, &u, &from.pins, &mut first);
    compare_measures(&g, &o, tol, &got.straps, &from.measures, &mut first);
    match first.0 {
        Some(d) => Err(d),
        None => Ok((from.after(&g, &o), first.1)),
    }
}

/// Whether the two streams hold as many events, counting `before` on
/// each side already compared.
fn count_divergence<T>(
    what: &str,
    g: &[T],
    o: &[T],
    before: usize,
    at: impl Fn(&T) -> Instant,
) -> Option<Divergence> {
    if g.len() == o.len() {
        return None;
    }
    let n = g.len().min(o.len());
    let when = o.get(n).or(g.get(n)).map(at).unwrap_or_default();
    Some(Divergence {
        at: when,
        quantity: format!("number of {what}"),
        golden: (before + g.len()).to_string(),
        got: (before + o.len()).to_string(),
        allowed: "equal".into(),
    })
}

fn compare_bus(
    g: &Streams,
    o: &Streams,
    tol: &Tolerances,
    u: &Unsure,
    before: usize,
    first: &mut First,
) {
    let polled = u.polled();
    for (i, (&(gt, ref ge, g_causes), &(ot, ref oe, o_causes))) in
        g.bus.iter().zip(&o.bus).enumerate()
    {
        if first.beaten_by(ot) {
            return;
        }
        let quantity = format!("bus transaction {} ({ge})", before + i + 1);
        let waits = |gw: Duration, ow: Duration, strobe: bool| {
            (
                Wait::of(gt, g_causes, gw, (g.first_look, polled.0), strobe),
                Wait::of(ot, o_causes, ow, (o.first_look, polled.1), strobe),
            )
        };
        let mismatch = match (ge, oe) {
            (
                BusEvent::Await {
                    flag: gf,
                    value: gv,
                    waited: gw,
                    status: gs,
                },
                BusEvent::Await {
                    flag: of,
                    value: ov,
                    waited: ow,
                    status: os,
                },
            ) if gf == of && gv == ov => match (gw, ow) {
                (Some(gw), Some(ow)) => {
                    let what = format!("{quantity}: {} seen", gf.name());
                    if wait_diverges(first, &what, waits(*gw, *ow, false), tol, u.wait()) {
                        return;
                    } else if gs != os {
                        Some((
                            format!("{quantity}: status"),
                            format!("0x{gs:02X}"),
                            format!("0x{os:02X}"),
                            "equal".into(),
                        ))
                    } else {
                        None
                    }
                }
                (None, None) if gs == os => None,
                _ => Some((
                    quantity.clone(),
                    ge.to_string(),
                    oe.to_string(),
                    "equal".into(),
                )),
            },
            (
                BusEvent::WriteCommand {
                    byte: gb,
                    waited: Some(gw),
                },
                BusEvent::WriteCommand {
                    byte: ob,
                    waited: Some(ow),
                },
            )
            | (
                BusEvent::WriteData {
                    byte: gb,
                    waited: Some(gw),
                },
                BusEvent::WriteData {
                    byte: ob,
                    waited: Some(ow),
                },
            )
            | (
                BusEvent::ReadData {
                    byte: gb,
                    waited: Some(gw),
                },
                BusEvent::ReadData {
                    byte: ob,
                    waited: Some(ow),
                },
            ) => {
                if gb != ob {
                    Some((
                        format!("{quantity}: value"),
                        format!("0x{gb:02X}"),
                        format!("0x{ob:02X}"),
                        "equal".into(),
                    ))
                } else {
                    let what = format!("{quantity}: IBF/OBF seen");
                    if wait_diverges(first, &what, waits(*gw, *ow, true), tol, u.wait()) {
                        return;
                    }
                    None
                }
            }
            _ if ge == oe => None,
            _ => Some((
                quantity.clone(),
                ge.to_string(),
                oe.to_string(),
                "equal".into(),
            )),
        };
        if let Some((quantity, golden, got, allowed)) = mismatch {
            first.offer(Divergence {
                at: ot,
                quantity,
                golden,
                got,
                allowed,
            });
            return;
        }
    }
    if let Some(d) = count_divergence("bus transactions", &g.bus, &o.bus, before, |e| e.0) {
        first.offer(d);
    }
}

fn compare_moves(g: &Streams, o: &Streams, before: usize, first: &mut First) {
    for (i, ((_, gm), (ot, om))) in g.moves.iter().zip(&o.moves).enumerate() {
        if gm != om {
            first.offer(Divergence {
                at: *ot,
                quantity: format!("move {}", before + i + 1),
                golden: gm.to_string(),
                got: om.to_string(),
                allowed: "equal".into(),
            });
            return;
        }
    }
    if let Some(d) = count_divergence("moves", &g.moves, &o.moves, before, |e| e.0) {
        first.offer(d);
    }
}

/// A position in a pulse stream: run index and pulse within the run.
#[derive(Debug, Clone, Copy, Default)]
struct Cursor {
    run: usize,
    pos: u32,
}

/// Compares the pulse streams run by run: a stretch where both traces keep
/// one period costs one check, so a 16-million-pulse move compares in
/// O(runs).
fn compare_pulses(
    g: &Streams,
    o: &Streams,
    tol: &Tolerances,
    u: &Unsure,
    before: u64,
    first: &mut First,
) {
    let total = |runs: &[Run]| before + runs.iter().map(|r| u64::from(r.run.count)).sum::<u64>();
    let (mut gc, mut oc) = (Cursor::default(), Cursor::default());
    let mut n: u64 = before; // pulses compared so far
                             // The previous (golden, got) pulse and how far each may be off.
    let mut prev: Option<(Instant, Instant, Duration)> = None;
    while gc.run < g.pulses.len() && oc.run < o.pulses.len() {
        let (gr, or) = (g.pulses[gc.run], o.pulses[oc.run]);
        let (gt, ot) = (gr.at(gc.pos), or.at(oc.pos));
        if first.beaten_by(ot) {
            return;
        }
        let k = n + 1;
        let diverge = |quantity: String, golden: String, got: String, allowed: String| Divergence {
            at: ot,
            quantity,
            golden,
            got,
            allowed,
        };
        // The pulse at the cursors, on its own.
        if gr.run.dir != or.run.dir {
            first.offer(diverge(
                format!("pulse {k} direction"),
                gr.run.dir.name().into(),
                or.run.dir.name().into(),
                "equal".into(),
            ));
            return;
        }
        let (g_first, o_first) = (
            gr.first_of_move && gc.pos == 0,
            or.first_of_move && oc.pos == 0,
        );
        if g_first != o_first {
            let what = |f: bool| {
                if f {
                    "first of a move"
                } else {
                    "inside a move"
                }
                .to_string()
            };
            first.offer(diverge(
                format!("pulse {k}: which move it belongs to"),
                what(g_first),
                what(o_first),
                "equal".into(),
            ));
            return;
        }
        let here = gr.jitter() + or.jitter();
        let (what, gd, od, bp, capture, unsure) = match prev {
            Some((gp, op, off)) if !g_first => (
                "interval",
                gt.saturating_since(gp),
                ot.saturating_since(op),
                tol.interval_bp,
                off + here,
                u.interval(),
            ),
            _ => (
                "delay from the move's start",
                gt.saturating_since(gr.anchor),
                ot.saturating_since(or.anchor),
                tol.latency_bp,
                here,
                u.first_pulse(),
            ),
        };
        let band = tol.band_widened(gd, bp, capture);
        let quantity = || format!("pulse {k} {what}");
        if first.check(ot, quantity, gd, od, band, unsure) {
            return;
        }
        // The rest of the stretch both runs share: one period each.
        let rest = (gr.run.count - gc.pos - 1).min(or.run.count - oc.pos - 1);
        if rest > 0 {
            let (gi, oi) = (gr.run.interval(), or.run.interval());
            let band = tol.band_widened(gi, tol.interval_bp, gr.spread() + or.spread());
            let quantity = || format!("pulse {} interval", k + 1);
            // A run's mean interval, from its two ends over its intervals.
            let intervals = u64::from(gr.run.count.min(or.run.count).max(2) - 1);
            let mean = Duration::from_nanos(u.interval().as_nanos().div_ceil(intervals));
            if first.check(or.at(oc.pos + 1), quantity, gi, oi, band, mean) {
                return;
            }
        }
        gc.pos += rest;
        oc.pos += rest;
        n += u64::from(rest) + 1;
        prev = Some((gr.at(gc.pos), or.at(oc.pos), here));
        for (c, runs) in [(&mut gc, &g.pulses), (&mut oc, &o.pulses)] {
            c.pos += 1;
            if c.pos >= runs[c.run].run.count {
                c.run += 1;
                c.pos = 0;
            }
        }
    }
    let (gn, on) = (total(&g.pulses), total(&o.pulses));
    if gn != on {
        let at = o
            .pulses
            .get(oc.run)
            .map(|r| r.at(oc.pos))
            .or_else(|| g.pulses.get(gc.run).map(|r| r.at(gc.pos)))
            .unwrap_or_default();
        first.offer(Divergence {
            at,
            quantity: "number of pulses".into(),
            golden: gn.to_string(),
            got: on.to_string(),
            allowed: "equal".into(),
        });
    }
}

fn compare_pins(
    g: &Streams,
    o: &Streams,
    tol: &Tolerances,
    u: &Unsure,
    before: &BTreeMap<Pin, usize>,
    first: &mut First,
) {
    let empty = Vec::new();
    let pins: std::collections::BTreeSet<&Pin> = g.pins.keys().chain(o.pins.keys()).collect();
    for pin in pins {
        // Stop switching as a bridge infers it is late by up to two
        // windows and blind to a stretch without a chopping edge: a
        // compare cut at every rest cannot hold it change by change.
        if *pin == Pin::Switching && u.infers_switching() {
            continue;
        }
        let gs = g.pins.get(pin).unwrap_or(&empty);
        let os = o.pins.get(pin).unwrap_or(&empty);
        let seen;
        let gs = match *pin == Pin::Busy && u.got_polls_busy() {
            true => {
                seen = busy_seen_by_reads(gs, &o.bus);
                &seen
            }
            false => gs,
        };
        let done = before.get(pin).copied().unwrap_or(0);
        let mut diverged = false;
        for (i, (&(_, gv, ga), &(ot, ov, oa))) in gs.iter().zip(os).enumerate() {
            if first.beaten_by(ot) {
                break;
            }
            let quantity = format!("pin {} change {}", pin.name(), done + i + 1);
            if gv != ov {
                first.offer(Divergence {
                    at: ot,
                    quantity: format!("{quantity}: value"),
                    golden: gv.to_string(),
                    got: ov.to_string(),
                    allowed: "equal".into(),
                });
                diverged = true;
                break;
            }
            let timings = Causes::timings(gs[i].0, ga, ot, oa);
            let slack = PinSlack::of(*pin, (gs[i].0, &ga), (ot, &oa), u.strobe_lag());
            let u = u.pin(*pin);
            let graded = |t: &Timing| slack.exact(t);
            let out = |t: &Timing, band: (Duration, Duration)| slack.out(t, band, u);
            let what = format!("{quantity}: time");
            if judge_change(first, ot, &what, &timings, tol, u, graded, out) {
                diverged = true;
                break;
            }
        }
        if !diverged {
            if let Some(d) =
                count_divergence(&format!("{} changes", pin.name()), gs, os, done, |e| e.0)
            {
                first.offer(d);
            }
        }
    }
}

fn compare_measures(
    g: &Streams,
    o: &Streams,
    tol: &Tolerances,
    straps: &Straps,
    before: &BTreeMap<String, usize>,
    first: &mut First,
) {
    let empty = Vec::new();
    let names: std::collections::BTreeSet<&String> =
        g.measures.keys().chain(o.measures.keys()).collect();
    for name in names {
        let gs = g.measures.get(name).unwrap_or(&empty);
        let os = o.measures.get(name).unwrap_or(&empty);
        let done = before.get(name).copied().unwrap_or(0);
        for (i, (&(_, gv, gu), &(ot, ov, ou))) in gs.iter().zip(os).enumerate() {
            let quantity = format!("measurement {name} #{}", done + i + 1);
            // Each side's own uncertainty, as it was measured.
            let u = gu + ou;
            if let Some(id) = TimingId::from_name(name) {
                let band = id.row().band_for(straps);
                let row = || format!("{quantity} (Table 3-3)");
                if first.check(ot, row, gv, ov, band, u) {
                    break;
                }
            }
            let band = tol.band(gv, tol.latency_bp);
            if first.check(ot, || quantity, gv, ov, band, u) {
                break;
            }
        }
        if let Some(d) = count_divergence(&format!("{name} measurements"), gs, os, done, |e| e.0) {
            first.offer(d);
        }
    }
}

/// Scales every time in a trace by `num / den` (for tolerance tests and
/// for simulating a board whose clock runs fast or slow).
pub fn scale_times(t: &Trace, num: u64, den: u64) -> Trace {
    let mut out = t.clone();
    for e in &mut out.events {
        e.at = Instant::from_nanos(
            Duration::from_nanos(e.at.as_nanos())
                .scale(num, den)
                .as_nanos(),
        );
        match &mut e.kind {
            EventKind::Pulses { span, jitter, .. } => {
                *span = span.scale(num, den);
                *jitter = jitter.scale(num, den);
            }
            EventKind::Measure { value, .. } => *value = value.scale(num, den),
            EventKind::Bus(
                BusEvent::Await {
                    waited: Some(w), ..
                }
                | BusEvent::WriteCommand {
                    waited: Some(w), ..
                }
                | BusEvent::WriteData {
                    waited: Some(w), ..
                }
                | BusEvent::ReadData {
                    waited: Some(w), ..
                },
            ) => *w = w.scale(num, den),
            _ => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOLDEN: &str = "ppmc-trace 1
scenario demo
section 3-3-5
target emu
detail sysclk_hz 16000000
detail csel high
detail vsel high
detail ext_clock_hz none
events
0.000us reset
1000.000us wc 0x44 waited=0.000us
1024.000us wd 0x00 waited=6.000us
1030.000us move constant cw steps=4 pout=0 winding=4ph-2 phase=0
1084.000us pin busy 1
1084.000us await busy=1 after 60.000us status=0x04
1218.000us pulses cw n=4 dt=102.000us
1550.000us pin busy 0
1600.000us measure constant_first_pout 194.000us
end
";

    fn golden() -> Trace {
        Trace::parse(GOLDEN).expect("golden parses")
    }

    /// An initialization (section 3-2) and its outputs, with the final
    /// data byte written `final_at` us after the reset and the phases set
    /// `phases_after` us after that byte.
    fn init_trace(final_at: u64, phases_after: u64) -> Trace {
        let text = format!(
            "ppmc-trace 1
scenario init
section 3-2
target emu
detail sysclk_hz 16000000
detail csel high
detail vsel high
detail ext_clock_hz none
events
0.000us reset
{}.000us wc 0x02 waited=0.000us
{final_at}.000us wd 0x00 waited=6.000us
{}.000us pin s 0b11000
end
",
            final_at - 6,
            final_at + phases_after,
        );
        Trace::parse(&text).expect("parses")
    }

    /// Section 3-2: the chip sets its outputs a fixed time after the
    /// initialization's final byte. A bridge whose ops take longer than
    /// the golden's writes that byte later after the reset (here 124 us
    /// for 24): timed from the reset, its outputs diverged for the
    /// bridge's pace; timed from the write, they agree. The chip setting
    /// them later after the write is still the divergence, named so.
    #[test]
    fn a_pin_change_before_any_move_is_timed_from_the_write_before_it() {
        let tol = Tolerances::default();
        compare(&init_trace(24, 44), &init_trace(124, 44), &tol)
            .expect("the same 44 us after the final byte");
        let late = compare(&init_trace(24, 44), &init_trace(124, 60), &tol)
            .expect_err("16 us later after the final byte");
        assert_eq!(
            late.quantity,
            "pin s change 1: time, from the write before it"
        );
        assert_eq!(late.golden, "44.000us");
        assert_eq!(late.got, "60.000us");
    }

    /// A trace of scenario `name` (`section`) at the reference straps,
    /// `text` its details after the straps and its events.
    fn trace_of(name: &str, section: &str, text: &str) -> Trace {
        let t = format!(
            "ppmc-trace 1\nscenario {name}\nsection {section}\ntarget t\ndetail sysclk_hz 16000000\ndetail csel high\ndetail vsel high\ndetail ext_clock_hz none\n{text}end\n"
        );
        Trace::parse(&t).expect("parses")
    }

    /// A change the chip makes on its own between two writes (AUX* on,
    /// Table 3-3, for an AUX ON command taken from the input buffer when
    /// an initialization ends, 3-1-1) comes after the second write on the
    /// emulator, which writes as IBF falls, and before it on a bridge,
    /// which writes about 2 us later (a poll's pass and its strobe). Both
    /// are timed from the first write, the bridge's time as a range of
    /// its lag: no departure (a differential run on the board twin found
    /// it). An AUX* late past the band and the lag still departs.
    #[test]
    fn a_change_between_writes_is_timed_from_the_same_write_on_both_sides() {
        let trace = |text: &str| trace_of("aux", "3-5-2", text);
        let golden = trace(
            "events
0.000us reset
1000.000us wc 0x25 waited=6.000us
1006.000us wd 0xCB waited=6.000us
1008.000us pin aux 1
",
        );
        // AUX* on at `aux` us, before the second write or after it.
        let board = |aux: &str| {
            let (before, after) = match aux < "1010.200" {
                true => (format!("{aux}us pin aux 1\n"), String::new()),
                false => (String::new(), format!("{aux}us pin aux 1\n")),
            };
            trace(&format!(
                "detail uncertainty edge=14ns sampled=5000ns access=134ns polled=1500ns
events
0.000us reset
1002.186us wc 0x25 waited=7.800us
{before}1010.200us wd 0xCB waited=6.000us
{after}"
            ))
        };
        let tol = Tolerances::default();
        compare(&golden, &board("1008.000"), &tol)
            .expect("8 us after the chip took AUX ON, on both sides");
        // After the second write on both sides: 2 us on the emulator, and
        // on the bridge 6.5 us, past even its lag of 3.134 us.
        let late = compare(&golden, &board("1016.700"), &tol).expect_err("6.5 us after wd 0xCB");
        assert_eq!(
            late.quantity,
            "pin aux change 1: time, from the write before it"
        );
        assert_eq!(
            (late.golden.as_str(), late.got.as_str()),
            ("2.000us", "6.500us ±0.148us")
        );
        let early = compare(&golden, &board("1003.000"), &tol).expect_err("0.8 us after wc 0x25");
        assert_eq!(early.got, "0.814us ±0.148us");
    }

    /// A bridge finds BUSY's change by reading the status register, and
    /// reads none while it waits out a delay: a change it stamps at the
    /// first read 9 ms after the read before lies anywhere between the
    /// two (docs/bridge-protocol.md section 4), and the 60 us Table 3-3
    /// gives lies in there. No departure; a change stamped early, with a
    /// read just before it, still departs.
    #[test]
    fn a_busy_change_stamped_after_a_long_gap_in_status_reads_is_a_range() {
        let trace = |text: &str| trace_of("busy", "3-3-5", text);
        let golden = |read: &str| {
            trace(&format!(
                "events
0.000us reset
1000.000us wd 0x00 waited=6.000us
1000.500us rs 0x00
{read}1060.000us pin busy 1
"
            ))
        };
        let board = |busy: &str, read: &str| {
            trace(&format!(
                "detail uncertainty edge=14ns sampled=5000ns access=134ns polled=1500ns
events
0.000us reset
1000.000us wd 0x00 waited=6.000us
1000.500us rs 0x00
{read}{busy}us pin busy 1
"
            ))
        };
        let tol = Tolerances::default();
        compare(&golden(""), &board("10120.000", ""), &tol)
            .expect("the change lies between 1000.5 us and 10120 us");
        let read = "1010.000us rs 0x00\n";
        let early = compare(&golden(read), &board("1011.000", read), &tol)
            .expect_err("BUSY 11 us after the write, not 60");
        assert_eq!(
            early.quantity,
            "pin busy change 1: time, from the write before it"
        );
    }

    /// A single step (3-3-3) between two status reads 3.8 ms apart: its
    /// BUSY (60 us after the write to 112 us, Table 3-3) rises and falls
    /// with no read to see it, so a bridge that finds BUSY by reading the
    /// status register records no change. No departure from such a board
    /// (the differential run against the twin found it, seed 4); one from
    /// a board that reads BUSY as exactly as its accesses (bridge-sim),
    /// and one where a read of the board's fell inside the stretch.
    #[test]
    fn a_busy_between_two_status_reads_is_not_held_to_a_bridge_that_polls_it() {
        let trace = |text: &str| trace_of("step", "3-3-3", text);
        let golden = |read: &str| {
            trace(&format!(
                "events
0.000us reset
1000.000us wc 0x4A waited=0.000us
1000.480us rs 0x00
1060.000us pin busy 1
{read}1112.000us pin busy 0
4800.000us rs 0x00
"
            ))
        };
        let board = |u: &str, read: &str| {
            trace(&format!(
                "detail uncertainty {u}
events
0.000us reset
1000.000us wc 0x4A waited=0.000us
1000.480us rs 0x00
{read}4800.000us rs 0x00
"
            ))
        };
        let polls = "edge=14ns sampled=5000ns access=134ns polled=1500ns";
        let tol = Tolerances::default();
        compare(&golden(""), &board(polls, ""), &tol)
            .expect("no read of the board's saw the single step's BUSY");
        let exact = compare(
            &golden(""),
            &board("edge=13ns sampled=13ns access=13ns polled=13ns", ""),
            &tol,
        )
        .expect_err("a bridge that reads BUSY as exactly as its accesses");
        assert_eq!(exact.quantity, "number of busy changes");
        let read = "1080.000us rs 0x04\n";
        let seen = compare(&golden(read), &board(polls, read), &tol)
            .expect_err("a read of the board's fell inside the stretch");
        assert_eq!(seen.quantity, "number of busy changes");
    }

    /// Stop switching (3-5-1) as a bridge infers it from S1..S5 sampled by
    /// its CPU: the model's 62 us of it, between an initialization's end
    /// and a move's BUSY, end before the chopping's first edge (65 us ON,
    /// Diagram 3-5), so the bridge sees none: no departure from a board
    /// whose sampled outputs are less sure than its edges (the twin found
    /// it), a departure from one that reports SWITCHING exactly (as
    /// bridge-sim does, from the model).
    #[test]
    fn stop_switching_is_not_held_change_by_change_to_a_bridge_that_infers_it() {
        let trace = |text: &str| trace_of("chop", "3-5-1", text);
        let golden = trace(
            "events
0.000us reset
1000.000us pin hold 1
1000.000us pin switching 1
1062.000us pin busy 1
1062.000us pin hold 0
1062.000us pin switching 0
",
        );
        let board = |u: &str| {
            trace(&format!(
                "detail uncertainty {u}
events
0.000us reset
1000.000us pin hold 1
1062.000us pin busy 1
1062.000us pin hold 0
"
            ))
        };
        let tol = Tolerances::default();
        compare(
            &golden,
            &board("edge=14ns sampled=5000ns access=134ns polled=1500ns"),
            &tol,
        )
        .expect("a stretch without an edge shows a sampling bridge nothing");
        let exact = compare(
            &golden,
            &board("edge=13ns sampled=13ns access=13ns polled=13ns"),
            &tol,
        )
        .expect_err("a bridge that reports SWITCHING exactly");
        assert_eq!(exact.quantity, "number of switching changes");
    }

    /// The decision rule (docs/conformance.md) in a compare: a board's
    /// trace whose run's mean interval lies 0.08 us outside the band
    /// (102 us, 1 % and the floor: up to 103.12 us) is the divergence when
    /// the trace is exact, MARGINAL when its bridge declares an edge
    /// uncertain by 150 ns (the run's two ends over its three intervals,
    /// 0.1 us), and the divergence again at 100 ns (0.067 us). A
    /// measurement's own `±` counts the same way (Table 3-3).
    #[test]
    fn a_timing_within_the_instruments_uncertainty_of_its_limit_is_marginal() {
        let board = |edge_ns: u64| {
            let mut t = GOLDEN.replace(
                "1218.000us pulses cw n=4 dt=102.000us",
                "1218.000us pulses cw n=4 dt=103.200us",
            );
            if edge_ns > 0 {
                t = t.replace(
                    "events\n",
                    &format!("detail uncertainty edge={edge_ns}ns sampled=0ns access=0ns polled=0ns\nevents\n"),
                );
            }
            Trace::parse(&t).expect("parses")
        };
        let tol = Tolerances::default();
        let exact = compare_graded(&golden(), &board(0), &tol).expect_err("exact: outside");
        assert_eq!(exact.quantity, "pulse 2 interval");
        assert_eq!(exact.got, "103.200us");
        let graded =
            compare_graded(&golden(), &board(150), &tol).expect("marginal, not a divergence");
        assert_eq!(graded.marginal, 1, "{graded:?}");
        let first = graded.first.expect("the first");
        assert_eq!(first.quantity, "pulse 2 interval");
        assert_eq!(first.u, Duration::from_nanos(100));
        let far = compare_graded(&golden(), &board(100), &tol).expect_err("outside by more than U");
        assert_eq!(far.got, "103.200us ±0.067us");
        // Table 3-3's constant first POUT band tops at 195.94 us, the
        // golden's (194 us, 1 % and the floor) at 196.04 us: 196 us
        // measured +-0.1 us straddles both.
        let measured = |line: &str| {
            let t = GOLDEN.replace("1600.000us measure constant_first_pout 194.000us", line);
            compare_graded(&golden(), &Trace::parse(&t).expect("parses"), &tol)
        };
        assert!(measured("1600.000us measure constant_first_pout 196.000us").is_err());
        let m = measured("1600.000us measure constant_first_pout 196.000us ±0.100us")
            .expect("within its uncertainty of the band");
        assert_eq!(m.marginal, 2);
        let first = m.first.expect("the first");
        assert!(first.quantity.ends_with("(Table 3-3)"), "{first}");
        // Exact traces grade nothing marginal: the band alone, as before.
        assert_eq!(
            compare_graded(&golden(), &golden(), &tol),
            Ok(Graded::default())
        );
    }

    #[test]
    fn identical_traces_match() {
        assert_eq!(
            compare(&golden(), &golden(), &Tolerances::default()),
            Ok(())
        );
    }

    /// A run captured by a bridge whose timer is not locked to the chip
    /// carries a jitter bound (bridge protocol section 7): its mean
    /// interval may be off the golden one by the tolerance plus what the
    /// bound leaves open (twice the jitter and a nanosecond), never more.
    #[test]
    fn a_run_with_jitter_is_judged_with_its_bound() {
        let with = |line: &str| {
            let t = GOLDEN.replace("1218.000us pulses cw n=4 dt=102.000us", line);
            compare(
                &golden(),
                &Trace::parse(&t).expect("parses"),
                &Tolerances::default(),
            )
        };
        // The band is 102 us +- (1 % + 0.1 us): up to 103.12 us. A mean of
        // 103.2 us is outside it, but within 0.401 us more.
        assert_eq!(
            with("1218.000us pulses cw n=4 span=309.600us jitter=0.200us"),
            Ok(())
        );
        let exact = with("1218.000us pulses cw n=4 dt=103.200us").expect_err("exact: outside");
        assert_eq!(exact.quantity, "pulse 2 interval");
        let far = with("1218.000us pulses cw n=4 span=310.800us jitter=0.200us")
            .expect_err("103.6 us is outside even with the bound");
        assert_eq!(far.quantity, "pulse 2 interval");
        assert_eq!(far.allowed, "100.479us..=103.521us");
        // The same pulses, exact in the golden and within their bound in
        // the other, whichever way round.
        let golden_jittered = GOLDEN.replace(
            "1218.000us pulses cw n=4 dt=102.000us",
            "1218.000us pulses cw n=4 span=306.003us jitter=0.002us",
        );
        let g = Trace::parse(&golden_jittered).expect("parses");
        assert_eq!(compare(&g, &golden(), &Tolerances::default()), Ok(()));
    }

    #[test]
    fn jitter_inside_the_tolerance_passes() {
        let jittered = GOLDEN
            .replace(
                "1218.000us pulses cw n=4 dt=102.000us",
                "1218.500us pulses cw n=4 dt=102.800us",
            )
            .replace("after 60.000us", "after 60.500us");
        let t = Trace::parse(&jittered).expect("parses");
        assert_eq!(compare(&golden(), &t, &Tolerances::default()), Ok(()));
        assert_eq!(
            compare(
                &golden(),
                &scale_times(&golden(), 1005, 1000),
                &Tolerances::default()
            ),
            Ok(())
        );
    }

    /// Section 3-3: BUSY rises 60 us after the move's final byte. A bridge
    /// whose ops take longer starts its wait for it later and waits 21 us,
    /// not 60: the same chip, no divergence (the wait's length diverged
    /// before). A bridge that found BUSY already up when it looked, 66 us
    /// after the byte, only bounds it: no divergence either. One that
    /// found it up 26 us after the byte saw it too early.
    #[test]
    fn a_wait_is_compared_by_the_chips_change_not_by_how_long_it_waited() {
        let trace = |at: &str, waited: &str| {
            let text = GOLDEN.replace("1084.000us pin busy 1\n", "").replace(
                "1084.000us await busy=1 after 60.000us",
                &format!("{at} await busy=1 after {waited}"),
            );
            Trace::parse(&text).expect("parses")
        };
        let golden = trace("1084.000us", "60.000us");
        let tol = Tolerances::default();
        compare(&golden, &trace("1084.000us", "21.000us"), &tol)
            .expect("a later start, the same change");
        compare(&golden, &trace("1090.000us", "0.000us"), &tol)
            .expect("found already up: the change came at or before");
        let early = compare(&golden, &trace("1050.000us", "0.000us"), &tol)
            .expect_err("found up 26 us after the byte");
        assert_eq!(
            early.quantity,
            "bus transaction 4 (await busy=1 after 60.000us status=0x04): busy seen, from the write before it"
        );
        assert_eq!(early.golden, "60.000us");
        assert_eq!(early.got, "26.000us");
        assert_eq!(early.allowed, "59.300us..=60.700us");
    }

    #[test]
    fn a_three_percent_slower_clock_is_caught_at_the_first_wait() {
        let slow = scale_times(&golden(), 103, 100);
        let d = compare(&golden(), &slow, &Tolerances::default()).expect_err("3 % off");
        // The data byte's IBF = 0 came 24 us after the command byte.
        assert_eq!(
            d.quantity,
            "bus transaction 3 (wd 0x00 waited=6.000us): IBF/OBF seen, from the write before it"
        );
        assert_eq!(d.golden, "24.000us");
        assert_eq!(d.got, "24.720us");
        assert_eq!(d.allowed, "23.660us..=24.340us");
    }

    proptest::proptest! {
        /// Timing jitter inside the tolerances never fails a comparison:
        /// every pulse, pin change and wait moved by up to 0.15 us
        /// (intervals then change by at most 0.3 us, inside 1 % of 102 us
        /// + 0.1 us; a wait's end from the write before it by as much,
        /// inside 1 % of 24 us + 0.1 us).
        #[test]
        fn jitter_inside_the_tolerances_never_fails(jitter in proptest::collection::vec(-150i64..=150, 16)) {
            let g = golden();
            let mut t = g.clone();
            // One event per pulse, so that each can move on its own.
            let mut events = Vec::new();
            for e in &t.events {
                match &e.kind {
                    EventKind::Pulses { dir, count, .. } => {
                        let run = e.pulse_run().expect("a pulses event");
                        for i in 0..*count {
                            events.push(crate::trace::Event {
                                at: run.at(i),
                                kind: EventKind::Pulses { dir: *dir, count: 1, span: Duration::ZERO, jitter: Duration::ZERO },
                            });
                        }
                    }
                    _ => events.push(e.clone()),
                }
            }
            for (i, e) in events.iter_mut().enumerate() {
                let j = jitter[i % jitter.len()];
                if !matches!(e.kind, EventKind::Move { .. } | EventKind::Bus(BusEvent::Reset)) {
                    e.at = Instant::from_nanos((e.at.as_nanos() as i64 + j) as u64);
                }
                if let EventKind::Bus(BusEvent::Await { waited: Some(w), .. }) = &mut e.kind {
                    *w = Duration::from_nanos((w.as_nanos() as i64 + j / 4) as u64);
                }
            }
            t.events = events;
            proptest::prop_assert_eq!(compare(&g, &t, &Tolerances::default()), Ok(()));
        }
    }

    #[test]
    fn an_interval_off_inside_a_run_is_found_in_one_step() {
        let t =
            Trace::parse(&GOLDEN.replace("n=4 dt=102.000us", "n=4 dt=104.000us")).expect("parses");
        let d = compare(&golden(), &t, &Tolerances::default()).expect_err("2 % off");
        assert_eq!(d.quantity, "pulse 2 interval");
        assert_eq!(
            (d.golden.as_str(), d.got.as_str()),
            ("102.000us", "104.000us")
        );
    }

    #[test]
    fn a_lost_pulse_is_a_count_divergence() {
        let t = Trace::parse(&GOLDEN.replace("n=4", "n=3")).expect("parses");
        let d = compare(&golden(), &t, &Tolerances::default()).expect_err("pulse lost");
        assert_eq!(d.quantity, "number of pulses");
        assert_eq!((d.golden.as_str(), d.got.as_str()), ("4", "3"));
    }

    #[test]
    fn a_different_status_value_is_exact() {
        let t = Trace::parse(&GOLDEN.replace("status=0x04", "status=0x84")).expect("parses");
        let d = compare(&golden(), &t, &Tolerances::default()).expect_err("status");
        assert!(d.quantity.ends_with(": status"), "{d}");
    }

    #[test]
    fn a_measurement_outside_table_3_3_fails_even_if_golden_agrees() {
        let odd = GOLDEN.replace(
            "measure constant_first_pout 194.000us",
            "measure constant_first_pout 200.000us",
        );
        let g = Trace::parse(&odd).expect("parses");
        let d = compare(&g, &g, &Tolerances::default()).expect_err("out of band");
        assert!(d.quantity.contains("Table 3-3"), "{d}");
    }

    #[test]
    fn the_earliest_divergence_wins() {
        let t = Trace::parse(
            &GOLDEN
                .replace("1550.000us pin busy 0", "1550.000us pin busy 1")
                .replace(
                    "1218.000us pulses cw n=4 dt=102.000us",
                    "1218.000us pulses ccw n=4 dt=102.000us",
                ),
        )
        .expect("parses");
        let d = compare(&golden(), &t, &Tolerances::default()).expect_err("two differences");
        assert_eq!(d.quantity, "pulse 1 direction");
    }
}

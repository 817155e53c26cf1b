//! A board's divergence held against the channel map (issue 40): a
//! capture whose probes were put on the wrong pins, or whose map names
//! them wrongly, diverges from the model at once, and the board is not to
//! blame. Where the board diverges, the capture is judged again with the
//! maps a probing mistake would have needed (two bus lines exchanged, a
//! strobe, POUT or DIR inverted), each only up to its own first
//! divergence. Where one of them judges the board good:
//!
//! - two bus lines exchanged, or a strobe inverted, is the capture's
//!   problem (exit 4), named: a board whose bus lines are crossed for
//!   writes and reads alike would not work at all, and a probe on the
//!   wrong line is the likely cause by far;
//! - POUT or DIR inverted stays the board's divergence, with a hint: a
//!   board's output stage may invert them by design (then `--map
//!   POUT=~pout` says so), but a board whose DIR is wired inverted is
//!   faulty, and the capture cannot tell the two apart.

use super::{judge_traced, CaptureVerdict, JudgeError, JudgeOptions, Judgement};
use ppmc::trace::Trace;
use ppmc_logic::map::{ChannelMap, Signal};
use ppmc_logic::source::{LogicError, LogicSource};

/// Opens the capture again from its start, for another look.
pub type Opener<'a> = dyn FnMut() -> Result<Box<dyn LogicSource>, LogicError> + 'a;

/// A map that judges the board good where the given one did not.
struct Suspect {
    /// What looks wrong, in words: `D0 and D1 look exchanged`.
    what: String,
    /// The capture's problem (exit 4), or the board's with a hint.
    capture: bool,
    map: ChannelMap,
}

/// [`judge_traced`] on `source`, and where the board diverges, the maps
/// a probing mistake would have needed tried in turn on the capture read
/// again (`reopen`; this module's doc): the verdict the capture's when a
/// bus line looks exchanged or a strobe inverted, a hint when POUT or DIR
/// looks inverted.
pub fn judge_reopening(
    source: &mut dyn LogicSource,
    reopen: &mut Opener<'_>,
    map: &ChannelMap,
    opts: &JudgeOptions,
    scenario: Option<&str>,
) -> Result<(Judgement, Option<Trace>), JudgeError> {
    let info = source.info().clone();
    let (mut j, trace) = judge_traced(source, map, opts, scenario)?;
    let CaptureVerdict::Failed(d) = &j.verdict else {
        return Ok((j, trace));
    };
    if let Some(s) = suspect(reopen, map, opts, &j)? {
        let base = ChannelMap::from_names(&info).unwrap_or_default();
        let spelled = match s.map.spelled_against(&base, &info) {
            m if m.is_empty() => "the channels as named (no --map)".to_string(),
            m => format!("`--map {m}`"),
        };
        if s.capture {
            j.verdict = CaptureVerdict::Capture(format!(
                "the board diverges from the model ({d}), but {}: judged with {spelled} it does not. Check the probes, or give that map",
                s.what
            ));
        } else {
            j.hints.push(format!(
                "{}: judged with {spelled} the board passes. If the board inverts it by design, give that map; if not, the board is wired wrong",
                s.what
            ));
        }
    }
    Ok((j, trace))
}

/// The first map a probing mistake would have needed that judges the
/// board good, if any: the board passes, having been judged on as many
/// register accesses as with the given map (`given`) and on at least as
/// many pulses as were compared before it diverged, and the host
/// firmware breaks no more rules than it did. (A strobe read inverted
/// can garble the bus into accesses the model follows: the host's
/// findings then say so; two strobes exchanged can hide every read.)
fn suspect(
    open: &mut Opener<'_>,
    map: &ChannelMap,
    opts: &JudgeOptions,
    given: &Judgement,
) -> Result<Option<Suspect>, JudgeError> {
    let quick = JudgeOptions {
        stop_at_divergence: true,
        partial: true,
        ..opts.clone()
    };
    for s in candidates(map) {
        let mut source = open()?;
        let (j, _) = judge_traced(source.as_mut(), &s.map, &quick, None)?;
        if j.verdict == CaptureVerdict::Passed
            && j.host.len() <= given.host.len()
            && j.accesses >= given.accesses
            && j.pulses >= given.pulses
        {
            return Ok(Some(s));
        }
    }
    Ok(None)
}

/// The maps to try, the likeliest mistakes first.
fn candidates(map: &ChannelMap) -> Vec<Suspect> {
    let mut out = Vec::new();
    let flip = |s: Signal| {
        let word = if map.is_inverted(s) {
            "is not inverted after all"
        } else {
            "looks inverted"
        };
        format!("{s} {word}")
    };
    for s in [Signal::Pout, Signal::Dir] {
        if map.get(s).is_some() {
            out.push(Suspect {
                what: flip(s),
                capture: false,
                map: map.with_inverted(s, !map.is_inverted(s)),
            });
        }
    }
    if map.get(Signal::Pout).is_some() && map.get(Signal::Dir).is_some() {
        out.push(Suspect {
            what: format!("{} and {}", flip(Signal::Pout), flip(Signal::Dir)),
            capture: false,
            map: map
                .with_inverted(Signal::Pout, !map.is_inverted(Signal::Pout))
                .with_inverted(Signal::Dir, !map.is_inverted(Signal::Dir)),
        });
    }
    for s in [Signal::Cs, Signal::Rd, Signal::Wr] {
        out.push(Suspect {
            what: flip(s),
            capture: true,
            map: map.with_inverted(s, !map.is_inverted(s)),
        });
    }
    let bus = [Signal::Cs, Signal::Rd, Signal::Wr, Signal::A0];
    let data: Vec<Signal> = (0..8).map(Signal::D).collect();
    for lines in [&bus[..], &data[..]] {
        for (i, &a) in lines.iter().enumerate() {
            for &b in &lines[i + 1..] {
                out.push(Suspect {
                    what: format!("{a} and {b} look exchanged"),
                    capture: true,
                    map: map.swapped(a, b),
                });
            }
        }
    }
    out
}

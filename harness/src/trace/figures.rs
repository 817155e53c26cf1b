//! What a run record draws of a scenario ([`Figures`], the record's
//! `figures`), taken from its trace: each move's pulse runs, the board's
//! and the golden trace's, and the pins around the point where the
//! scenario failed.

use super::{BusEvent, EventKind, Trace};
use crate::protocol::Pin;
use crate::time::Instant;
use ppmc_record::{Figures, MoveFigure, PinWave, Waveform, MAX_WAVE_PULSES};

/// Events either side of the failure the waveform's window takes in.
const WAVE_EVENTS: usize = 8;

/// Each move of `trace` with its pulse runs.
fn moves_of(trace: &Trace) -> Vec<MoveFigure> {
    let mut moves: Vec<MoveFigure> = Vec::new();
    for e in &trace.events {
        match &e.kind {
            EventKind::Move {
                kind, dir, steps, ..
            } => moves.push(MoveFigure {
                at_ns: e.at.as_nanos(),
                kind: kind.name().to_string(),
                dir: dir.name().to_string(),
                steps: *steps,
                runs: Vec::new(),
                golden: None,
            }),
            EventKind::Pulses { count, span, .. } => {
                if let Some(m) = moves.last_mut() {
                    let from = e.at.as_nanos().saturating_sub(m.at_ns);
                    m.runs.push([from, u64::from(*count), span.as_nanos()]);
                }
            }
            _ => {}
        }
    }
    moves
}

/// The figures of a scenario's `trace`, with the `golden` trace's moves
/// beside the board's, and the pins around `failed_at`.
pub fn figures(trace: &Trace, golden: Option<&Trace>, failed_at: Option<Instant>) -> Figures {
    let mut moves = moves_of(trace);
    if let Some(g) = golden {
        let mut theirs = moves_of(g).into_iter();
        for m in &mut moves {
            m.golden = theirs.next().map(|g| g.runs);
        }
    }
    let waveform = failed_at.map(|at| waveform(trace, &moves, at.as_nanos()));
    Figures { moves, waveform }
}

/// Pulse `k` (from 0) of the run `[from, count, span]`, at `base + from`.
fn pulse_at(base: u64, run: &[u64; 3], k: u64) -> u64 {
    let [from, count, span] = *run;
    let step = match count {
        0 | 1 => 0,
        n => (u128::from(k) * u128::from(span) / u128::from(n - 1)) as u64,
    };
    base.saturating_add(from).saturating_add(step)
}

/// The pulses of `runs` (placed at `base`) within `from..=to`, at most
/// `cap` of them, found by index, never by walking every pulse.
fn pulses_within(base: u64, runs: &[[u64; 3]], from: u64, to: u64, cap: usize) -> Vec<u64> {
    let mut out = Vec::new();
    for run in runs {
        let [start, count, span] = *run;
        let first = base.saturating_add(start);
        let last = first.saturating_add(span);
        if count == 0 || last < from || first > to {
            continue;
        }
        // The first pulse at or after `from`.
        let k0 = match count {
            1 => 0,
            _ if from <= first => 0,
            n => ((from - first) as u128 * u128::from(n - 1)).div_ceil(u128::from(span.max(1)))
                as u64,
        };
        for k in k0..count {
            let t = pulse_at(base, run, k);
            if t > to || out.len() >= cap {
                break;
            }
            if t >= from {
                out.push(t);
            }
        }
    }
    out
}

/// The bus access of `e` in a waveform's words.
fn bus_label(e: &BusEvent) -> Option<String> {
    Some(match e {
        // A command by its name: what the host asked for, at a glance.
        BusEvent::WriteCommand { byte, .. } => {
            format!("{} 0x{byte:02X}", crate::protocol::Command::decode(*byte))
        }
        BusEvent::WriteData { byte, .. } => format!("wd 0x{byte:02X}"),
        BusEvent::ReadStatus(value) => format!("rs 0x{value:02X}"),
        BusEvent::ReadData { byte, .. } => format!("rd 0x{byte:02X}"),
        BusEvent::SetInput { input, asserted } => {
            format!("{} {}", input.name(), if *asserted { "on" } else { "off" })
        }
        BusEvent::Reset => "reset".to_string(),
        _ => return None,
    })
}

/// How many bits a pin's value has.
fn bits_of(pin: Pin) -> u8 {
    match pin {
        Pin::Auxo => 4,
        Pin::Phases => 5,
        _ => 1,
    }
}

/// The pins of `trace` in a window of a few events either side of `mark`.
fn waveform(trace: &Trace, moves: &[MoveFigure], mark: u64) -> Waveform {
    // Candidate edges near the mark: the pulses either side of it in each
    // move, and every other event.
    let mut times: Vec<u64> = trace
        .events
        .iter()
        .filter(|e| matches!(e.kind, EventKind::Pin { .. } | EventKind::Bus(_)))
        .map(|e| e.at.as_nanos())
        .collect();
    for m in moves {
        for run in &m.runs {
            let [from, count, span] = *run;
            if count == 0 {
                continue;
            }
            let at = m.at_ns.saturating_add(from);
            let k = match (count, mark > at) {
                (1, _) | (_, false) => 0,
                (n, true) => ((mark - at) as u128 * u128::from(n - 1) / u128::from(span.max(1)))
                    .min(u128::from(n - 1)) as u64,
            };
            let lo = k.saturating_sub(WAVE_EVENTS as u64);
            let hi = (k + WAVE_EVENTS as u64).min(count - 1);
            times.extend((lo..=hi).map(|k| pulse_at(m.at_ns, run, k)));
        }
    }
    times.sort_unstable();
    times.dedup();
    let i = times.partition_point(|&t| t < mark);
    let from = times[..i]
        .iter()
        .rev()
        .nth(WAVE_EVENTS - 1)
        .or(times.first())
        .copied()
        .unwrap_or(mark)
        .min(mark);
    let to = times[i..]
        .get(WAVE_EVENTS)
        .or(times.last())
        .copied()
        .unwrap_or(mark)
        .max(mark);
    // A little room either side, and never a window of no width.
    let pad = ((to - from) / 20).max(500);
    let (from, to) = (from.saturating_sub(pad), to + pad);
    let mut wave = Waveform {
        from_ns: from,
        to_ns: to,
        mark_ns: mark,
        ..Waveform::default()
    };
    // The move the window is in, for the golden pulses.
    let current = moves.iter().rposition(|m| m.at_ns <= to);
    for m in moves {
        let room = MAX_WAVE_PULSES - wave.pout.len();
        wave.pout
            .extend(pulses_within(m.at_ns, &m.runs, from, to, room));
    }
    if let Some(golden) = current.and_then(|c| moves[c].golden.as_ref().map(|g| (c, g))) {
        let (c, g) = golden;
        wave.golden_pout = Some(pulses_within(moves[c].at_ns, g, from, to, MAX_WAVE_PULSES));
    }
    for pin in Pin::ALL {
        let mut p = PinWave {
            name: pin.name().to_string(),
            bits: bits_of(pin),
            ..PinWave::default()
        };
        let mut seen = false;
        for e in &trace.events {
            let EventKind::Pin { pin: q, value } = e.kind else {
                continue;
            };
            if q != pin {
                continue;
            }
            seen = true;
            let t = e.at.as_nanos();
            if t < from {
                p.initial = value;
            } else if t <= to {
                p.changes.push([t, u64::from(value)]);
            }
        }
        if seen {
            wave.pins.push(p);
        }
    }
    wave.bus = trace
        .events
        .iter()
        .filter(|e| (from..=to).contains(&e.at.as_nanos()))
        .filter_map(|e| match &e.kind {
            EventKind::Bus(b) => bus_label(b).map(|l| (e.at.as_nanos(), l)),
            _ => None,
        })
        .collect();
    wave
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pulses_within_a_window_are_found_by_index() {
        // 1,000,001 pulses 10 ns apart from 100 ns.
        let runs = [[100, 1_000_001, 10_000_000]];
        let got = pulses_within(0, &runs, 5_000_005, 5_000_050, 100);
        assert_eq!(
            got,
            vec![5_000_010, 5_000_020, 5_000_030, 5_000_040, 5_000_050]
        );
        assert!(pulses_within(0, &runs, 0, 99, 100).is_empty());
        assert_eq!(pulses_within(0, &runs, 0, u64::MAX, 3), vec![100, 110, 120]);
    }
}

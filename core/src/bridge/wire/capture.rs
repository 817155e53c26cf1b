//! Capture records on the wire: pulse runs, pin changes and move starts.

use super::bytes::{R, W};
use super::message::*;
use crate::protocol::capture::MoveStart;
use crate::protocol::{MoveKind, Pin, PinEvent, PulseRun, Winding};
use crate::time::Duration;

pub(super) fn pin_code(p: Pin) -> u8 {
    Pin::ALL.iter().position(|x| *x == p).unwrap_or(0) as u8
}

pub(super) fn winding_code(w: Option<Winding>) -> u8 {
    w.and_then(|w| Winding::ALL.iter().position(|x| *x == w))
        .map_or(0, |i| i as u8 + 1)
}

pub(super) fn winding_from(c: u8) -> Option<Winding> {
    Winding::ALL.get(usize::from(c).checked_sub(1)?).copied()
}

pub(super) fn move_kind_code(k: MoveKind) -> u8 {
    k.code()
}

pub(super) fn move_kind_from(at: usize, c: u8) -> Result<MoveKind, WireError> {
    MoveKind::ALL
        .into_iter()
        .find(|k| k.code() == c)
        .ok_or(WireError::BadValue {
            at,
            field: "move kind",
            value: u64::from(c),
        })
}

/// Bytes of one pulse run on the wire.
pub(super) const RUN_BYTES: usize = 8 + 8 + 4 + 1 + 4;

pub(super) fn put_capture(w: &mut W, c: &CaptureChunk) {
    w.u16(c.runs.len() as u16);
    for run in &c.runs {
        w.time(run.start);
        w.dur(run.span);
        w.u32(run.count);
        w.u8(u8::from(run.dir.bit()));
        w.bound(run.jitter);
    }
    w.u16(c.pins.len() as u16);
    for p in &c.pins {
        w.time(p.at);
        w.u8(pin_code(p.pin));
        w.u8(p.value);
    }
    w.u16(c.moves.len() as u16);
    for m in &c.moves {
        w.time(m.at);
        w.u8(move_kind_code(m.kind));
        w.u8(u8::from(m.dir.bit()));
        w.u8(u8::from(m.pout));
        w.u32(m.steps);
        w.u8(winding_code(m.winding));
        w.u32(m.phase_index);
        w.u32(m.first_run as u32);
    }
    w.u64(c.overwritten_bytes);
    w.u8(u8::from(c.more));
}

pub(super) fn get_capture(r: &mut R) -> Result<CaptureChunk, WireError> {
    let mut c = CaptureChunk::default();
    let n = r.count(RUN_BYTES)?;
    for _ in 0..n {
        let start = r.time()?;
        let span = r.dur()?;
        let cat = r.at;
        let count = r.u32()?;
        let dir = r.dir()?;
        let mut jitter = r.bound()?;
        if count == 0 || (count == 1 && span != Duration::ZERO) {
            return Err(WireError::BadValue {
                at: cat,
                field: if count == 0 {
                    "pulse count"
                } else {
                    "span of a one-pulse run"
                },
                value: if count == 0 { 0 } else { span.as_nanos() },
            });
        }
        // Start and span each lose up to a nanosecond on the way from
        // ticks, so the pulses between them may sit up to two nanoseconds
        // further from the line.
        if count > 2 && !r.timer.whole_nanos() {
            jitter += Duration::from_nanos(2);
        }
        c.runs.push(PulseRun {
            start,
            count,
            dir,
            span,
            jitter,
        });
    }
    let n = r.count(10)?;
    for _ in 0..n {
        let at = r.time()?;
        let pat = r.at;
        let code = r.u8()?;
        let pin = *Pin::ALL.get(usize::from(code)).ok_or(WireError::BadValue {
            at: pat,
            field: "pin",
            value: u64::from(code),
        })?;
        c.pins.push(PinEvent {
            at,
            pin,
            value: r.u8()?,
        });
    }
    let n = r.count(24)?;
    for _ in 0..n {
        let at = r.time()?;
        let kat = r.at;
        let kind = move_kind_from(kat, r.u8()?)?;
        let dir = r.dir()?;
        let pout = r.bool("pout")?;
        let steps = r.u32()?;
        let wat = r.at;
        let wc = r.u8()?;
        let winding = winding_from(wc);
        if wc != 0 && winding.is_none() {
            return Err(WireError::BadValue {
                at: wat,
                field: "winding",
                value: u64::from(wc),
            });
        }
        let phase_index = r.u32()?;
        let first_run = r.u32()? as usize;
        c.moves.push(MoveStart {
            at,
            kind,
            dir,
            pout,
            steps,
            first_run,
            phase_index,
            winding,
        });
    }
    c.overwritten_bytes = r.u64()?;
    c.more = r.bool("more")?;
    Ok(c)
}

//! Requests and responses to bytes and back: [`Request::encode`],
//! [`Request::decode`], [`Response::encode`], [`Response::decode`], and
//! the straps as HELLO_REPLY carries them.

use super::bytes::{Timer, R, W};
use super::capture::{get_capture, put_capture};
use super::message::*;
use super::ops::{get_ops, get_replies, put_ops, put_replies};
use crate::bus::{SelfTestPlan, SelfTestReply, Uncertainty};
use crate::protocol::Straps;
use crate::time::Duration;
use alloc::boxed::Box;
use alloc::vec::Vec;

/// Strap flags in HELLO_REPLY.
mod strap_flag {
    pub const CSEL_HIGH: u8 = 0x01;
    pub const VSEL_HIGH: u8 = 0x02;
    pub const EXT_CLOCK: u8 = 0x04;
}

fn put_straps(w: &mut W, s: &Straps) {
    w.u32(s.sysclk_hz);
    let mut flags = 0;
    if s.csel_high {
        flags |= strap_flag::CSEL_HIGH;
    }
    if s.vsel_high {
        flags |= strap_flag::VSEL_HIGH;
    }
    if s.ext_clock_hz.is_some() {
        flags |= strap_flag::EXT_CLOCK;
    }
    w.u8(flags);
    w.u32(s.ext_clock_hz.unwrap_or(0));
}

fn get_straps(r: &mut R) -> Result<Straps, WireError> {
    let sysclk_hz = r.u32()?;
    let at = r.at;
    let flags = r.u8()?;
    let all = strap_flag::CSEL_HIGH | strap_flag::VSEL_HIGH | strap_flag::EXT_CLOCK;
    if flags & !all != 0 {
        return Err(WireError::BadValue {
            at,
            field: "strap flags",
            value: u64::from(flags),
        });
    }
    let at = r.at;
    let ext = r.u32()?;
    let fitted = flags & strap_flag::EXT_CLOCK != 0;
    if fitted != (ext != 0) {
        return Err(WireError::BadValue {
            at,
            field: "external clock (0 exactly when not fitted)",
            value: u64::from(ext),
        });
    }
    Ok(Straps {
        sysclk_hz,
        csel_high: flags & strap_flag::CSEL_HIGH != 0,
        vsel_high: flags & strap_flag::VSEL_HIGH != 0,
        ext_clock_hz: fitted.then_some(ext),
    })
}

/// Where a capture fetch starts, and its chunk size (CAPTURE,
/// BATCH_CAPTURE).
fn put_capture_from(w: &mut W, runs: u32, pins: u32, moves: u32, max: u16) {
    w.u32(runs);
    w.u32(pins);
    w.u32(moves);
    w.u16(max);
}

impl Request {
    /// The frame payload for this request with sequence number `seq`,
    /// times in ticks of `timer`.
    pub fn encode(&self, seq: u8, timer: Timer) -> Vec<u8> {
        let mut w = W(Vec::new(), timer);
        w.u8(seq);
        match self {
            Request::Hello { version, host } => {
                w.u8(kind::HELLO);
                w.u16(*version);
                w.u32(*host);
            }
            Request::Batch(ops) => {
                w.u8(kind::BATCH);
                put_ops(&mut w, ops);
            }
            Request::Capture {
                runs,
                pins,
                moves,
                max,
            } => {
                w.u8(kind::CAPTURE);
                put_capture_from(&mut w, *runs, *pins, *moves, *max);
            }
            Request::BatchCapture {
                ops,
                runs,
                pins,
                moves,
                max,
            } => {
                w.u8(kind::BATCH_CAPTURE);
                put_ops(&mut w, ops);
                put_capture_from(&mut w, *runs, *pins, *moves, *max);
            }
            Request::Link { fragment, pad } => {
                w.u8(kind::LINK);
                w.u8(*fragment);
                w.u16(*pad);
            }
            Request::SelfTest(p) => {
                w.u8(kind::SELF_TEST);
                w.u32(p.count);
                w.dur(p.high);
                w.dur(p.low);
                w.u16(p.bursts);
                w.dur(p.gap);
            }
            Request::Abort { request } => {
                w.u8(kind::ABORT);
                w.u8(*request);
            }
            Request::Resend { fragments } => {
                w.u8(kind::RESEND);
                w.u8(fragments.len().min(255) as u8);
                for f in fragments.iter().take(255) {
                    w.u8(*f);
                }
            }
        }
        w.0
    }

    /// `(seq, request)` from a frame payload, times in ticks of `timer`.
    pub fn decode(payload: &[u8], timer: Timer) -> Result<(u8, Request), WireError> {
        let mut r = R::new(payload, timer);
        let seq = r.u8()?;
        let req = match r.u8()? {
            kind::HELLO => {
                let version = r.u16()?;
                if version != PROTOCOL_VERSION {
                    // Another version's HELLO may carry other fields: the
                    // bridge answers VERSION whatever follows.
                    return Ok((seq, Request::Hello { version, host: 0 }));
                }
                Request::Hello {
                    version,
                    host: r.u32()?,
                }
            }
            kind::BATCH => Request::Batch(get_ops(&mut r)?),
            kind::CAPTURE => Request::Capture {
                runs: r.u32()?,
                pins: r.u32()?,
                moves: r.u32()?,
                max: r.u16()?,
            },
            kind::BATCH_CAPTURE => {
                let ops = get_ops(&mut r)?;
                Request::BatchCapture {
                    ops,
                    runs: r.u32()?,
                    pins: r.u32()?,
                    moves: r.u32()?,
                    max: r.u16()?,
                }
            }
            kind::LINK => Request::Link {
                fragment: r.u8()?,
                pad: r.u16()?,
            },
            kind::ABORT => Request::Abort { request: r.u8()? },
            kind::RESEND => {
                let n = usize::from(r.u8()?);
                Request::Resend {
                    fragments: r.take(n)?.to_vec(),
                }
            }
            kind::SELF_TEST => {
                let at = r.at;
                let count = r.u32()?;
                if count == 0 {
                    return Err(WireError::BadValue {
                        at,
                        field: "self-test pulse count",
                        value: 0,
                    });
                }
                let (high, low) = (r.dur()?, r.dur()?);
                let at = r.at;
                let bursts = r.u16()?;
                if bursts == 0 {
                    return Err(WireError::BadValue {
                        at,
                        field: "self-test burst count",
                        value: 0,
                    });
                }
                Request::SelfTest(SelfTestPlan {
                    count,
                    high,
                    low,
                    bursts,
                    gap: r.dur()?,
                })
            }
            k => return Err(WireError::UnknownKind(k)),
        };
        r.end()?;
        Ok((seq, req))
    }
}

impl Response {
    /// The frame payload for this response to request `seq`, times in
    /// ticks of `timer`.
    pub fn encode(&self, seq: u8, timer: Timer) -> Vec<u8> {
        let mut w = W(Vec::new(), timer);
        w.u8(seq);
        match self {
            Response::Hello(h) => {
                w.u8(kind::HELLO_REPLY);
                w.u16(h.version);
                w.u32(h.session);
                w.u64(h.timer_hz);
                w.u16(h.max_batch_ops);
                w.u16(h.max_payload);
                w.u32(h.capture_capacity);
                w.u16(h.inputs_wired);
                w.u8(u8::from(h.virtual_time));
                w.str(&h.firmware);
                put_straps(&mut w, &h.straps);
                w.u8(u8::from(h.resumed));
                w.str(&h.serial);
                let u = &h.uncertainty;
                for d in [u.edge, u.sampled, u.access, u.polled] {
                    w.u32(u32::try_from(d.as_nanos()).unwrap_or(u32::MAX));
                }
            }
            Response::Batch(replies) => {
                w.u8(kind::BATCH_REPLY);
                put_replies(&mut w, replies);
            }
            Response::Capture(c) => {
                w.u8(kind::CAPTURE_REPLY);
                put_capture(&mut w, c);
            }
            Response::BatchCapture { replies, capture } => {
                w.u8(kind::BATCH_CAPTURE_REPLY);
                put_replies(&mut w, replies);
                put_capture(&mut w, capture);
            }
            Response::Error { code, detail } => {
                w.u8(kind::ERROR);
                w.u8(code.code());
                w.str(detail);
            }
            Response::Link { fragment, pad } => {
                w.u8(kind::LINK_REPLY);
                w.u8(*fragment);
                w.u16(*pad);
            }
            Response::Working { elapsed } => {
                w.u8(kind::WORKING);
                w.dur(*elapsed);
            }
            Response::Abort { stopped } => {
                w.u8(kind::ABORT_REPLY);
                w.u8(u8::from(*stopped));
            }
            Response::SelfTest(t) => {
                w.u8(kind::SELF_TEST_REPLY);
                w.dur(t.high);
                w.dur(t.low);
                let n = t.starts.len().min(usize::from(u16::MAX));
                w.u16(n as u16);
                for at in &t.starts[..n] {
                    w.time(*at);
                }
            }
        }
        w.0
    }

    /// `(seq, response)` from a frame payload, times in ticks of `timer`.
    pub fn decode(payload: &[u8], timer: Timer) -> Result<(u8, Response), WireError> {
        // No bridge sends a longer one (it answers OVERFLOW instead).
        if payload.len() > MAX_REPLY {
            return Err(WireError::BadValue {
                at: 0,
                field: "response length",
                value: payload.len() as u64,
            });
        }
        let mut r = R::new(payload, timer);
        let seq = r.u8()?;
        let resp = match r.u8()? {
            kind::HELLO_REPLY => Response::Hello(Box::new(Hello {
                version: r.u16()?,
                session: r.u32()?,
                timer_hz: r.u64()?,
                max_batch_ops: r.u16()?,
                max_payload: r.u16()?,
                capture_capacity: r.u32()?,
                inputs_wired: r.u16()?,
                virtual_time: r.bool("virtual time flag")?,
                firmware: r.str()?,
                straps: get_straps(&mut r)?,
                resumed: r.bool("resumed flag")?,
                serial: r.str()?,
                uncertainty: {
                    let mut ns = || r.u32().map(|n| Duration::from_nanos(u64::from(n)));
                    Uncertainty {
                        edge: ns()?,
                        sampled: ns()?,
                        access: ns()?,
                        polled: ns()?,
                    }
                },
            })),
            kind::BATCH_REPLY => Response::Batch(get_replies(&mut r)?),
            kind::CAPTURE_REPLY => Response::Capture(get_capture(&mut r)?),
            kind::BATCH_CAPTURE_REPLY => {
                let replies = get_replies(&mut r)?;
                Response::BatchCapture {
                    replies,
                    capture: get_capture(&mut r)?,
                }
            }
            kind::ERROR => Response::Error {
                code: BridgeErrorCode::from_code(r.u8()?),
                detail: r.str()?,
            },
            kind::WORKING => Response::Working { elapsed: r.dur()? },
            kind::ABORT_REPLY => Response::Abort {
                stopped: r.bool("stopped flag")?,
            },
            kind::LINK_REPLY => Response::Link {
                fragment: r.u8()?,
                pad: r.u16()?,
            },
            kind::SELF_TEST_REPLY => {
                let (high, low) = (r.dur()?, r.dur()?);
                let n = r.count(8)?;
                let mut starts = Vec::with_capacity(n);
                for _ in 0..n {
                    starts.push(r.time()?);
                }
                Response::SelfTest(SelfTestReply { starts, high, low })
            }
            k => return Err(WireError::UnknownKind(k)),
        };
        r.end()?;
        Ok((seq, resp))
    }
}

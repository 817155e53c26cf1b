//! `rfc2217://host:port`: a serial port served over telnet with the
//! COM-PORT-OPTION of RFC 2217, as ser2net's `telnet(rfc2217)` mode and
//! labgrid's exporter serve it.
//!
//! Telnet puts its commands in the byte stream behind IAC (0xFF), so a data
//! byte 0xFF is sent as 0xFF 0xFF and read back the same way; bridge frames
//! contain 0xFF often. The link asks for binary transmission both ways (so
//! that no CR is rewritten), answers the server's option requests (yes to
//! BINARY, SUPPRESS-GO-AHEAD and COM-PORT-OPTION, no to anything else), and
//! sets the line to 8N1 without flow control at the baud rate given. A
//! server that never answers the port settings is tolerated: over a pseudo-
//! terminal or USB CDC the settings change nothing, and the link layer's
//! health check says whether the bridge is there.

use super::tcp::{host_and_port, TcpLink, HOST_PORT_HINT};
use super::{bad_address, Link, LinkDriver};
use crate::stop::StopRequest;
use std::fmt;
use std::io;
use std::time::Duration as WallDuration;

const IAC: u8 = 255;
const DONT: u8 = 254;
const DO: u8 = 253;
const WONT: u8 = 252;
const WILL: u8 = 251;
const SB: u8 = 250;
const SE: u8 = 240;

const BINARY: u8 = 0;
const SGA: u8 = 3;
const COM_PORT: u8 = 44;

// COM-PORT-OPTION subnegotiations, client to server (RFC 2217).
const SET_BAUDRATE: u8 = 1;
const SET_DATASIZE: u8 = 2;
const SET_PARITY: u8 = 3;
const SET_STOPSIZE: u8 = 4;
const SET_CONTROL: u8 = 5;

/// Where the telnet parser is in the incoming stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Rx {
    Data,
    Iac,
    /// After IAC WILL/WONT/DO/DONT: the option comes next.
    Verb(u8),
    /// Inside IAC SB ... IAC SE.
    Sub,
    SubIac,
}

/// The telnet layer, apart from the socket, so that it can be tested on
/// bytes alone.
#[derive(Debug, Clone)]
pub struct Telnet {
    rx: Rx,
    /// Replies to the server's option requests, to send.
    pub answers: Vec<u8>,
    /// The (verb, option) pairs answered already: each is answered once,
    /// so a server that repeats its requests (an option storm) cannot make
    /// the client send without end (RFC 1143's rule against loops).
    answered: std::collections::HashSet<(u8, u8)>,
    /// Telnet commands read since the last data byte.
    pub commands_without_data: u64,
}

impl Default for Telnet {
    fn default() -> Self {
        Telnet {
            rx: Rx::Data,
            answers: Vec::new(),
            answered: std::collections::HashSet::new(),
            commands_without_data: 0,
        }
    }
}

/// Telnet commands a server may send with no data between them before the
/// link takes it for an option storm and fails the connection: far more
/// than any negotiation takes (ser2net's takes a dozen).
pub const MAX_COMMANDS_WITHOUT_DATA: u64 = 4096;

impl Telnet {
    /// What the client says first: binary both ways, no go-ahead, and the
    /// COM port at `baud`, 8N1, no flow control.
    pub fn opening(baud: u32) -> Vec<u8> {
        let mut v = vec![
            IAC, WILL, BINARY, IAC, DO, BINARY, IAC, WILL, SGA, IAC, DO, SGA, IAC, WILL, COM_PORT,
        ];
        let mut sub = |cmd: u8, value: &[u8]| {
            v.extend([IAC, SB, COM_PORT, cmd]);
            v.extend(escape(value));
            v.extend([IAC, SE]);
        };
        sub(SET_BAUDRATE, &baud.to_be_bytes());
        sub(SET_DATASIZE, &[8]);
        sub(SET_PARITY, &[1]); // none
        sub(SET_STOPSIZE, &[1]); // one
        sub(SET_CONTROL, &[1]); // no flow control
        v
    }

    /// The data in `bytes` from the server, telnet commands taken out (and
    /// answered in `answers`).
    pub fn receive(&mut self, bytes: &[u8], out: &mut Vec<u8>) {
        for &b in bytes {
            self.rx = match (self.rx, b) {
                (Rx::Data, IAC) => Rx::Iac,
                (Rx::Data, b) => {
                    out.push(b);
                    self.commands_without_data = 0;
                    Rx::Data
                }
                (Rx::Iac, IAC) => {
                    out.push(IAC);
                    self.commands_without_data = 0;
                    Rx::Data
                }
                (Rx::Iac, v @ (WILL | WONT | DO | DONT)) => Rx::Verb(v),
                (Rx::Iac, SB) => {
                    self.commands_without_data += 1;
                    Rx::Sub
                }
                // NOP, GA and the other one-byte commands.
                (Rx::Iac, _) => {
                    self.commands_without_data += 1;
                    Rx::Data
                }
                (Rx::Verb(v), opt) => {
                    self.commands_without_data += 1;
                    if self.answered.insert((v, opt)) {
                        self.answer(v, opt);
                    }
                    Rx::Data
                }
                (Rx::Sub, IAC) => Rx::SubIac,
                (Rx::Sub, _) => Rx::Sub,
                (Rx::SubIac, SE) => Rx::Data,
                (Rx::SubIac, _) => Rx::Sub,
            };
        }
    }

    fn answer(&mut self, verb: u8, opt: u8) {
        let wanted = matches!(opt, BINARY | SGA | COM_PORT);
        let reply = match verb {
            // The server offers or asks: take what we want.
            WILL => Some(if wanted { DO } else { DONT }),
            DO => Some(if wanted { WILL } else { WONT }),
            // A refusal needs no answer, and we sent the requests already.
            _ => None,
        };
        if let Some(r) = reply {
            // Answers to our own requests would loop; the requests above
            // are sent once, and a WILL/DO for them is their acceptance.
            let ours = matches!(opt, BINARY | SGA) || (opt == COM_PORT && verb == DO);
            if !ours {
                self.answers.extend([IAC, r, opt]);
            }
        }
    }
}

/// `bytes` with every 0xFF doubled, as telnet data.
pub fn escape(bytes: &[u8]) -> Vec<u8> {
    let mut v = Vec::with_capacity(bytes.len() + 8);
    for &b in bytes {
        v.push(b);
        if b == IAC {
            v.push(IAC);
        }
    }
    v
}

/// `host:port` and the baud rate of `rfc2217://host:port[,baud=N]`.
pub fn parse_rfc2217(spec: &str) -> Option<(String, u32)> {
    let rest = spec.strip_prefix("rfc2217://")?;
    let (addr, baud) = match rest.split_once(',') {
        Some((a, opt)) => (a, opt.strip_prefix("baud=")?.parse().ok()?),
        None => (rest, 115_200),
    };
    super::tcp::parse_tcp(&format!("tcp://{addr}"))?;
    (baud > 0).then(|| (addr.to_string(), baud))
}

pub struct Rfc2217Link {
    tcp: TcpLink,
    baud: u32,
    telnet: Telnet,
    /// Data received but not yet handed out.
    pending: Vec<u8>,
}

impl fmt::Debug for Rfc2217Link {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Rfc2217Link")
            .field("tcp", &self.tcp)
            .field("baud", &self.baud)
            .finish()
    }
}

/// The driver of `rfc2217://<host>:<port>[,baud=N]`.
#[derive(Debug)]
pub struct Rfc2217Driver;

pub(super) static DRIVER: Rfc2217Driver = Rfc2217Driver;

impl LinkDriver for Rfc2217Driver {
    fn prefix(&self) -> &'static str {
        "rfc2217://"
    }

    fn form(&self) -> &'static str {
        "rfc2217://<host>:<port>[,baud=N]"
    }

    fn about(&self) -> &'static str {
        "served over telnet with RFC 2217, as ser2net's telnet(rfc2217) mode and labgrid's exporter serve it"
    }

    fn default_pad(&self) -> u16 {
        64
    }

    fn check(&self, address: &str) -> Result<(), &'static str> {
        parse_rfc2217(address)
            .filter(|(addr, _)| host_and_port(addr))
            .map(drop)
            .ok_or(HOST_PORT_HINT)
    }

    fn open(&self, address: &str, how: &super::LinkOpen) -> io::Result<Box<dyn Link>> {
        let (addr, baud) = parse_rfc2217(address).ok_or_else(|| bad_address(self, address))?;
        Ok(Box::new(Rfc2217Link::open_until(
            &addr,
            baud,
            how.stop.clone(),
        )?))
    }
}

impl Rfc2217Link {
    pub fn open(addr: &str, baud: u32) -> io::Result<Rfc2217Link> {
        Self::open_until(addr, baud, StopRequest::default())
    }

    /// [`Self::open`], abandoning a connection attempt once `stop` is
    /// asked for. The error names the link.
    pub fn open_until(addr: &str, baud: u32, stop: StopRequest) -> io::Result<Rfc2217Link> {
        let mut link = Rfc2217Link {
            tcp: TcpLink::open_until(addr, stop)?,
            baud,
            telnet: Telnet::default(),
            pending: Vec::new(),
        };
        link.greet()
            .map_err(|e| io::Error::new(e.kind(), format!("{}: {e}", link.name())))?;
        Ok(link)
    }

    fn greet(&mut self) -> io::Result<()> {
        self.telnet = Telnet::default();
        self.pending.clear();
        self.tcp.send(&Telnet::opening(self.baud))
    }

    fn flush_answers(&mut self) -> io::Result<()> {
        if !self.telnet.answers.is_empty() {
            let a = std::mem::take(&mut self.telnet.answers);
            self.tcp.send(&a)?;
        }
        Ok(())
    }
}

impl Link for Rfc2217Link {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.tcp.send(&escape(bytes))
    }

    fn recv(&mut self, buf: &mut [u8], timeout: WallDuration) -> io::Result<usize> {
        if self.pending.is_empty() {
            let mut raw = [0u8; 4096];
            let n = self.tcp.recv(&mut raw, timeout)?;
            self.telnet.receive(&raw[..n], &mut self.pending);
            self.flush_answers()?;
            if self.telnet.commands_without_data > MAX_COMMANDS_WITHOUT_DATA {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    format!(
                        "the server sent over {MAX_COMMANDS_WITHOUT_DATA} telnet commands and no data (an option storm)"
                    ),
                ));
            }
        }
        let n = self.pending.len().min(buf.len());
        buf[..n].copy_from_slice(&self.pending[..n]);
        self.pending.drain(..n);
        Ok(n)
    }

    fn close(&mut self) {
        self.tcp.close();
        self.pending.clear();
    }

    fn reopen(&mut self) -> io::Result<()> {
        self.tcp.reopen()?;
        self.greet()
    }

    fn name(&self) -> String {
        format!("rfc2217://{}", self.tcp.name().trim_start_matches("tcp://"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A server that repeats its option requests without end is answered
    /// once per request, and counted, so the link can give up on it.
    #[test]
    fn an_option_storm_is_answered_once_and_counted() {
        let mut t = Telnet::default();
        let mut out = Vec::new();
        let storm: Vec<u8> = (0..1000)
            .flat_map(|_| [IAC, DO, 24, IAC, WILL, 1])
            .collect();
        t.receive(&storm, &mut out);
        assert!(out.is_empty());
        assert_eq!(t.answers, [IAC, WONT, 24, IAC, DONT, 1]);
        assert_eq!(t.commands_without_data, 2000);
        t.receive(b"x", &mut out);
        assert_eq!((out.as_slice(), t.commands_without_data), (&b"x"[..], 0));
    }

    #[test]
    fn data_0xff_is_doubled_and_read_back_once() {
        assert_eq!(
            escape(&[1, 0xFF, 2, 0xFF, 0xFF]),
            [1, 0xFF, 0xFF, 2, 0xFF, 0xFF, 0xFF, 0xFF]
        );
        let mut t = Telnet::default();
        let mut out = Vec::new();
        t.receive(&escape(&[0, 0xFF, 7, 0xFF]), &mut out);
        assert_eq!(out, [0, 0xFF, 7, 0xFF]);
        // Split anywhere, even between the two 0xFF.
        let mut t = Telnet::default();
        let mut out = Vec::new();
        for b in escape(&[9, 0xFF, 8]) {
            t.receive(&[b], &mut out);
        }
        assert_eq!(out, [9, 0xFF, 8]);
    }

    #[test]
    fn commands_are_taken_out_and_answered() {
        let mut t = Telnet::default();
        let mut out = Vec::new();
        // The server: WILL ECHO (1), DO TERMINAL-TYPE (24), a COM-PORT
        // reply to SET-BAUDRATE with an escaped 0xFF in its value, a NOP,
        // then data.
        let stream = [
            IAC, WILL, 1, IAC, DO, 24, IAC, SB, COM_PORT, 101, 0, 0, 0xFF, 0xFF, 0, IAC, SE, IAC,
            241, b'o', b'k',
        ];
        t.receive(&stream, &mut out);
        assert_eq!(out, b"ok");
        assert_eq!(t.answers, [IAC, DONT, 1, IAC, WONT, 24]);
        // Offers of what the client asked for need no answer.
        let mut t = Telnet::default();
        t.receive(
            &[IAC, WILL, BINARY, IAC, DO, COM_PORT, IAC, WILL, SGA],
            &mut out,
        );
        assert!(t.answers.is_empty());
    }

    #[test]
    fn the_opening_sets_the_port() {
        let o = Telnet::opening(115_200);
        assert!(o.starts_with(&[IAC, WILL, BINARY, IAC, DO, BINARY]));
        let baud = [IAC, SB, COM_PORT, SET_BAUDRATE, 0, 1, 0xC2, 0x00, IAC, SE];
        assert!(o.windows(baud.len()).any(|w| w == baud), "{o:?}");
    }

    #[test]
    fn specs_name_a_host_a_port_and_maybe_a_baud_rate() {
        assert_eq!(
            parse_rfc2217("rfc2217://127.0.0.1:4000"),
            Some(("127.0.0.1:4000".into(), 115_200))
        );
        assert_eq!(
            parse_rfc2217("rfc2217://exporter:20001,baud=921600"),
            Some(("exporter:20001".into(), 921_600))
        );
        for bad in [
            "rfc2217://",
            "rfc2217://h",
            "rfc2217://h:1,baud=0",
            "rfc2217://h:1,bd=9",
            "tcp://h:1",
        ] {
            assert_eq!(parse_rfc2217(bad), None, "{bad}");
        }
    }
}

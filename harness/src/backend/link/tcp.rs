//! A bridge across the lab network: `tcp://host:port`, a raw byte stream
//! to a serial port server (ser2net in raw mode, `socat`), behind the same
//! link layer as a local port (retransmission, reconnect, health check).
//!
//! A request and its reply are small, so latency is everything. The server
//! may run with Nagle's algorithm on (ser2net's default), and then holds
//! the second piece of a reply until the first is acknowledged; a client
//! that delays its acknowledgements (Linux does, up to 40 ms) makes every
//! split reply wait for that. The link therefore sends with TCP_NODELAY
//! and, where the OS has it, asks for quick acknowledgements before every
//! read (TCP_QUICKACK, which Linux clears again as it goes).

use super::{bad_address, timed_out, Link, LinkDriver};
use crate::stop::StopRequest;
use std::fmt;
use std::io::{self, Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::time::Duration as WallDuration;

/// How long a connection attempt may take.
const CONNECT_TIMEOUT: WallDuration = WallDuration::from_secs(5);

/// How long a send may block on a server that does not read (its window
/// closed): then the connection is taken as failed, and reopened. A
/// request is at most a few kilobytes, far less than a socket's buffer, so
/// only a server that stopped reading makes a send wait at all.
const SEND_TIMEOUT: WallDuration = WallDuration::from_secs(1);

pub struct TcpLink {
    /// `host:port` as given.
    addr: String,
    stream: Option<TcpStream>,
    /// Asked for, a connection attempt under way is abandoned.
    stop: StopRequest,
}

impl fmt::Debug for TcpLink {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("TcpLink").field("addr", &self.addr).finish()
    }
}

/// The driver of `tcp://<host>:<port>`.
#[derive(Debug)]
pub struct TcpDriver;

pub(super) static DRIVER: TcpDriver = TcpDriver;

/// The hint of a `host:port` that does not read.
pub(super) const HOST_PORT_HINT: &str = " (an IPv6 address in brackets: [::1])";

impl LinkDriver for TcpDriver {
    fn prefix(&self) -> &'static str {
        "tcp://"
    }

    fn form(&self) -> &'static str {
        "tcp://<host>:<port>"
    }

    fn about(&self) -> &'static str {
        "a bridge's serial port served on the network in raw mode, as ser2net or socat serve it"
    }

    fn default_pad(&self) -> u16 {
        64
    }

    fn check(&self, address: &str) -> Result<(), &'static str> {
        parse_tcp(address)
            .filter(|addr| host_and_port(addr))
            .map(drop)
            .ok_or(HOST_PORT_HINT)
    }

    fn open(&self, address: &str, how: &super::LinkOpen) -> io::Result<Box<dyn Link>> {
        let addr = parse_tcp(address).ok_or_else(|| bad_address(self, address))?;
        Ok(Box::new(TcpLink::open_until(&addr, how.stop.clone())?))
    }
}

/// `host:port` of a `tcp://host:port` target, if it is one.
pub fn parse_tcp(spec: &str) -> Option<String> {
    let rest = spec.strip_prefix("tcp://")?;
    let (host, port) = rest.rsplit_once(':')?;
    (!host.is_empty() && port.parse::<u16>().is_ok_and(|p| p != 0)).then(|| rest.to_string())
}

/// Whether `addr` reads as `host:port` that a connection can be tried to:
/// a port from 1 to 65535 after a host name, an IPv4 address or an IPv6
/// address in brackets (`[::1]:4321`). Anything else (`[::1`, `::1:4321`,
/// a space in the name) is the user's typing, refused before any
/// connection, never a network failure.
pub(super) fn host_and_port(addr: &str) -> bool {
    let Some((host, port)) = addr.rsplit_once(':') else {
        return false;
    };
    let port_ok = port.parse::<u16>().is_ok_and(|p| p != 0);
    let host_ok = match host.strip_prefix('[') {
        Some(v6) => v6
            .strip_suffix(']')
            .is_some_and(|v6| v6.parse::<std::net::Ipv6Addr>().is_ok()),
        None => {
            !host.is_empty()
                && host
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '.' | '_'))
        }
    };
    port_ok && host_ok
}

impl TcpLink {
    pub fn open(addr: &str) -> io::Result<TcpLink> {
        Self::open_until(addr, StopRequest::default())
    }

    /// [`Self::open`], abandoning a connection attempt (this one, or a
    /// reconnect's) once `stop` is asked for. The error names the link.
    pub fn open_until(addr: &str, stop: StopRequest) -> io::Result<TcpLink> {
        let mut link = TcpLink {
            addr: addr.to_string(),
            stream: None,
            stop,
        };
        link.reopen().map_err(|e| {
            let why = match e.kind() {
                io::ErrorKind::ConnectionRefused => {
                    format!("{e}: nothing listens there (is the serial port server running?)")
                }
                _ => e.to_string(),
            };
            io::Error::new(e.kind(), format!("{}: {why}", link.name()))
        })?;
        Ok(link)
    }

    fn stream(&mut self) -> io::Result<&mut TcpStream> {
        self.stream
            .as_mut()
            .ok_or_else(|| io::Error::new(io::ErrorKind::NotConnected, "not connected"))
    }

    fn quick_ack(stream: &TcpStream) {
        #[cfg(target_os = "linux")]
        {
            let _ = socket2::SockRef::from(stream).set_tcp_quickack(true);
        }
        #[cfg(not(target_os = "linux"))]
        let _ = stream;
    }
}

impl Link for TcpLink {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        let s = self.stream()?;
        s.write_all(bytes)?;
        s.flush()
    }

    fn recv(&mut self, buf: &mut [u8], timeout: WallDuration) -> io::Result<usize> {
        let s = self.stream()?;
        Self::quick_ack(s);
        s.set_read_timeout(Some(timeout.max(WallDuration::from_millis(1))))?;
        match s.read(buf) {
            // The server closed the connection: the link is down, and the
            // link layer reconnects.
            Ok(0) => {
                self.stream = None;
                Err(io::Error::new(
                    io::ErrorKind::ConnectionAborted,
                    "the server closed the connection",
                ))
            }
            Ok(n) => {
                Self::quick_ack(s);
                Ok(n)
            }
            Err(e) if timed_out(&e) || e.kind() == io::ErrorKind::Interrupted => Ok(0),
            Err(e) => Err(e),
        }
    }

    fn close(&mut self) {
        self.stream = None;
    }

    fn reopen(&mut self) -> io::Result<()> {
        self.stream = None;
        let s = connect(self.addr.clone(), &self.stop)?;
        s.set_nodelay(true)?;
        s.set_write_timeout(Some(SEND_TIMEOUT))?;
        Self::quick_ack(&s);
        self.stream = Some(s);
        Ok(())
    }

    fn name(&self) -> String {
        format!("tcp://{}", self.addr)
    }
}

/// Resolves `addr` and connects to its first address that answers, each
/// within [`CONNECT_TIMEOUT`], or until `stop` is asked for: the attempt
/// (the name lookup included, which can take long) runs on a thread of its
/// own, since neither can be woken, and is left to finish alone when
/// abandoned.
fn connect(addr: String, stop: &StopRequest) -> io::Result<TcpStream> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let attempt = || {
            let mut last = io::Error::new(io::ErrorKind::NotFound, "the host has no address");
            for a in addr.to_socket_addrs()? {
                match TcpStream::connect_timeout(&a, CONNECT_TIMEOUT) {
                    Ok(s) => return Ok(s),
                    Err(e) => last = e,
                }
            }
            Err(last)
        };
        let _ = tx.send(attempt());
    });
    loop {
        if stop.requested() {
            return Err(io::Error::new(
                io::ErrorKind::Interrupted,
                "connection attempt abandoned: a stop was asked for",
            ));
        }
        match rx.recv_timeout(StopRequest::SLICE) {
            Ok(r) => return r,
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                return Err(io::Error::other(
                    "the connection attempt ended without a word",
                ))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn network_addresses_are_host_and_port_or_the_users_mistake() {
        for good in [
            "bench1.lab:4321",
            "127.0.0.1:2001",
            "[::1]:4321",
            "[fe80::1]:1",
            "rig_1:65535",
        ] {
            assert!(host_and_port(good), "{good}");
        }
        for bad in [
            "[::1",
            "[::1]",
            "[::1:4321",
            "::1:4321",
            "[nothost]:4321",
            "host:0",
            "host:65536",
            ":4321",
            "host name:4321",
            "host",
        ] {
            assert!(!host_and_port(bad), "{bad}");
        }
    }

    #[test]
    fn tcp_specs_name_a_host_and_a_port() {
        assert_eq!(
            parse_tcp("tcp://127.0.0.1:3333").as_deref(),
            Some("127.0.0.1:3333")
        );
        assert_eq!(
            parse_tcp("tcp://lab-rack-4:2000").as_deref(),
            Some("lab-rack-4:2000")
        );
        assert_eq!(parse_tcp("tcp://[::1]:2000").as_deref(), Some("[::1]:2000"));
        for bad in [
            "tcp://",
            "tcp://host",
            "tcp://host:0",
            "tcp://:2000",
            "tcp://h:99999",
            "serial:/x",
        ] {
            assert_eq!(parse_tcp(bad), None, "{bad}");
        }
    }

    #[test]
    fn a_refused_connection_names_the_target() {
        // A port nothing listens on: bind one, learn it, free it.
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .and_then(|l| l.local_addr())
            .map(|a| a.port())
            .expect("a free port");
        let e = TcpLink::open(&format!("127.0.0.1:{port}")).expect_err("refused");
        let text = e.to_string();
        assert!(text.contains(&format!("tcp://127.0.0.1:{port}")), "{text}");
    }

    #[test]
    fn bytes_go_both_ways_and_a_closed_server_is_an_error() {
        let server = std::net::TcpListener::bind("127.0.0.1:0").expect("listen");
        let addr = server.local_addr().expect("addr").to_string();
        let echo = std::thread::spawn(move || {
            let (mut s, _) = server.accept().expect("accept");
            let mut b = [0u8; 4];
            s.read_exact(&mut b).expect("read");
            s.write_all(&b).expect("write");
            // Then the server goes away.
        });
        let mut link = TcpLink::open(&addr).expect("connects");
        link.send(b"ping").expect("sends");
        let mut got = Vec::new();
        let mut buf = [0u8; 16];
        while got.len() < 4 {
            let n = link
                .recv(&mut buf, WallDuration::from_secs(2))
                .expect("reads");
            got.extend_from_slice(&buf[..n]);
        }
        assert_eq!(got, b"ping");
        echo.join().expect("echo ends");
        let e = loop {
            match link.recv(&mut buf, WallDuration::from_millis(200)) {
                Ok(0) => continue,
                Ok(_) => panic!("no more bytes"),
                Err(e) => break e,
            }
        };
        assert_eq!(e.kind(), io::ErrorKind::ConnectionAborted);
    }
}

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

use super::{timed_out, Link};
use crate::backend::serial::SerialError;
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

/// `host:port` of a `tcp://host:port` target, if it is one.
pub fn parse_tcp(spec: &str) -> Option<String> {
    let rest = spec.strip_prefix("tcp://")?;
    let (host, port) = rest.rsplit_once(':')?;
    (!host.is_empty() && port.parse::<u16>().is_ok_and(|p| p != 0)).then(|| rest.to_string())
}

impl TcpLink {
    pub fn open(addr: &str) -> Result<TcpLink, SerialError> {
        Self::open_until(addr, StopRequest::default())
    }

    /// [`Self::open`], abandoning a connection attempt (this one, or a
    /// reconnect's) once `stop` is asked for.
    pub fn open_until(addr: &str, stop: StopRequest) -> Result<TcpLink, SerialError> {
        let mut link = TcpLink {
            addr: addr.to_string(),
            stream: None,
            stop,
        };
        link.reopen().map_err(|e| SerialError::Io {
            path: link.name(),
            source: match e.kind() {
                io::ErrorKind::ConnectionRefused => io::Error::new(
                    e.kind(),
                    format!("{e}: nothing listens there (is the serial port server running?)"),
                ),
                _ => e,
            },
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

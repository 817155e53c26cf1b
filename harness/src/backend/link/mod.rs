//! The byte links a bridge is reached over: the [`Link`] trait and one
//! file per kind: a serial port (`serial.rs`), raw TCP (`tcp.rs`), telnet
//! with RFC 2217 (`rfc2217.rs`), a labgrid place's port (`labgrid.rs`).
//! The bridge protocol on top of any of them is `backend::serial`'s
//! `SerialTarget`; which address form opens which link is
//! `backend::spec`'s `LinkKind`.

pub mod labgrid;
pub mod rfc2217;
pub mod serial;
pub mod tcp;

use std::fmt;
use std::io;
use std::time::Duration as WallDuration;

/// A byte link to a bridge.
pub trait Link: Send + fmt::Debug {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()>;
    /// Reads what arrives within `timeout`; `Ok(0)` when nothing did.
    fn recv(&mut self, buf: &mut [u8], timeout: WallDuration) -> io::Result<usize>;
    /// Opens the link again after it failed.
    fn reopen(&mut self) -> io::Result<()>;
    /// What to call the link in messages: `serial:/dev/ttyACM0`.
    fn name(&self) -> String;
    /// The serial number of the device at the link's far end, where the
    /// operating system knows it (a USB serial port's iSerial); `None`
    /// across a network.
    fn device_serial(&self) -> Option<String> {
        None
    }
}

/// A read that ended because its timeout passed (or, on a nonblocking
/// socket, because nothing was there): nothing arrived, no failure.
pub(crate) fn timed_out(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
    )
}

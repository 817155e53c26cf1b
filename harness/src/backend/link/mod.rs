//! The byte links a bridge is reached over: the [`Link`] trait, the
//! [`LinkDriver`] of each kind in a file of its own (a serial port in
//! `serial.rs`, raw TCP in `tcp.rs`, telnet with RFC 2217 in
//! `rfc2217.rs`, a labgrid place's port in `labgrid.rs`), and
//! [`DRIVERS`], the one list of them: as probe-rs lists its probe drivers.
//! A driver says what its addresses look like, reads them, and opens its
//! link; the `--target` help, the usage errors and `backend::open` all go
//! through the list. The bridge protocol on top of any link is
//! `backend::bridged`'s `BridgeTarget`.
//!
//! A new link kind is a file here with its [`Link`] and its driver, and
//! one line in [`DRIVERS`].

pub mod labgrid;
pub mod lease;
pub mod rfc2217;
pub mod serial;
pub mod tcp;

use crate::stop::StopRequest;
use std::fmt;
use std::io;
use std::time::Duration as WallDuration;

/// Every kind of link, in the order the help and the usage errors list
/// them. The first whose [`LinkDriver::prefix`] an address starts with
/// reads it.
pub static DRIVERS: [&dyn LinkDriver; 4] = [
    &serial::DRIVER,
    &tcp::DRIVER,
    &rfc2217::DRIVER,
    &labgrid::DRIVER,
];

/// The driver whose prefix `address` starts with.
pub fn driver_for(address: &str) -> Option<&'static dyn LinkDriver> {
    DRIVERS
        .iter()
        .copied()
        .find(|d| address.starts_with(d.prefix()))
}

/// One kind of link: its addresses and how one opens.
pub trait LinkDriver: Sync + fmt::Debug {
    /// What an address of this kind starts with: `tcp://`.
    fn prefix(&self) -> &'static str;
    /// The address form, as the help and the usage errors write it:
    /// `tcp://<host>:<port>`.
    fn form(&self) -> &'static str;
    /// What it reaches, for the `--target` help: a phrase after the form.
    fn about(&self) -> &'static str;
    /// The reply padding asked for when a target gives none (`pad=`). A
    /// serial server on the way (ser2net, labgrid's exporter) holds a
    /// partly filled 64-byte buffer for a millisecond or more; a reply
    /// padded to fill it goes at once (`docs/bridge-protocol.md`, LINK).
    /// On a serial port the padding would only cost time.
    fn default_pad(&self) -> u16;
    /// Whether `address` (which starts with [`Self::prefix`]) reads:
    /// `Err` with a hint to add to the form when it does not.
    fn check(&self, address: &str) -> Result<(), &'static str>;
    /// Opens the link at `address` (one [`Self::check`] passed), given up
    /// once `how.stop` is asked for. The error names the link and says why.
    fn open(&self, address: &str, how: &LinkOpen) -> io::Result<Box<dyn Link>>;
}

/// How a link is opened.
#[derive(Debug, Clone, Default)]
pub struct LinkOpen {
    /// Asked for: the open is given up.
    pub stop: StopRequest,
    /// A link that acquires a place (`labgrid:<place>,acquire`) may take
    /// a lock a dead ppmc left (`--steal-stale`; `lease.rs`).
    pub steal_stale: bool,
}

/// An error for an address that does not read, from a driver's `open`
/// (which [`LinkDriver::check`] guards).
pub(crate) fn bad_address(driver: &dyn LinkDriver, address: &str) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("bad target `{address}`: write {}", driver.form()),
    )
}

/// A byte link to a bridge.
pub trait Link: Send + fmt::Debug {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()>;
    /// Reads what arrives within `timeout`; `Ok(0)` when nothing did.
    fn recv(&mut self, buf: &mut [u8], timeout: WallDuration) -> io::Result<usize>;
    /// Opens the link again after it failed.
    fn reopen(&mut self) -> io::Result<()>;
    /// Lets go of the connection while the far end's power is cycled (a
    /// USB port held open across it may come back under another name);
    /// [`Self::restart`] opens it again. The default keeps it.
    fn close(&mut self) {}
    /// Opens the link anew after the far end lost its power: where a link
    /// is found again (a serial server that moved, a port enumerated
    /// again) it is looked up again. The default reopens.
    fn restart(&mut self) -> io::Result<()> {
        self.reopen()
    }
    /// What to call the link in messages: `serial:/dev/ttyACM0`.
    fn name(&self) -> String;
    /// The serial number of the device at the link's far end, where the
    /// operating system knows it (a USB serial port's iSerial); `None`
    /// across a network.
    fn device_serial(&self) -> Option<String> {
        None
    }
}

impl Link for Box<dyn Link> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        (**self).send(bytes)
    }

    fn recv(&mut self, buf: &mut [u8], timeout: WallDuration) -> io::Result<usize> {
        (**self).recv(buf, timeout)
    }

    fn reopen(&mut self) -> io::Result<()> {
        (**self).reopen()
    }

    fn close(&mut self) {
        (**self).close()
    }

    fn restart(&mut self) -> io::Result<()> {
        (**self).restart()
    }

    fn name(&self) -> String {
        (**self).name()
    }

    fn device_serial(&self) -> Option<String> {
        (**self).device_serial()
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

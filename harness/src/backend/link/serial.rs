//! A serial port (USB CDC, a UART, a pseudo-terminal) as a [`Link`], and
//! its driver: `serial:<path>[,baud=N]` addresses.

use super::{bad_address, timed_out, Link, LinkDriver};
use std::fmt;
use std::io::{self, Read, Write};
use std::time::Duration as WallDuration;

/// A serial port (USB CDC, UART, or a pseudo-terminal) through `serialport`.
pub struct SerialLink {
    path: String,
    baud: u32,
    port: Option<Box<dyn serialport::SerialPort>>,
}

impl fmt::Debug for SerialLink {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SerialLink")
            .field("path", &self.path)
            .field("baud", &self.baud)
            .finish()
    }
}

/// The driver of `serial:<path>[,baud=N]`.
#[derive(Debug)]
pub struct SerialDriver;

pub(super) static DRIVER: SerialDriver = SerialDriver;

impl LinkDriver for SerialDriver {
    fn prefix(&self) -> &'static str {
        "serial:"
    }

    fn form(&self) -> &'static str {
        "serial:<path>[,baud=N]"
    }

    fn about(&self) -> &'static str {
        "a board, or `ppmc bridge-sim`, behind the serial bus bridge"
    }

    fn default_pad(&self) -> u16 {
        0
    }

    fn check(&self, address: &str) -> Result<(), &'static str> {
        parse_serial_address(address).map(drop).ok_or("")
    }

    fn open(&self, address: &str, _how: &super::LinkOpen) -> io::Result<Box<dyn Link>> {
        let (path, baud) =
            parse_serial_address(address).ok_or_else(|| bad_address(self, address))?;
        Ok(Box::new(SerialLink::open(&path, baud)?))
    }
}

impl SerialLink {
    /// Opens the port at `path`; the error names it and says whether it
    /// is missing or held by another program.
    pub fn open(path: &str, baud: u32) -> io::Result<SerialLink> {
        let mut link = SerialLink {
            path: path.to_string(),
            baud,
            port: None,
        };
        link.reopen().map_err(|e| open_error(path, e))?;
        Ok(link)
    }

    /// The USB serial number of the device behind `path`, as Linux's sysfs
    /// gives it (`/sys/class/tty/<tty>/device/../serial`); `None` for a port
    /// that is not USB, or elsewhere.
    pub fn usb_serial(path: &str) -> Option<String> {
        let dev = std::fs::canonicalize(path).ok()?;
        let tty = dev.file_name()?.to_str()?;
        let iface = std::fs::canonicalize(format!("/sys/class/tty/{tty}/device")).ok()?;
        let serial = std::fs::read_to_string(iface.parent()?.join("serial")).ok()?;
        let serial = serial.trim();
        (!serial.is_empty() && serial.len() <= 128).then(|| serial.to_string())
    }

    fn port(&mut self) -> io::Result<&mut Box<dyn serialport::SerialPort>> {
        self.port
            .as_mut()
            .ok_or_else(|| io::Error::new(io::ErrorKind::NotConnected, "port closed"))
    }
}

/// `e`, from opening the port at `path`, in words that name the port and
/// say what to check.
fn open_error(path: &str, e: io::Error) -> io::Error {
    let busy = matches!(
        e.kind(),
        io::ErrorKind::PermissionDenied | io::ErrorKind::ResourceBusy
    ) || e.raw_os_error() == Some(16);
    // ENOTTY: a file or device without a terminal's settings (serialport
    // words it as nix does, "Not a typewriter", and drops the number).
    let not_a_tty = e.raw_os_error() == Some(25)
        || ["typewriter", "Inappropriate ioctl"]
            .iter()
            .any(|w| e.to_string().contains(w));
    let message = if e.kind() == io::ErrorKind::NotFound {
        format!("{path}: no such serial port (is the bridge plugged in?)")
    } else if not_a_tty {
        format!(
            "{path}: not a serial port (no terminal settings: {e}); give the bridge's port, such as /dev/ttyACM0, or the pty ppmc bridge-sim prints"
        )
    } else if busy {
        format!("{path}: port busy or not accessible ({e}); is another program using it?")
    } else {
        format!("{path}: {e}")
    };
    io::Error::new(e.kind(), message)
}

impl Link for SerialLink {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        let port = self.port()?;
        port.write_all(bytes)?;
        port.flush()
    }

    fn recv(&mut self, buf: &mut [u8], timeout: WallDuration) -> io::Result<usize> {
        let port = self.port()?;
        port.set_timeout(timeout.max(WallDuration::from_millis(1)))
            .map_err(io::Error::from)?;
        match port.read(buf) {
            Ok(0) => Err(io::Error::new(io::ErrorKind::UnexpectedEof, "link closed")),
            Ok(n) => Ok(n),
            Err(e) if timed_out(&e) => Ok(0),
            Err(e) => Err(e),
        }
    }

    fn close(&mut self) {
        self.port = None;
    }

    fn reopen(&mut self) -> io::Result<()> {
        self.port = None;
        let port = serialport::new(&self.path, self.baud)
            .timeout(WallDuration::from_millis(100))
            .open()
            .map_err(|e| match e.kind {
                // serialport reports EBUSY (another program holds the
                // port's exclusive lock) as `NoDevice`, which its io::Error
                // conversion turns into NotFound: keep it apart from a
                // port that is not there.
                serialport::ErrorKind::NoDevice => {
                    io::Error::new(io::ErrorKind::ResourceBusy, e.description)
                }
                _ => io::Error::from(e),
            })?;
        self.port = Some(port);
        Ok(())
    }

    fn name(&self) -> String {
        format!("serial:{}", self.path)
    }

    fn device_serial(&self) -> Option<String> {
        SerialLink::usb_serial(&self.path)
    }
}

/// Parses `serial:<path>[,baud=N]`.
pub fn parse_serial_address(spec: &str) -> Option<(String, u32)> {
    let rest = spec.strip_prefix("serial:")?;
    let mut parts = rest.split(',');
    let path = parts.next().filter(|p| !p.is_empty())?.to_string();
    let mut baud = 115_200;
    for p in parts {
        let (k, v) = p.split_once('=')?;
        match k {
            "baud" => baud = v.parse().ok().filter(|b| *b > 0)?,
            _ => return None,
        }
    }
    Some((path, baud))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_busy_or_forbidden_port_says_another_program_may_hold_it() {
        // (A real second open cannot be refused here: CI runs as root, and
        // root passes the exclusive lock serialport takes on the port.)
        for e in [
            io::Error::from_raw_os_error(16), // EBUSY
            io::Error::new(io::ErrorKind::ResourceBusy, "busy"),
            io::Error::new(io::ErrorKind::PermissionDenied, "denied"),
        ] {
            let msg = open_error("/dev/ttyACM0", e).to_string();
            assert!(msg.starts_with("/dev/ttyACM0: port busy"), "{msg}");
            assert!(msg.contains("another program"), "{msg}");
        }
        let missing = open_error("/dev/ttyACM9", io::ErrorKind::NotFound.into());
        assert!(missing.to_string().contains("no such serial port"));
    }

    /// Issue 42: `serial:/dev/null` said only "Not a typewriter".
    #[cfg(unix)]
    #[test]
    fn a_file_that_is_no_terminal_is_said_not_a_serial_port() {
        let e = match SerialLink::open("/dev/null", 115_200) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("/dev/null opened as a serial port"),
        };
        assert!(
            e.starts_with("/dev/null: not a serial port (no terminal settings:"),
            "{e}"
        );
        assert!(e.contains("/dev/ttyACM0"), "{e}");
    }

    #[test]
    fn specs_parse() {
        assert_eq!(
            parse_serial_address("serial:/dev/ttyACM0"),
            Some(("/dev/ttyACM0".into(), 115_200))
        );
        assert_eq!(
            parse_serial_address("serial:/dev/pts/3,baud=921600"),
            Some(("/dev/pts/3".into(), 921_600))
        );
        assert_eq!(parse_serial_address("serial:"), None);
        assert_eq!(parse_serial_address("serial:/x,speed=1"), None);
        assert_eq!(parse_serial_address("emu"), None);
    }
}

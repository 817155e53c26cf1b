//! `labgrid:<place>`: the bridge's serial port of a labgrid place.
//!
//! The place is acquired by the user (or the CI job) with labgrid's own
//! client; ppmc only asks where its serial port is. It runs
//! `labgrid-client -c ENV -p PLACE export --format json FILE` with an
//! environment that binds a `SerialDriver` to the place. The client writes
//! the port's host, port, protocol and speed to FILE and then keeps running,
//! because when labgrid reaches the exporter through an SSH proxy
//! (`LG_PROXY`) the address it wrote is a forwarding that lives as long as
//! the client. The link keeps the client until it is dropped, then stops it.
//!
//! With `,acquire` ppmc acquires the place itself first, and lets go of it
//! on every way out (`lease.rs`: a dead job's lock is told from a live
//! one's, and `--steal-stale` takes it).
//!
//! The coordinator is the client's business: `LG_COORDINATOR` (and
//! `LG_PROXY`) in the environment reach it unchanged. The client program is
//! `labgrid-client` on the `PATH`, or `PPMC_LABGRID_CLIENT`.

use super::lease::{client_program, Lease};
use super::rfc2217::Rfc2217Link;
use super::serial::SerialLink;
use super::tcp::TcpLink;
use super::{bad_address, Link, LinkDriver, LinkOpen};
use crate::stop::StopRequest;
use std::fmt;
use std::io::{self, BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration as WallDuration, Instant as WallInstant};

/// How long the client may take to say where the port is: it starts
/// Python, reaches the coordinator and, through a proxy, opens SSH.
const EXPORT_TIMEOUT: WallDuration = WallDuration::from_secs(60);

/// The place (and, with `,port=NAME`, which of its serial ports) of a
/// `labgrid:<place>[,port=NAME][,acquire]` target.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Place {
    pub name: String,
    pub port: Option<String>,
    /// `,acquire`: ppmc acquires the place, and releases it at the end.
    pub acquire: bool,
}

/// The driver of `labgrid:<place>[,port=NAME][,acquire]`.
#[derive(Debug)]
pub struct LabgridDriver;

pub(super) static DRIVER: LabgridDriver = LabgridDriver;

impl LinkDriver for LabgridDriver {
    fn prefix(&self) -> &'static str {
        "labgrid:"
    }

    fn form(&self) -> &'static str {
        "labgrid:<place>[,port=NAME][,acquire]"
    }

    fn about(&self) -> &'static str {
        "the serial port of a labgrid place you have acquired (`,acquire`: ppmc acquires it, and releases it however the run ends)"
    }

    fn default_pad(&self) -> u16 {
        64
    }

    fn check(&self, address: &str) -> Result<(), &'static str> {
        parse_labgrid(address).map(drop).ok_or("")
    }

    fn open(&self, address: &str, how: &LinkOpen) -> io::Result<Box<dyn Link>> {
        let place = parse_labgrid(address).ok_or_else(|| bad_address(self, address))?;
        let lease = match place.acquire {
            true => Some(Lease::acquire(&place.name, how.steal_stale)?),
            false => None,
        };
        let mut link = LabgridLink::open_until(place, how.stop.clone())?;
        link._lease = lease;
        Ok(Box::new(link))
    }
}

/// Reads `labgrid:<place>[,port=NAME][,acquire]`. A place name is what
/// labgrid accepts: letters, digits, `-`, `_`, `.`.
pub fn parse_labgrid(spec: &str) -> Option<Place> {
    let rest = spec.strip_prefix("labgrid:")?;
    let mut parts = rest.split(',');
    let ok = |s: &str| {
        !s.is_empty()
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
    };
    let name = parts.next().filter(|n| ok(n))?.to_string();
    let mut port = None;
    let mut acquire = false;
    for p in parts {
        match p.split_once('=') {
            Some(("port", v)) if ok(v) => port = Some(v.to_string()),
            None if p == "acquire" => acquire = true,
            _ => return None,
        }
    }
    Some(Place {
        name,
        port,
        acquire,
    })
}

/// The running `labgrid-client export`, stopped when dropped.
struct Export {
    child: Child,
    /// Holds the environment and the export file.
    _dir: tempfile::TempDir,
}

impl Drop for Export {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            // SIGTERM lets the client end its SSH forwardings; the std
            // library only sends SIGKILL.
            let _ = Command::new("kill")
                .args(["-TERM", &self.child.id().to_string()])
                .stderr(Stdio::null())
                .status();
            let deadline = WallInstant::now() + WallDuration::from_secs(5);
            while WallInstant::now() < deadline {
                if !matches!(self.child.try_wait(), Ok(None)) {
                    return;
                }
                std::thread::sleep(WallDuration::from_millis(20));
            }
            let _ = self.child.kill();
        }
        let _ = self.child.wait();
    }
}

/// Where labgrid says the place's serial port is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Exported {
    /// `None` for a port local to this machine (`port` is then its path).
    pub host: Option<String>,
    pub port: String,
    /// `rfc2217` or `raw` (network ports only).
    pub protocol: Option<String>,
    pub speed: u32,
}

/// Reads the `export --format json` file: `LG__<DRIVER>_HOST`, `_PORT`,
/// `_PROTOCOL`, `_SPEED`, for the one serial driver of the environment.
pub fn parse_export(json: &str) -> Result<Exported, String> {
    let v: serde_json::Value =
        serde_json::from_str(json).map_err(|e| format!("its export is not JSON ({e})"))?;
    let map = v
        .as_object()
        .ok_or("its export is not a JSON object of variables")?;
    let get = |suffix: &str| {
        map.iter()
            .find(|(k, _)| k.starts_with("LG__") && k.ends_with(suffix))
            .and_then(|(_, v)| v.as_str())
            .map(str::to_string)
    };
    let port = get("_PORT").ok_or("its export names no serial port (no LG__*_PORT)")?;
    let speed = match get("_SPEED") {
        Some(s) => s
            .parse::<u32>()
            .ok()
            .filter(|s| *s > 0)
            .ok_or_else(|| format!("its export gives the speed `{s}`"))?,
        None => 115_200,
    };
    Ok(Exported {
        host: get("_HOST"),
        port,
        protocol: get("_PROTOCOL"),
        speed,
    })
}

/// The environment labgrid's client is given: the place, and a serial
/// driver bound to its port. JSON is YAML, and quotes the names safely.
fn environment(place: &Place) -> String {
    let mut driver = serde_json::json!({});
    if let Some(port) = &place.port {
        driver = serde_json::json!({ "bindings": { "port": port } });
    }
    serde_json::json!({
        "targets": {
            place.name.clone(): {
                "resources": { "RemotePlace": { "name": place.name } },
                "drivers": { "SerialDriver": driver },
            }
        }
    })
    .to_string()
}

/// The serial port of a labgrid place, reached the way labgrid says.
pub struct LabgridLink {
    place: Place,
    inner: Box<dyn Link>,
    /// Declared after `inner`: the connection closes before the client
    /// (and any forwarding it keeps) stops.
    _export: Export,
    /// The place, when ppmc acquired it: released last.
    _lease: Option<Lease>,
    stop: StopRequest,
}

impl fmt::Debug for LabgridLink {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("LabgridLink")
            .field("place", &self.place)
            .field("inner", &self.inner)
            .finish()
    }
}

impl LabgridLink {
    /// Asks labgrid where `place`'s serial port is and connects to it.
    /// Every failure is the infrastructure's, and names the place.
    pub fn open(place: Place) -> io::Result<LabgridLink> {
        Self::open_until(place, StopRequest::default())
    }

    /// [`Self::open`], given up (the client's export, a connection
    /// attempt) once `stop` is asked for.
    pub fn open_until(place: Place, stop: StopRequest) -> io::Result<LabgridLink> {
        let who = format!("labgrid:{}", place.name);
        let (export, found) =
            export(&place, &stop).map_err(|e| io::Error::other(format!("{who}: {e}")))?;
        let inner: Box<dyn Link> = match (&found.host, found.protocol.as_deref()) {
            (None, _) => Box::new(SerialLink::open(&found.port, found.speed)?),
            (Some(host), proto) => {
                let host = if host.contains(':') && !host.starts_with('[') {
                    format!("[{host}]")
                } else {
                    host.clone()
                };
                let addr = format!("{host}:{}", found.port);
                match proto {
                    Some("rfc2217") => Box::new(Rfc2217Link::open_until(&addr, found.speed, stop.clone())?),
                    Some("raw") => Box::new(TcpLink::open_until(&addr, stop.clone())?),
                    other => {
                        return Err(io::Error::new(
                            io::ErrorKind::Unsupported,
                            format!(
                                "{who}: labgrid serves the port as `{}`, which ppmc does not speak (rfc2217 or raw)",
                                other.unwrap_or("(no protocol)")
                            ),
                        ))
                    }
                }
            }
        };
        Ok(LabgridLink {
            place,
            inner,
            _export: export,
            _lease: None,
            stop,
        })
    }
}

/// Runs the client's export and waits for the file it writes.
fn export(place: &Place, stop: &StopRequest) -> Result<(Export, Exported), String> {
    let program = client_program();
    let dir = tempfile::Builder::new()
        .prefix("ppmc-labgrid-")
        .tempdir()
        .map_err(|e| format!("cannot make a temporary directory: {e}"))?;
    let env_path = dir.path().join("env.yaml");
    let out_path = dir.path().join("export.json");
    std::fs::write(&env_path, environment(place))
        .map_err(|e| format!("cannot write {}: {e}", env_path.display()))?;
    let mut child = Command::new(&program)
        .arg("-c")
        .arg(&env_path)
        .args(["-p", &place.name, "export", "--format", "json"])
        .arg(&out_path)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| match e.kind() {
            io::ErrorKind::NotFound => format!(
                "`{program}` not found (install labgrid, `pip install labgrid`, or set PPMC_LABGRID_CLIENT)"
            ),
            _ => format!("cannot run `{program}`: {e}"),
        })?;
    let stderr = child.stderr.take();
    let mut export = Export { child, _dir: dir };
    // The client's messages, line by line; the thread drains them for as
    // long as the client runs, so it never blocks on a full pipe.
    let (tx, rx) = mpsc::channel();
    if let Some(stderr) = stderr {
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    // Nobody listens any more: keep draining.
                    continue;
                }
            }
        });
    }
    let deadline = WallInstant::now() + EXPORT_TIMEOUT;
    let mut said = Vec::new();
    loop {
        if stop.requested() {
            return Err("interrupted by a stop request while labgrid exported the port".into());
        }
        let left = deadline.saturating_duration_since(WallInstant::now());
        match rx.recv_timeout(left.min(StopRequest::SLICE)) {
            Ok(line) if line.starts_with("Exported to") => break,
            Ok(line) => said.push(line),
            Err(mpsc::RecvTimeoutError::Timeout) if !left.is_zero() => {}
            Err(mpsc::RecvTimeoutError::Timeout) => {
                return Err(format!(
                    "`{program} export` said nothing of the place's port within {} s{}",
                    EXPORT_TIMEOUT.as_secs(),
                    last_words(&said)
                ))
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                let status = export.child.wait().ok();
                let acquire = if said.iter().any(|l| l.contains("not acquired")) {
                    format!(
                        "; acquire it first (`labgrid-client -p {} acquire`)",
                        place.name
                    )
                } else {
                    String::new()
                };
                return Err(format!(
                    "`{program} export` ended{}{}{acquire}",
                    status.map_or(String::new(), |s| format!(" ({s})")),
                    last_words(&said)
                ));
            }
        }
    }
    let text = std::fs::read_to_string(&out_path)
        .map_err(|e| format!("cannot read labgrid's export {}: {e}", out_path.display()))?;
    let found = parse_export(&text).map_err(|e| format!("`{program}`: {e}"))?;
    Ok((export, found))
}

/// The client's last lines of complaint, for an error message.
fn last_words(said: &[String]) -> String {
    let tail: Vec<&str> = said
        .iter()
        .map(|l| l.trim())
        .filter(|l| !l.is_empty() && !l.starts_with("Traceback") && !l.starts_with("File "))
        .collect();
    match tail.len() {
        0 => String::new(),
        n => format!(": {}", tail[n.saturating_sub(2)..].join(" / ")),
    }
}

impl Link for LabgridLink {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.inner.send(bytes)
    }

    fn recv(&mut self, buf: &mut [u8], timeout: WallDuration) -> io::Result<usize> {
        self.inner.recv(buf, timeout)
    }

    fn reopen(&mut self) -> io::Result<()> {
        self.inner.reopen()
    }

    /// The connection closes (a serial server serves one client at a
    /// time); the export and the lease stay.
    fn close(&mut self) {
        self.inner = Box::new(Closed(self.inner.name()));
    }

    /// Asks labgrid again where the port is: after a power cycle the
    /// exporter may serve it anew, on another port. The lease is kept.
    fn restart(&mut self) -> io::Result<()> {
        self.close();
        let fresh = LabgridLink::open_until(self.place.clone(), self.stop.clone())?;
        self.inner = fresh.inner;
        self._export = fresh._export;
        Ok(())
    }

    fn name(&self) -> String {
        format!("labgrid:{} ({})", self.place.name, self.inner.name())
    }
}

/// A connection closed while another is opened in its place.
#[derive(Debug)]
struct Closed(String);

impl Link for Closed {
    fn send(&mut self, _: &[u8]) -> io::Result<()> {
        Err(io::ErrorKind::NotConnected.into())
    }

    fn recv(&mut self, _: &mut [u8], _: WallDuration) -> io::Result<usize> {
        Err(io::ErrorKind::NotConnected.into())
    }

    fn reopen(&mut self) -> io::Result<()> {
        Err(io::ErrorKind::NotConnected.into())
    }

    fn name(&self) -> String {
        self.0.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn places_and_ports_are_read_and_bad_ones_refused() {
        assert_eq!(
            parse_labgrid("labgrid:board-1"),
            Some(Place {
                name: "board-1".into(),
                port: None,
                acquire: false,
            })
        );
        assert_eq!(
            parse_labgrid("labgrid:rig.2,port=bridge"),
            Some(Place {
                name: "rig.2".into(),
                port: Some("bridge".into()),
                acquire: false,
            })
        );
        assert!(parse_labgrid("labgrid:rig1,acquire,port=b").is_some_and(|p| p.acquire));
        for bad in [
            "labgrid:",
            "labgrid:a b",
            "labgrid:a,port=",
            "labgrid:a,speed=9",
            "labgrid:a,acquire=yes",
            "serial:x",
        ] {
            assert_eq!(parse_labgrid(bad), None, "{bad}");
        }
    }

    #[test]
    fn the_export_gives_host_port_protocol_and_speed() {
        let json = r#"{"LG__SERIALDRIVER_HOST": "127.0.0.1", "LG__SERIALDRIVER_PORT": "41234",
            "LG__SERIALDRIVER_PROTOCOL": "rfc2217", "LG__SERIALDRIVER_SPEED": "115200",
            "LG__CLIENT_PID": "77"}"#;
        assert_eq!(
            parse_export(json),
            Ok(Exported {
                host: Some("127.0.0.1".into()),
                port: "41234".into(),
                protocol: Some("rfc2217".into()),
                speed: 115_200,
            })
        );
        let err = parse_export(r#"{"LG__CLIENT_PID": "77"}"#).expect_err("refused");
        assert!(err.contains("names no serial port"), "{err}");
        let err =
            parse_export(r#"{"LG__X_PORT": "1", "LG__X_SPEED": "fast"}"#).expect_err("refused");
        assert!(err.contains("`fast`"), "{err}");
        assert!(parse_export("not json").is_err());
    }

    #[test]
    fn the_environment_is_yaml_that_quotes_the_place() {
        let env = environment(&Place {
            name: "b1".into(),
            port: Some("bridge".into()),
            acquire: true,
        });
        let v: serde_json::Value = serde_json::from_str(&env).expect("JSON");
        assert_eq!(v["targets"]["b1"]["resources"]["RemotePlace"]["name"], "b1");
        assert_eq!(
            v["targets"]["b1"]["drivers"]["SerialDriver"]["bindings"]["port"],
            "bridge"
        );
    }
}

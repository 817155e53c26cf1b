//! A real PostgreSQL server for the store's tests: Debian's, a throwaway
//! cluster (initdb in a temporary folder, its own port on 127.0.0.1,
//! trust authentication for the user `ppmc`), stopped when dropped.
//!
//! `.ci/run` starts one for the whole test step and names it in
//! `PPMC_TEST_POSTGRES` (`postgres://ppmc@127.0.0.1:PORT`); each test then
//! makes a database of its own in it. Without it, a test starts its own
//! cluster. Without PostgreSQL installed, [`Db::new`] gives `None` and the
//! test says it was skipped, except under CI (`CI` set), where it fails:
//! CI installs it.

use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

/// A throwaway cluster, stopped when dropped.
#[derive(Debug)]
pub struct Cluster {
    dir: tempfile::TempDir,
    bin: PathBuf,
    pub port: u16,
    /// With TLS: the authority's certificate (PEM) that signed the
    /// server's, issued to 127.0.0.1.
    pub ca: Option<PathBuf>,
}

/// One database of its own, in the CI's server or in a cluster of its
/// own.
#[derive(Debug)]
pub struct Db {
    /// `postgres://ppmc@127.0.0.1:PORT/NAME`
    pub url: String,
    _cluster: Option<Cluster>,
}

/// Debian's PostgreSQL programs: `PPMC_PG_BIN`, else the newest under
/// /usr/lib/postgresql.
pub fn bin_dir() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("PPMC_PG_BIN") {
        return Some(PathBuf::from(dir));
    }
    let mut found: Vec<PathBuf> = std::fs::read_dir("/usr/lib/postgresql")
        .ok()?
        .filter_map(|e| e.ok())
        .map(|e| e.path().join("bin"))
        .filter(|b| b.join("initdb").exists())
        .collect();
    found.sort_by_key(|p| {
        p.parent()
            .and_then(|v| v.file_name())
            .and_then(|v| v.to_str())
            .and_then(|v| v.parse::<u32>().ok())
    });
    found.pop()
}

/// The server is missing: `None` where a test may be skipped, a failure
/// under CI.
fn missing(why: &str) -> Option<Db> {
    if std::env::var_os("CI").is_some() {
        panic!("no PostgreSQL for the store's tests: {why} (.ci/run installs Debian's)");
    }
    eprintln!("skipped: no PostgreSQL here ({why}); apt install postgresql to run this test");
    None
}

impl Db {
    /// A new, empty database.
    pub fn new() -> Option<Db> {
        if let Ok(server) = std::env::var("PPMC_TEST_POSTGRES") {
            return Some(Db {
                url: create_database(server.trim_end_matches('/')),
                _cluster: None,
            });
        }
        let Some(bin) = bin_dir() else {
            return missing("no initdb under /usr/lib/postgresql");
        };
        let cluster = Cluster::start(&bin, false);
        Some(Db {
            url: create_database(&cluster.url()),
            _cluster: Some(cluster),
        })
    }
}

/// A database of a name no other test has, in `server`.
fn create_database(server: &str) -> String {
    static N: AtomicU32 = AtomicU32::new(0);
    let name = format!(
        "ppmc_test_{}_{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    );
    let mut c = postgres::Client::connect(&format!("{server}/postgres"), postgres::NoTls)
        .unwrap_or_else(|e| panic!("connecting to {server}: {e}"));
    c.batch_execute(&format!("CREATE DATABASE {name}"))
        .expect("a database for the test");
    format!("{server}/{name}")
}

/// Runs `cmd` as the user `postgres` when this is root (initdb and the
/// server refuse root).
fn as_server_user(bin: &Path, program: &str) -> Command {
    let uid = std::fs::metadata("/proc/self")
        .map(|m| std::os::unix::fs::MetadataExt::uid(&m))
        .unwrap_or(1);
    if uid == 0 {
        let mut c = Command::new("runuser");
        c.args(["-u", "postgres", "--"]).arg(bin.join(program));
        c
    } else {
        Command::new(bin.join(program))
    }
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

impl Cluster {
    /// initdb, then the server on a free port of 127.0.0.1 (TLS on, with a
    /// certificate of its own authority, when `tls`).
    pub fn start(bin: &Path, tls: bool) -> Cluster {
        let dir = tempfile::Builder::new()
            .prefix("ppmc-pg-")
            .tempdir()
            .expect("a folder for the cluster");
        let root = std::fs::metadata("/proc/self")
            .map(|m| std::os::unix::fs::MetadataExt::uid(&m) == 0)
            .unwrap_or(false);
        if root {
            let pg = Command::new("id")
                .args(["-u", "postgres"])
                .output()
                .expect("id");
            let uid: u32 = String::from_utf8_lossy(&pg.stdout)
                .trim()
                .parse()
                .expect("the user postgres (Debian's package makes it)");
            std::os::unix::fs::chown(dir.path(), Some(uid), None).expect("chown");
        }
        let data = dir.path().join("data");
        let out = as_server_user(bin, "initdb")
            .args([
                "-U",
                "ppmc",
                "--auth=trust",
                "--no-sync",
                "-E",
                "UTF8",
                "-D",
            ])
            .arg(&data)
            .stdout(Stdio::null())
            .output()
            .expect("initdb");
        assert!(
            out.status.success(),
            "initdb: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let mut ca = None;
        let mut conf = String::from(
            "fsync = off\nsynchronous_commit = off\nfull_page_writes = off\nmax_connections = 100\n",
        );
        if tls {
            ca = Some(make_certificates(&data, root));
            conf.push_str("ssl = on\nssl_cert_file = 'server.crt'\nssl_key_file = 'server.key'\n");
        }
        let auto = data.join("postgresql.auto.conf");
        let mut text = std::fs::read_to_string(&auto).unwrap_or_default();
        text.push_str(&conf);
        std::fs::write(&auto, text).expect("the cluster's settings");
        let port = free_port();
        let out = as_server_user(bin, "pg_ctl")
            .args(["-D"])
            .arg(&data)
            .args(["-w", "-t", "60", "-l"])
            .arg(dir.path().join("server.log"))
            .arg("-o")
            .arg(format!(
                "-h 127.0.0.1 -p {port} -k {}",
                dir.path().display()
            ))
            .arg("start")
            .stdout(Stdio::null())
            .output()
            .expect("pg_ctl start");
        let log = std::fs::read_to_string(dir.path().join("server.log")).unwrap_or_default();
        assert!(
            out.status.success(),
            "pg_ctl start: {}{log}",
            String::from_utf8_lossy(&out.stderr)
        );
        let cluster = Cluster {
            dir,
            bin: bin.to_path_buf(),
            port,
            ca,
        };
        cluster.wait_ready();
        cluster
    }

    /// The server, as a URL with no database.
    pub fn url(&self) -> String {
        format!("postgres://ppmc@127.0.0.1:{}", self.port)
    }

    fn wait_ready(&self) {
        let end = Instant::now() + Duration::from_secs(60);
        loop {
            let url = format!("{}/postgres", self.url());
            if postgres::Client::connect(&url, postgres::NoTls).is_ok() {
                return;
            }
            assert!(Instant::now() < end, "the cluster did not take connections");
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// Stops the server at once (its data is thrown away anyway).
    pub fn stop(&self) {
        let _ = as_server_user(&self.bin, "pg_ctl")
            .args(["-D"])
            .arg(self.dir.path().join("data"))
            .args(["-m", "immediate", "-w", "stop"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status();
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        self.stop();
    }
}

/// An authority, and a server certificate it signed for 127.0.0.1, made
/// by the openssl command; the server's key readable by the server only.
fn make_certificates(data: &Path, root: bool) -> PathBuf {
    let dir = data.parent().expect("the cluster's folder");
    let run = |args: &[&str]| {
        let out = Command::new("openssl")
            .args(args)
            .current_dir(dir)
            .output()
            .expect("openssl");
        assert!(
            out.status.success(),
            "openssl {args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    run(&[
        "req",
        "-x509",
        "-newkey",
        "rsa:2048",
        "-nodes",
        "-days",
        "2",
        "-subj",
        "/CN=ppmc test CA",
        "-keyout",
        "ca.key",
        "-out",
        "ca.crt",
    ]);
    run(&[
        "req",
        "-newkey",
        "rsa:2048",
        "-nodes",
        "-subj",
        "/CN=127.0.0.1",
        "-keyout",
        "server.key",
        "-out",
        "server.csr",
    ]);
    std::fs::write(dir.join("san.ext"), "subjectAltName=IP:127.0.0.1\n").expect("ext");
    run(&[
        "x509",
        "-req",
        "-in",
        "server.csr",
        "-CA",
        "ca.crt",
        "-CAkey",
        "ca.key",
        "-CAcreateserial",
        "-days",
        "2",
        "-extfile",
        "san.ext",
        "-out",
        "server.crt",
    ]);
    for f in ["server.crt", "server.key"] {
        std::fs::copy(dir.join(f), data.join(f)).expect("into the data folder");
    }
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(
        data.join("server.key"),
        std::fs::Permissions::from_mode(0o600),
    )
    .expect("chmod");
    if root {
        let _ = Command::new("chown")
            .arg("postgres")
            .arg(data.join("server.crt"))
            .arg(data.join("server.key"))
            .status();
    }
    dir.join("ca.crt")
}

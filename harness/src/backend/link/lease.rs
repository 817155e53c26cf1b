//! A labgrid place that ppmc acquires itself (`labgrid:<place>,acquire`),
//! and lets go of on every way out: when the run ends, fails or panics (the
//! [`Lease`] is dropped), and when a third signal ends the process at once
//! ([`release_all`], from the signal thread). Only a process killed outright
//! (SIGKILL, a power cut) leaves its lock; the place then carries tags that
//! say whose it was, so that the next run can tell a dead job's lock from a
//! live one's:
//!
//! | tag | value |
//! |---|---|
//! | `ppmc_pid` | the process's id |
//! | `ppmc_host` | the machine's name |
//! | `ppmc_boot` | the machine's boot id, first 12 hex digits: a lock from before a reboot is dead |
//! | `ppmc_start` | the process's start, in clock ticks since boot (`/proc/PID/stat`): a pid used again is another process |
//! | `ppmc_since` | when it acquired the place, seconds since 1970 |
//! | `ppmc_pidns` | its PID namespace (`/proc/self/ns/pid`): a process of another container cannot be seen |
//! | `ppmc_owner` | the place's holder as labgrid names it (`host/user`) when ppmc acquired it |
//!
//! A lock is stale only when all of it says so: the place is still held by
//! the holder the tags name (not by someone who took it over since), and
//! its ppmc ran on this machine, in this PID namespace, and is gone (no
//! such process, another process under its pid, or a boot since). The run
//! then says whose it was and how old it is, and `--steal-stale` takes it
//! (`labgrid-client release-from HOLDER`, which lets go only if that holder
//! still has it, then acquires). A lock whose holder cannot be told gone
//! (another machine's, another container's, a run still going, a person's,
//! or a machine without `/proc`) is never taken.

use std::io;
use std::process::Command;
use std::sync::Mutex;
use std::time::{SystemTime, UNIX_EPOCH};

/// Places this process holds: what [`release_all`] lets go of.
static HELD: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// The tags a lease sets, and clears when it ends.
const TAGS: [&str; 7] = [
    "ppmc_pid",
    "ppmc_host",
    "ppmc_boot",
    "ppmc_start",
    "ppmc_since",
    "ppmc_pidns",
    "ppmc_owner",
];

/// How long a labgrid client may take for one step of a lease.
const CLIENT_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(30);
/// How long letting go may take when the process is about to end at once
/// (a third signal): it must end.
const LAST_GASP: std::time::Duration = std::time::Duration::from_secs(5);

/// A place acquired by this process, released when dropped.
#[derive(Debug)]
pub struct Lease {
    place: String,
    released: bool,
}

/// What `labgrid-client show` says of a place, as far as a lease needs.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Shown {
    /// `host/user`, or `None` when nobody holds it.
    pub acquired: Option<String>,
    pub tags: Vec<(String, String)>,
    /// When the place last changed, as the client prints it (local time).
    pub changed: Option<String>,
}

impl Shown {
    /// Reads the client's `show` output.
    pub fn parse(text: &str) -> Shown {
        let mut s = Shown::default();
        for line in text.lines().map(str::trim) {
            if let Some(v) = line.strip_prefix("acquired: ") {
                s.acquired = (v != "None").then(|| v.to_string());
            } else if let Some(v) = line.strip_prefix("tags: ") {
                s.tags = v
                    .split(", ")
                    .filter_map(|kv| kv.split_once('='))
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect();
            } else if let Some(v) = line.strip_prefix("changed: ") {
                s.changed = Some(v.to_string());
            }
        }
        s
    }

    fn tag(&self, key: &str) -> Option<&str> {
        self.tags
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

/// Who holds a place, in words, and whether the holder is a ppmc of this
/// machine that is gone.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Holder {
    pub words: String,
    pub stale: bool,
}

/// Judges the holder of a place `shown` says is acquired, `now` seconds
/// since 1970, on this machine (`me`).
pub fn holder(shown: &Shown, me: &Machine, now: u64, alive: impl Fn(u32, &str) -> bool) -> Holder {
    let by = shown.acquired.as_deref().unwrap_or("nobody");
    let (Some(pid), Some(host)) = (shown.tag("ppmc_pid"), shown.tag("ppmc_host")) else {
        let since = shown
            .changed
            .as_deref()
            .map_or(String::new(), |c| format!(", changed {c}"));
        return Holder {
            words: format!("acquired by {by} (not by a ppmc run{since})"),
            stale: false,
        };
    };
    let age = shown
        .tag("ppmc_since")
        .and_then(|s| s.parse::<u64>().ok())
        .map_or("for a time it did not record".into(), |t| {
            format!("for {}", human_age(now.saturating_sub(t)))
        });
    let owner = format!("acquired by {by}, by ppmc pid {pid} on {host}, {age}");
    let verdict = |words: &str, stale: bool| Holder {
        words: format!("{owner}: {words}"),
        stale,
    };
    if shown.tag("ppmc_owner") != shown.acquired.as_deref() {
        return verdict(
            "but held by someone else since (the tags are an older run's)",
            false,
        );
    }
    if host != me.host {
        return verdict("another machine's run, which this one cannot see", false);
    }
    if me.boot.is_empty() || me.pidns.is_empty() {
        return verdict("this machine cannot tell whether that run is going", false);
    }
    if shown.tag("ppmc_boot").is_some_and(|b| b != me.boot) {
        return verdict(
            "a run from before this machine's last boot, and left its lock",
            true,
        );
    }
    if shown.tag("ppmc_pidns") != Some(me.pidns.as_str()) {
        return verdict(
            "a run in another container of this machine, which this one cannot see",
            false,
        );
    }
    match (pid.parse::<u32>().ok(), shown.tag("ppmc_start")) {
        (Some(p), Some(start)) if !alive(p, start) => {
            verdict("that process is gone, and left its lock", true)
        }
        (Some(_), Some(_)) => verdict("that run is still going", false),
        _ => verdict("its tags do not say which process it was", false),
    }
}

/// `secs` as a person says it.
fn human_age(secs: u64) -> String {
    match secs {
        0..=119 => format!("{secs} s"),
        120..=7199 => format!("{} min", secs / 60),
        _ => format!("{:.1} h", secs as f64 / 3600.0),
    }
}

/// This machine and process, as a lease's tags name them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Machine {
    pub host: String,
    pub boot: String,
    /// This process's PID namespace (digits of `/proc/self/ns/pid`).
    pub pidns: String,
}

impl Machine {
    pub fn this() -> Machine {
        let read = |p: &str| std::fs::read_to_string(p).unwrap_or_default();
        let host: String = read("/proc/sys/kernel/hostname")
            .trim()
            .chars()
            .map(|c| match c {
                'a'..='z' | '0'..='9' | '_' | '-' | '.' => c,
                'A'..='Z' => c.to_ascii_lowercase(),
                _ => '_',
            })
            .collect();
        let boot: String = read("/proc/sys/kernel/random/boot_id")
            .chars()
            .filter(char::is_ascii_hexdigit)
            .take(12)
            .collect();
        let pidns: String = std::fs::read_link("/proc/self/ns/pid")
            .map(|p| {
                p.to_string_lossy()
                    .chars()
                    .filter(char::is_ascii_digit)
                    .collect()
            })
            .unwrap_or_default();
        Machine {
            host: if host.is_empty() {
                "unknown".into()
            } else {
                host
            },
            boot,
            pidns,
        }
    }
}

/// A process's start, in clock ticks since boot (field 22 of its
/// `/proc/PID/stat`), or `None` when there is no such process.
pub fn start_ticks(pid: u32) -> Option<String> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name may hold spaces: count from after its `)`.
    let rest = &stat[stat.rfind(')')? + 2..];
    rest.split(' ').nth(19).map(str::to_string)
}

/// The labgrid client: `labgrid-client` on the `PATH`, or
/// `PPMC_LABGRID_CLIENT`.
pub(crate) fn client_program() -> String {
    std::env::var("PPMC_LABGRID_CLIENT").unwrap_or_else(|_| "labgrid-client".into())
}

/// Runs the labgrid client on `place`, at most `limit`: its output.
fn client_within(place: &str, args: &[&str], limit: std::time::Duration) -> io::Result<String> {
    let program = client_program();
    let shown = format!("{program} -p {place} {}", args.join(" "));
    let mut cmd = Command::new(&program);
    cmd.args(["-p", place]).args(args);
    crate::backend::command::run_within(&mut cmd, &shown, limit)
}

fn client(place: &str, args: &[&str]) -> io::Result<String> {
    client_within(place, args, CLIENT_TIMEOUT)
}

impl Lease {
    /// Acquires `place` for this process. A place someone holds is refused
    /// with whose it is and for how long; a dead ppmc's lock (see the
    /// module) is taken only with `steal_stale`.
    pub fn acquire(place: &str, steal_stale: bool) -> io::Result<Lease> {
        let who = format!("labgrid:{place}");
        let fail = |e: io::Error| io::Error::other(format!("{who}: {e}"));
        let me = Machine::this();
        let shown = Shown::parse(&client(place, &["show"]).map_err(fail)?);
        if shown.acquired.is_some() {
            let now = SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0, |d| d.as_secs());
            let h = holder(&shown, &me, now, |pid, start| {
                start_ticks(pid).as_deref() == Some(start)
            });
            if !(h.stale && steal_stale) {
                let hint = match h.stale {
                    true => "; --steal-stale takes it",
                    false => "; wait for it, or ask its owner",
                };
                return Err(io::Error::new(
                    io::ErrorKind::ResourceBusy,
                    format!("{who}: the place is {}{hint}", h.words),
                ));
            }
            // Only if that holder still has it: a lock taken over since
            // the look above is not kicked.
            let holder = shown.acquired.as_deref().unwrap_or_default();
            client(place, &["release-from", holder]).map_err(fail)?;
            eprintln!("ppmc: {who}: took a stale lock: the place was {}", h.words);
        }
        client(place, &["acquire"]).map_err(fail)?;
        let owner = Shown::parse(&client(place, &["show"]).map_err(fail)?)
            .acquired
            .unwrap_or_default();
        let lease = Lease {
            place: place.to_string(),
            released: false,
        };
        if let Ok(mut held) = HELD.lock() {
            held.push(place.to_string());
        }
        let since = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        let pid = std::process::id();
        let tags = [
            format!("ppmc_pid={pid}"),
            format!("ppmc_host={}", me.host),
            format!("ppmc_boot={}", me.boot),
            format!("ppmc_start={}", start_ticks(pid).unwrap_or_default()),
            format!("ppmc_since={since}"),
            format!("ppmc_pidns={}", me.pidns),
            format!("ppmc_owner={owner}"),
        ];
        let mut args = vec!["set-tags"];
        args.extend(tags.iter().map(String::as_str));
        // Without its tags the lock could not be told from a live one's;
        // the lease (dropped here) lets the place go again.
        client(place, &args).map_err(fail)?;
        Ok(lease)
    }

    /// Lets go of the place (its tags cleared first); once.
    pub fn release(&mut self) {
        if std::mem::replace(&mut self.released, true) {
            return;
        }
        release_place(&self.place, CLIENT_TIMEOUT);
        if let Ok(mut held) = HELD.lock() {
            held.retain(|p| *p != self.place);
        }
    }
}

impl Drop for Lease {
    fn drop(&mut self) {
        self.release();
    }
}

fn release_place(place: &str, limit: std::time::Duration) {
    let clear: Vec<String> = TAGS.iter().map(|t| format!("{t}=")).collect();
    let mut args = vec!["set-tags"];
    args.extend(clear.iter().map(String::as_str));
    let cleared = client_within(place, &args, limit);
    if let Err(e) = cleared.and_then(|_| client_within(place, &["release"], limit)) {
        eprintln!("ppmc: labgrid:{place}: could not let go of the place: {e}");
    }
}

/// Lets go of every place this process holds: for a process about to end
/// at once (a third signal), whose leases will not be dropped.
pub fn release_all() {
    let places = HELD
        .lock()
        .map(|mut h| std::mem::take(&mut *h))
        .unwrap_or_default();
    for p in places {
        release_place(&p, LAST_GASP);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHOW: &str = "\
Place 'rig1':
  tags: ppmc_boot=0123456789ab, ppmc_host=bench-7, ppmc_owner=bench-7/ci, ppmc_pid=4242, ppmc_pidns=4026531836, ppmc_since=1000, ppmc_start=777
  matches:
    bench1/bridge/*
  acquired: bench-7/ci
  acquired resources:
  created: 2026-11-30 10:00:00.000000
  changed: 2026-11-30 10:01:00.000000
";

    fn me() -> Machine {
        Machine {
            host: "bench-7".into(),
            boot: "0123456789ab".into(),
            pidns: "4026531836".into(),
        }
    }

    /// A lock is stale only when its ppmc is of this machine and gone: by
    /// its process, or by a reboot; another machine's, or a live one's, is
    /// never taken. Each says whose and how old.
    #[test]
    fn a_lock_is_stale_only_when_its_process_is_known_gone() {
        let shown = Shown::parse(SHOW);
        assert_eq!(shown.acquired.as_deref(), Some("bench-7/ci"));
        let gone = holder(&shown, &me(), 1_300, |_, _| false);
        assert!(gone.stale);
        assert_eq!(
            gone.words,
            "acquired by bench-7/ci, by ppmc pid 4242 on bench-7, for 5 min: that process is gone, and left its lock"
        );
        let live = holder(&shown, &me(), 1_300, |pid, start| {
            pid == 4242 && start == "777"
        });
        assert!(!live.stale, "{live:?}");
        let rebooted = Machine {
            boot: "ffffffffffff".into(),
            ..me()
        };
        assert!(holder(&shown, &rebooted, 1_300, |_, _| true).stale);
        // Taken over since by someone (the tags stay): never stale.
        let mut taken = shown.clone();
        taken.acquired = Some("bench-7/alice".into());
        let h = holder(&taken, &me(), 1_300, |_, _| false);
        assert!(
            !h.stale && h.words.contains("held by someone else"),
            "{h:?}"
        );
        // Another container, or a machine that cannot tell: never stale.
        let contained = Machine {
            pidns: "4026532000".into(),
            ..me()
        };
        assert!(!holder(&shown, &contained, 1_300, |_, _| false).stale);
        let blind = Machine {
            boot: String::new(),
            ..me()
        };
        assert!(!holder(&shown, &blind, 1_300, |_, _| false).stale);
        let elsewhere = Machine {
            host: "bench-8".into(),
            ..me()
        };
        let other = holder(&shown, &elsewhere, 1_300, |_, _| false);
        assert!(
            !other.stale && other.words.contains("another machine"),
            "{other:?}"
        );
        let by_hand = Shown::parse("  acquired: bench-7/alice\n  changed: 2026-11-30 09:00:00\n");
        let h = holder(&by_hand, &me(), 0, |_, _| false);
        assert!(!h.stale);
        assert_eq!(
            h.words,
            "acquired by bench-7/alice (not by a ppmc run, changed 2026-11-30 09:00:00)"
        );
        assert_eq!(Shown::parse("  acquired: None\n").acquired, None);
    }

    #[test]
    fn this_process_has_a_start() {
        assert!(start_ticks(std::process::id()).is_some_and(|s| s.parse::<u64>().is_ok()));
        assert_eq!(start_ticks(u32::MAX), None);
    }
}

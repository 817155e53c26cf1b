//! What the tests of several ppmc crates share: a host that follows the
//! datasheet flowcharts for the behaviour tests ([`Host`], which drives the
//! emulator through the [`Target`] trait, so the tests also exercise the
//! op / reply path every other front end uses); the suite run in process;
//! the fuzz corpora; sigrok-cli, where it is installed; bridges served on
//! pseudo-terminals and through proxies ([`served`]).
//!
//! A dev-dependency only: nothing here is part of ppmc's API.

// Test helpers, never printed.
#![allow(missing_debug_implementations)]

pub mod postgres;
pub mod served;

use ppmc::backend::{EmuTarget, Op, Reply, Target};
use ppmc::emu::{Chip, ModelConfig};
use ppmc::protocol::{
    Direction, ErrorCode, InitData, Input, MoveCommand, MoveKind, PulseCount, Status, Straps,
};
use ppmc::time::{Duration, Instant};

pub const US: fn(u64) -> Duration = Duration::from_micros;
pub const MS: fn(u64) -> Duration = Duration::from_millis;

/// RL = 100, RH = 20, PA = 100: the console example of issue 2.
pub const EXAMPLE_INIT: InitData = InitData {
    rl: 100,
    rh: 20,
    pa: 100,
};

/// 4-phase motor, 2-phase excitation, negative logic, internal clock.
pub fn init_4ph() -> u8 {
    ppmc::scenario::Init::four_phase().code()
}

pub struct Host {
    pub t: EmuTarget,
}

impl Default for Host {
    fn default() -> Self {
        Host::new()
    }
}

impl Host {
    pub fn new() -> Self {
        Host::with(Straps::default(), ModelConfig::default())
    }

    pub fn with(straps: Straps, cfg: ModelConfig) -> Self {
        Host {
            t: EmuTarget::new(straps, cfg).expect("valid straps and config"),
        }
    }

    pub fn chip(&self) -> &Chip {
        self.t.chip()
    }

    pub fn now(&self) -> Instant {
        self.t.chip().now()
    }

    fn one(&mut self, op: Op) -> Reply {
        self.t.execute_one(op).expect("the emulator never fails")
    }

    /// Flowchart write: wait for IBF = 0, then write the command register.
    /// Returns the time of the write.
    pub fn wc(&mut self, byte: u8) -> Instant {
        match self.one(Op::WriteCommand {
            byte,
            wait_ibf: Some(Duration::from_secs(1)),
        }) {
            Reply::Written { at, .. } => at,
            other => panic!("wc 0x{byte:02X}: {other:?}"),
        }
    }

    /// Flowchart write of the data register.
    pub fn wd(&mut self, byte: u8) -> Instant {
        match self.one(Op::WriteData {
            byte,
            wait_ibf: Some(Duration::from_secs(1)),
        }) {
            Reply::Written { at, .. } => at,
            other => panic!("wd 0x{byte:02X}: {other:?}"),
        }
    }

    /// Writes the command register at once, ignoring IBF (raw layer).
    pub fn wc_now(&mut self, byte: u8) {
        self.one(Op::WriteCommand {
            byte,
            wait_ibf: None,
        });
    }

    /// Writes the data register at once, ignoring IBF (raw layer).
    pub fn wd_now(&mut self, byte: u8) {
        self.one(Op::WriteData {
            byte,
            wait_ibf: None,
        });
    }

    /// A command and its data bytes, each after IBF = 0. Returns the time of
    /// the final write.
    pub fn send(&mut self, cmd: u8, data: &[u8]) -> Instant {
        let mut at = self.wc(cmd);
        for b in data {
            at = self.wd(*b);
        }
        at
    }

    pub fn status(&self) -> Status {
        self.t.board().read_status()
    }

    /// Waits for the byte in the input buffer to be taken, then returns the
    /// status: what the host sees once the chip has reacted.
    pub fn settled_status(&mut self) -> Status {
        self.await_flag(Status::IBF, false, MS(1000))
            .expect("IBF clears");
        self.status()
    }

    /// Flowchart read: wait for OBF = 1, then read the data register.
    pub fn rd(&mut self) -> u8 {
        match self.one(Op::ReadData {
            wait_obf: Some(Duration::from_secs(1)),
        }) {
            Reply::Data { byte, .. } => byte,
            other => panic!("rd: {other:?}"),
        }
    }

    pub fn wait(&mut self, d: Duration) {
        self.one(Op::Delay(d));
    }

    /// Waits for a status flag; `Some(waited)` or `None` on timeout.
    pub fn await_flag(&mut self, mask: u8, value: bool, timeout: Duration) -> Option<Duration> {
        match self.one(Op::AwaitStatus {
            mask,
            value: if value { mask } else { 0 },
            timeout,
        }) {
            Reply::Awaited { waited, .. } => Some(waited),
            _ => None,
        }
    }

    pub fn set(&mut self, input: Input, asserted: bool) {
        self.one(Op::SetInput { input, asserted });
    }

    /// Initialization with the given code and data, then waits until the
    /// chip takes commands again.
    pub fn init(&mut self, code: u8, data: InitData) {
        self.send(code, &data.to_bytes());
        self.wait(MS(200));
    }

    /// The console example's initialization: 4-phase, RL 100, RH 20, PA 100.
    pub fn init_example(&mut self) {
        self.init(init_4ph(), EXAMPLE_INIT);
    }

    /// Issues a move and returns the time of its final write.
    pub fn start(&mut self, cmd: MoveCommand, rate: Option<u8>, steps: Option<u32>) -> Instant {
        let mut data = Vec::new();
        if let Some(r) = rate {
            data.push(r);
        }
        if let Some(n) = steps {
            data.extend(PulseCount::new(n).expect("step count in range").to_bytes());
        }
        self.wait_ready();
        self.send(Command::move_byte(cmd), &data)
    }

    /// Waits for BUSY = 0 and IBF = 0, as the flowcharts require before an
    /// operation command.
    pub fn wait_ready(&mut self) {
        self.await_flag(Status::BUSY, false, Duration::from_secs(10_000))
            .expect("BUSY clears");
        self.await_flag(Status::IBF, false, MS(1000))
            .expect("IBF clears");
    }

    /// Waits for BUSY = 0 (a move already under way ends).
    pub fn await_idle(&mut self) {
        self.await_flag(Status::BUSY, false, Duration::from_secs(10_000))
            .expect("BUSY falls");
    }

    /// Waits for BUSY to rise and fall again.
    pub fn run_to_end(&mut self) {
        self.await_flag(Status::BUSY, true, MS(5))
            .expect("BUSY rises");
        self.await_flag(Status::BUSY, false, Duration::from_secs(10_000))
            .expect("BUSY falls");
    }

    /// Accel/decel move of `steps` in `dir` (interrupt enabled), run to end.
    pub fn accel_move(&mut self, dir: Direction, steps: u32) {
        self.start(
            MoveCommand::new(MoveKind::AccelDecel, dir, true),
            None,
            Some(steps),
        );
        self.run_to_end();
    }

    /// Reads a register with the flowchart (BUSY = 0, IBF = 0, command,
    /// then OBF = 1 before each byte).
    pub fn read_reg(&mut self, code: u8, bytes: usize) -> Vec<u8> {
        self.wait_ready();
        self.wc(code);
        (0..bytes).map(|_| self.rd()).collect()
    }

    pub fn finish_status(&mut self) -> u8 {
        self.read_reg(0x80, 1)[0]
    }

    /// The remaining-pulses register as read (one less than the remainder).
    pub fn remaining_read(&mut self) -> u32 {
        let b = self.read_reg(0x83, 3);
        u32::from_le_bytes([b[0], b[1], b[2], 0])
    }

    pub fn error(&self) -> Option<ErrorCode> {
        self.status().error()
    }

    /// Pulses of the most recent move.
    pub fn pulses(&self) -> u64 {
        self.t.chip().record().last_move_pulses().count
    }

    /// Times of every pulse recorded so far.
    pub fn pulse_times(&self) -> Vec<Instant> {
        self.t.chip().record().pulses().map(|(t, _)| t).collect()
    }

    /// Time of the first pulse of the most recent move.
    pub fn first_pulse(&self) -> Instant {
        self.t
            .chip()
            .record()
            .last_move_pulses()
            .first
            .expect("the move pulsed")
    }

    pub fn last_pulse(&self) -> Instant {
        self.t
            .chip()
            .record()
            .last_move_pulses()
            .last
            .expect("the move pulsed")
    }

    /// Time of the first pin event for `pin` with `value` at or after `from`.
    pub fn pin_event(&self, pin: ppmc::protocol::Pin, value: u8, from: Instant) -> Option<Instant> {
        self.t
            .chip()
            .record()
            .pins
            .iter()
            .find(|e| e.pin == pin && e.value == value && e.at >= from)
            .map(|e| e.at)
    }
}

/// Encoding helper, kept here so the tests read as command names.
pub struct Command;

impl Command {
    pub fn move_byte(cmd: MoveCommand) -> u8 {
        ppmc::protocol::Command::Move(cmd).encode()
    }
}

/// Whether `got` is within `permille` of `want`.
pub fn within(got: Duration, want: Duration, permille: u64) -> bool {
    let tol = want.scale(permille, 1000);
    got >= want.saturating_sub(tol) && got <= want + tol
}

/// The whole conformance suite on the default emulator (default straps and
/// model), as `ppmc run` runs it.
/// A trace's events as an exact instrument would give them: each
/// measurement's value kept, its uncertainty (a bridge's, `±`) dropped;
/// and how many measurements carried one.
pub fn values_of(t: &ppmc::trace::Trace) -> (Vec<ppmc::trace::Event>, usize) {
    let unsure = t
        .events
        .iter()
        .filter(
            |e| matches!(e.kind, ppmc::trace::EventKind::Measure { u, .. } if u > Duration::ZERO),
        )
        .count();
    (t.values(), unsure)
}

pub fn suite_in_process() -> Vec<ppmc::scenario::ScenarioResult> {
    let mut t = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    ppmc::runner::run_suite(
        &mut t,
        &ppmc_scenarios::all(),
        1,
        ppmc::scenario::DriverOptions::default(),
        |_| {},
    )
}

/// Every committed input of a fuzz target, seeds (`fuzz/corpus/<target>/`)
/// then regressions (`fuzz/regressions/<target>/`), each sorted by name:
/// `(path, bytes)`.
pub fn fuzz_inputs(target: &str) -> Vec<(std::path::PathBuf, Vec<u8>)> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    let mut out = Vec::new();
    for dir in ["corpus", "regressions"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir).join(target)) else {
            continue;
        };
        let mut files: Vec<_> = entries.filter_map(Result::ok).map(|e| e.path()).collect();
        files.sort();
        for f in files.into_iter().filter(|f| f.is_file()) {
            let data = std::fs::read(&f).expect("readable corpus file");
            out.push((f, data));
        }
    }
    out
}

/// At most once across reconnects (`docs/bridge-protocol.md` section 3),
/// on a real bridge: the scenarios named run through a chaos proxy on
/// 127.0.0.1 in front of `bridge` that cuts the connection once, after
/// frame `k`, for every `k` of a clean run in turn (the bridge's side of
/// the proxy stays up, as a serial server's does). Every run's verdicts
/// must be the clean run's: a request the bridge ran, sent again after the
/// reconnect, must not run again. Returns how many frames a clean run
/// takes (each a boundary cut at).
pub fn drop_at_every_frame(bridge: ppmc::chaos::Upstream, names: &[&str]) -> u64 {
    use ppmc::backend::{BridgeOptions, BridgeTarget, TcpLink};
    use ppmc::chaos::{Behaviour, ChaosProxy};
    use ppmc::scenario::Verdict;
    let suite: Vec<_> = ppmc_scenarios::all()
        .into_iter()
        .filter(|s| names.contains(&s.name))
        .collect();
    assert_eq!(suite.len(), names.len(), "every scenario named exists");
    let run = |behaviour| {
        let proxy =
            ChaosProxy::start("127.0.0.1:0", bridge.clone(), behaviour, 1).expect("the proxy");
        let link = TcpLink::open(&proxy.addr().to_string()).expect("the proxy accepts");
        let opts = BridgeOptions {
            reply_timeout: std::time::Duration::from_millis(500),
            ..BridgeOptions::default()
        };
        let (verdicts, resent): (Vec<Verdict>, u64) = match BridgeTarget::open(link, opts) {
            Ok(mut t) => {
                let v = ppmc::runner::run_suite(
                    &mut t,
                    &suite,
                    1,
                    ppmc::scenario::DriverOptions::default(),
                    |_| {},
                )
                .into_iter()
                .map(|r| r.verdict)
                .collect();
                (v, t.stats.retransmissions)
            }
            Err(e) => panic!("{behaviour}: the bridge did not open: {e}"),
        };
        (verdicts, proxy.stop(), resent)
    };
    let (clean, stats, resent) = run(Behaviour::Clean);
    assert!(
        clean.iter().all(|v| v.ok()),
        "the clean run passes: {clean:?}"
    );
    // On a virtual UART a run's frame count moves a little (a garbled
    // byte makes the host ask for smaller fragments): cut after frame 1, 2,
    // ... until a run ends before its cut, which must be near the clean
    // run's end.
    let mut k = 0;
    loop {
        k += 1;
        let (verdicts, cut, _) = run(Behaviour::DropAt(k));
        assert!(cut.cuts <= 1, "cut once, after frame {k}: {cut:?}");
        assert_eq!(verdicts, clean, "the connection cut after frame {k}");
        if cut.cuts == 0 {
            break;
        }
    }
    // A loaded machine may make the clean run ask again for a reply that
    // came late (a request and its reply more each): those frames are
    // the machine's, not the run's.
    let natural = stats.frames.saturating_sub(2 * resent);
    assert!(
        k * 10 >= natural * 8,
        "the runs ended after {k} frames, the clean one after {} ({resent} requests sent again)",
        stats.frames
    );
    stats.frames
}

/// Whether sigrok-cli is here to check `what` against. Without it a test
/// says so and passes, except in CI (`CI` set), where `.ci/run` installs
/// it and its absence fails.
pub fn sigrok_cli(what: &str) -> bool {
    let found = std::process::Command::new("sigrok-cli")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must check {what} with sigrok-cli (apt install sigrok-cli)"
        );
        eprintln!("sigrok-cli is not installed: {what} is not checked against it");
    }
    found
}

/// Runs sigrok-cli with `args`, which must succeed; its standard output.
pub fn run_sigrok_cli(args: &[&str]) -> String {
    let out = std::process::Command::new("sigrok-cli")
        .args(args)
        .output()
        .expect("sigrok-cli runs");
    assert!(
        out.status.success(),
        "sigrok-cli {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("sigrok-cli prints text")
}

//! The bridge target over scripted and misbehaving links.

use super::error::*;
use super::options::*;
use super::target::*;
use crate::backend::link::Link;
use crate::backend::target::{Op, Reply, Target, TargetErrorKind};
use crate::stop::StopRequest;
use ppmc_core::bridge::frame::{self, FrameDecoder};
use ppmc_core::bridge::wire::{Hello, Request, Response, Timer, PROTOCOL_VERSION};
use std::io;
use std::time::{Duration as WallDuration, Instant as WallInstant};

use crate::emu::ModelConfig;
use crate::protocol::Straps;
use crate::time::Duration;
use ppmc_core::bridge::engine::BridgeEngine;
use ppmc_core::bus::EmuBus;

/// A link straight into a bridge server, which fails on demand.
#[derive(Debug)]
struct MemLink {
    server: BridgeEngine<EmuBus>,
    pending: Vec<u8>,
    fail_sends: u32,
    fail_reopens: u32,
    restart_on_reopen: bool,
    /// The bridge restarts at the next reopen with this firmware text
    /// (a panic record in it).
    panic_on_reopen: Option<String>,
    /// How many bytes the bridge sent for each request.
    sent: Vec<usize>,
    /// Frames that crossed the link so far, both ways.
    frames: u64,
    /// The connection drops at this frame boundary: before the frame
    /// with this index crosses (a request is lost, or a reply cut
    /// after the frames before it), and the link fails until reopened.
    cut_at: Option<u64>,
    broken: bool,
    /// The bridge hears, but nothing comes back (a stalled server).
    mute: bool,
    /// Requests sent so far, counted from 1 (LINK and HELLO included).
    sends: usize,
    /// These sends arrive garbled (the bridge answers BAD_FRAME).
    garble: Vec<usize>,
    /// The replies to these sends are held back, and arrive just before
    /// the reply to the next send outside them (a slow path).
    hold: Vec<usize>,
    held: Vec<u8>,
    /// The link was let go of for a power cycle: the bridge at the next
    /// reopen is a fresh one, strapped so.
    powered_off: Option<Straps>,
    /// The straps of the bridge that answers after a power cycle.
    straps_after_cycle: Straps,
}

impl MemLink {
    fn new() -> MemLink {
        MemLink {
            server: Self::bridge(1),
            pending: Vec::new(),
            fail_sends: 0,
            fail_reopens: 0,
            restart_on_reopen: false,
            panic_on_reopen: None,
            sent: Vec::new(),
            frames: 0,
            cut_at: None,
            broken: false,
            mute: false,
            sends: 0,
            garble: Vec::new(),
            hold: Vec::new(),
            held: Vec::new(),
            powered_off: None,
            straps_after_cycle: Straps::default(),
        }
    }

    /// Whether the connection drops before the next frame crosses.
    fn cut_now(&mut self) -> bool {
        if self.cut_at == Some(self.frames) {
            self.broken = true;
        }
        self.frames += 1;
        self.broken
    }

    fn bridge(session: u32) -> BridgeEngine<EmuBus> {
        let bus = EmuBus::new(Straps::default(), ModelConfig::default()).expect("emu");
        BridgeEngine::new(bus, session, true, "test-bridge")
    }
}

impl Link for MemLink {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        if self.fail_sends > 0 {
            self.fail_sends -= 1;
            return Err(io::Error::new(io::ErrorKind::BrokenPipe, "unplugged"));
        }
        let pipe = || io::Error::new(io::ErrorKind::BrokenPipe, "connection dropped");
        if self.broken || (bytes != [0] && self.cut_now()) {
            return Err(pipe());
        }
        if self.mute {
            return Ok(());
        }
        if bytes != [0] {
            self.sends += 1;
        }
        let mut bytes = bytes.to_vec();
        if self.garble.contains(&self.sends) && bytes.len() > 3 {
            bytes[2] ^= 0x5A;
        }
        let out = self.server.on_bytes(&bytes);
        if self.hold.contains(&self.sends) {
            self.held.extend(out);
            return Ok(());
        }
        let held = std::mem::take(&mut self.held);
        self.pending.extend(held);
        self.sent.push(out.len());
        // The reply's frames, each a boundary the connection may drop at.
        for f in out.split_inclusive(|b| *b == 0) {
            if f != [0] && self.cut_now() {
                break;
            }
            self.pending.extend_from_slice(f);
        }
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], _timeout: WallDuration) -> io::Result<usize> {
        if self.pending.is_empty() && self.broken {
            return Err(io::Error::new(
                io::ErrorKind::ConnectionAborted,
                "connection dropped",
            ));
        }
        let n = self.pending.len().min(buf.len());
        buf[..n].copy_from_slice(&self.pending[..n]);
        self.pending.drain(..n);
        Ok(n)
    }

    fn close(&mut self) {
        self.powered_off = Some(self.straps_after_cycle);
    }

    fn reopen(&mut self) -> io::Result<()> {
        if self.fail_reopens > 0 {
            self.fail_reopens -= 1;
            return Err(io::Error::new(io::ErrorKind::NotFound, "no such port"));
        }
        self.pending.clear();
        self.broken = false;
        if let Some(straps) = self.powered_off.take() {
            let bus = EmuBus::new(straps, ModelConfig::default()).expect("emu");
            self.server = BridgeEngine::new(bus, 9, true, "test-bridge");
            self.mute = false;
        }
        if self.restart_on_reopen {
            self.server = Self::bridge(2);
        }
        if let Some(firmware) = self.panic_on_reopen.take() {
            let bus = EmuBus::new(Straps::default(), ModelConfig::default()).expect("emu");
            self.server = BridgeEngine::new(bus, 3, true, firmware);
        }
        Ok(())
    }

    fn name(&self) -> String {
        "mem".into()
    }
}

fn quick() -> BridgeOptions {
    BridgeOptions {
        reply_timeout: WallDuration::from_millis(20),
        min_reply_timeout: WallDuration::from_millis(1),
        retries: 2,
        reopen_attempts: 3,
        backoff: WallDuration::from_millis(1),
        quiet: WallDuration::from_millis(1),
        pad: 0,
        stop: StopRequest::default(),
    }
}

#[test]
fn asked_to_pad_the_bridge_sends_whole_multiples_of_the_padding() {
    let opts = BridgeOptions { pad: 64, ..quick() };
    let mut t = BridgeTarget::open(MemLink::new(), opts).expect("opens");
    let replies = t.execute(&[Op::Reset, Op::ReadStatus]).expect("runs");
    assert_eq!(replies.len(), 2);
    let sent = &t.link.sent;
    // The hello reply (before LINK) is not padded; from LINK's own
    // reply on, every reply fills whole 64-byte buffers.
    assert_ne!(sent[0] % 64, 0, "{sent:?}");
    assert!(sent.len() >= 3, "{sent:?}");
    assert!(sent[1..].iter().all(|n| n % 64 == 0), "{sent:?}");
    // Unasked, nothing is padded.
    let mut plain = BridgeTarget::open(MemLink::new(), quick()).expect("opens");
    plain.execute(&[Op::ReadStatus]).expect("runs");
    assert!(
        plain.link.sent.iter().all(|n| n % 64 != 0),
        "{:?}",
        plain.link.sent
    );
}

/// Pin samples of a phase-stepping move (Section 3-3-5), `n` of them
/// `step` apart, taken by a scenario driver on `t`.
fn sample_a_move(
    t: &mut dyn Target,
    step: fn(Duration) -> Duration,
    n: usize,
) -> Vec<(crate::time::Instant, crate::protocol::Pins)> {
    use crate::protocol::Direction;
    use crate::scenario::{Driver, DriverOptions, Init, Move};
    let mut d = Driver::new(t, DriverOptions::default());
    d.reset().expect("reset");
    d.init_and_wait(Init::four_phase()).expect("init");
    d.start(Move::constant(Direction::Cw, 100, 50_000))
        .expect("move");
    let period = d.period(100);
    d.sample_pins(step(period), n).expect("samples")
}

#[test]
fn pin_sampling_costs_a_round_trip_per_1500_samples_and_matches_the_emulator() {
    // On the pulse grid, and off it (every sample then differs from the
    // one before: no run-length saving at all).
    let steps: [fn(Duration) -> Duration; 2] = [|p| p, |p| p.scale(13, 10)];
    for step in steps {
        let mut emu =
            crate::backend::EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emu");
        let want = sample_a_move(&mut emu, step, 3_000);
        // Counting round trips: waits long enough that a loaded
        // machine never makes a reply late and asked for again.
        let patient = BridgeOptions {
            reply_timeout: WallDuration::from_secs(5),
            min_reply_timeout: WallDuration::from_secs(2),
            ..quick()
        };
        let mut t = BridgeTarget::open(MemLink::new(), patient).expect("healthy");
        let before = t.stats.round_trips;
        let got = sample_a_move(&mut t, step, 3_000);
        assert_eq!(got, want);
        // One batch for everything before the samples and the first
        // ~1,500 of them, one for the rest (it was 47 at 128 ops each).
        assert_eq!(t.stats.round_trips - before, 2);
    }
}

/// At most once across reconnects (`docs/bridge-protocol.md` section
/// 3): the connection drops at every frame boundary of a run in turn,
/// requests lost on the way and replies cut after any of their frames,
/// and every run sees exactly what a clean run sees. A batch run twice
/// would move the chip's clock, the pins or the status.
#[test]
fn a_connection_dropped_at_any_frame_boundary_changes_no_reply() {
    use crate::protocol::Direction;
    use crate::scenario::{Driver, DriverOptions, Init, Move};
    let run = |link: MemLink| {
        // Waits long enough that a loaded machine never gives up on a
        // reply (the link never loses one unless cut), short enough
        // that asking again for fragments costs little.
        let opts = BridgeOptions {
            reply_timeout: WallDuration::from_millis(500),
            min_reply_timeout: WallDuration::from_millis(5),
            retries: 10,
            ..quick()
        };
        let mut t = BridgeTarget::open(link, opts).expect("opens");
        let mut d = Driver::new(&mut t, DriverOptions::default());
        d.reset().expect("reset");
        d.init_and_wait(Init::four_phase()).expect("init");
        d.start(Move::constant(Direction::Cw, 100, 50_000))
            .expect("move");
        let period = d.period(100);
        // Round trips after the chip reset: none of them gives the
        // same replies if it runs twice (the chip's clock moves on).
        let samples: Vec<_> = [40, 300, 7]
            .into_iter()
            .map(|n| d.sample_pins(period.scale(13, 10), n).expect("samples"))
            .collect();
        drop(d);
        let pulses = t.execute(&[Op::ReadPulses]).expect("pulses");
        let capture = t.capture().expect("capture");
        (samples, pulses, capture, t.link.frames, t.stats.reopens)
    };
    let (samples, pulses, capture, frames, reopens) = run(MemLink::new());
    assert_eq!(reopens, 0);
    assert!(frames > 20, "precondition: {frames} frames");
    for cut in 0..frames {
        let link = MemLink {
            cut_at: Some(cut),
            ..MemLink::new()
        };
        let (s, p, c, _, reopens) = run(link);
        assert_eq!(reopens, 1, "cut at frame {cut}");
        // (Not assert_eq: the samples would fill the screen.)
        assert!(s == samples, "cut at frame {cut}: the samples differ");
        assert!(p == pulses, "cut at frame {cut}: the pulses differ");
        assert!(c == capture, "cut at frame {cut}: the capture differs");
    }
}

/// A "no reply to sequence N" answers a probe of whether the bridge ran
/// request N. If the probes go unanswered for a while, and N is then
/// sent again and runs, their late answers must not be believed: the
/// host would split N and run its ops a second time. Here N arrives
/// garbled twice, the first probe too, and the probes' answers come
/// only after N was sent again.
#[test]
fn a_late_answer_to_a_lost_probe_never_runs_a_request_twice() {
    let mut t = BridgeTarget::open(MemLink::new(), quick()).expect("healthy");
    let ms = |n| Op::Delay(Duration::from_millis(n));
    let ops = [ms(5), ms(5), Op::ReadStatus];
    let before = t.link.server.now();
    let n = t.link.sends;
    // N, N again, the first probe: garbled. The probes' answers held.
    t.link.garble = vec![n + 1, n + 2, n + 3];
    t.link.hold = (n + 3..=n + 3 + quick().retries as usize).collect();
    let r = t.execute(&ops);
    let ran = t.link.server.now().as_nanos() - before.as_nanos();
    assert_eq!(ran, 10_000_000, "the delays ran once: {r:?}");
    let r = r.expect("answered from the bridge's cache");
    assert_eq!(r.len(), 3);
}

/// A bridge that another host said HELLO to while the link was down
/// may have had its chip used: a reconnect that finds it so ends the
/// run as a link error, rather than resend a request it may run again.
#[test]
fn a_reconnect_to_a_bridge_another_host_used_is_not_trusted() {
    let mut t = BridgeTarget::open(MemLink::new(), quick()).expect("healthy");
    let other = Request::Hello {
        version: PROTOCOL_VERSION,
        host: t.host.wrapping_add(1).max(1),
    };
    t.link
        .server
        .on_bytes(&frame::encode(&other.encode(1, Timer::NANOS)));
    t.link.fail_sends = 1;
    let e = t.execute(&[Op::ReadStatus]).expect_err("displaced");
    assert_eq!(e.kind, TargetErrorKind::Link);
    assert!(
        matches!(
            e.get_ref().downcast_ref::<BridgeError>(),
            Some(BridgeError::Displaced { .. })
        ),
        "{e}"
    );
}

/// A bridge whose capture overran answers so until a chip reset: each
/// answer is the scenario's error, not a request given up, however
/// many scenarios in a row overrun.
#[test]
fn capture_overruns_do_not_use_up_the_link() {
    let mut link = MemLink::new();
    link.server = MemLink::bridge(1).with_capture_capacity(3);
    let mut t = BridgeTarget::open(link, quick()).expect("healthy");
    // Initialization (RL 100, RH 20, PA 100) and a single step: more
    // than 3 records.
    let wait_ibf = Some(Duration::from_secs(1));
    let mut ops = vec![Op::WriteCommand {
        byte: 0x06,
        wait_ibf: None,
    }];
    ops.extend([100, 20, 100, 0].map(|byte| Op::WriteData { byte, wait_ibf }));
    ops.push(Op::Delay(Duration::from_millis(200)));
    ops.push(Op::WriteCommand {
        byte: 0x4A,
        wait_ibf,
    });
    ops.push(Op::Delay(Duration::from_millis(5)));
    for n in 0..2 * MAX_GIVE_UPS {
        let mut batch = vec![Op::Reset];
        batch.extend(ops.iter().copied());
        let e = t
            .execute(&batch)
            .and_then(|_| t.capture())
            .expect_err("the capture overran");
        assert!(
            matches!(
                e.get_ref().downcast_ref::<BridgeError>(),
                Some(BridgeError::CaptureOverrun { .. })
            ),
            "{n}: {e}"
        );
    }
    assert_eq!(t.give_ups, 0);
    t.execute(&[Op::Reset, Op::ReadStatus])
        .expect("the link is still used");
}

/// Every wait has an end: a bridge that goes silent costs each request
/// its tries and one reconnect, and after three requests given up the
/// link is not used again, so the rest of a run ends at once.
#[test]
fn a_link_that_gave_up_three_times_is_not_used_again() {
    let mut t = BridgeTarget::open(MemLink::new(), quick()).expect("healthy");
    t.link.mute = true;
    for n in 1..=MAX_GIVE_UPS {
        let e = t.execute(&[Op::ReadStatus]).expect_err("silence");
        assert_eq!(e.kind, TargetErrorKind::Link);
        let text = e.to_string();
        assert!(text.contains("no bridge answering"), "{n}: {text}");
        assert!(text.contains("nothing came back"), "{n}: {text}");
    }
    let reopens = t.stats.reopens;
    let began = WallInstant::now();
    let e = t.execute(&[Op::ReadStatus]).expect_err("given up");
    assert!(
        e.to_string()
            .contains("the link gave up on 3 requests in this run"),
        "{e}"
    );
    assert_eq!(t.stats.reopens, reopens, "not even a reconnect");
    assert!(t.capture().is_err());
    // (A bound, not a speed: nothing at all was waited for.)
    assert!(began.elapsed() < WallDuration::from_secs(1));
}

/// A stop request ends a wait on a silent link at once, as an
/// interruption, not a link failure.
#[test]
fn a_stop_request_ends_a_wait_as_an_interruption() {
    let opts = BridgeOptions {
        reply_timeout: WallDuration::from_secs(30),
        min_reply_timeout: WallDuration::from_secs(30),
        ..quick()
    };
    let stop = opts.stop.clone();
    let mut t = BridgeTarget::open(MemLink::new(), opts).expect("healthy");
    t.link.mute = true;
    let asker = std::thread::spawn(move || {
        std::thread::sleep(WallDuration::from_millis(200));
        stop.request();
    });
    let e = t.execute(&[Op::ReadStatus]).expect_err("stopped");
    asker.join().expect("asker");
    assert_eq!(e.kind, TargetErrorKind::Interrupted, "{e}");
    assert_eq!(t.give_ups, 0, "an interruption is nobody's failure");
}

#[test]
fn a_vanished_port_is_reopened_and_the_run_goes_on() {
    let mut t = BridgeTarget::open(MemLink::new(), quick()).expect("healthy");
    t.link.fail_sends = 1;
    t.link.fail_reopens = 2;
    let r = t.execute(&[Op::ReadStatus]).expect("recovered");
    assert!(matches!(r[0], Reply::Status { .. }));
    assert_eq!(t.stats.reopens, 1);
}

#[test]
fn a_port_that_stays_gone_ends_with_link_lost() {
    let mut t = BridgeTarget::open(MemLink::new(), quick()).expect("healthy");
    t.link.fail_sends = 1;
    t.link.fail_reopens = 10;
    let e = t.execute(&[Op::ReadStatus]).expect_err("gone");
    assert_eq!(e.kind, TargetErrorKind::Link);
    assert!(
        e.to_string()
            .contains("link lost and not back after 3 reopen attempts"),
        "{e}"
    );
    // The serial backend's own error is kept, not flattened to text.
    assert!(matches!(
        e.get_ref().downcast_ref::<BridgeError>(),
        Some(BridgeError::LinkLost { .. })
    ));
}

#[test]
fn a_restarted_bridge_is_not_trusted() {
    let mut t = BridgeTarget::open(MemLink::new(), quick()).expect("healthy");
    t.link.fail_sends = 1;
    t.link.restart_on_reopen = true;
    let e = t.execute(&[Op::ReadStatus]).expect_err("restarted");
    assert!(
        e.to_string().contains("the bridge restarted"),
        "{}",
        e.to_string()
    );
}

/// Issue 28, item 6: the RP2350 image keeps a panic's place across the
/// watchdog's reset and says it in HELLO; a run that loses its bridge
/// to a panic ends in an infrastructure error naming it.
#[test]
fn a_bridge_that_panicked_is_an_infrastructure_error_naming_the_panic() {
    let e = restarted_as(
        "ppmc-bridge-rp2350 0.1.0; restarted after a panic at bridge/src/board.rs:442",
    );
    assert!(
        e.contains(
            "the bridge restarted (session 00000001 -> 00000003) after a panic at bridge/src/board.rs:442"
        ),
        "{e}"
    );
    assert_eq!(restart_cause("ppmc-bridge-rp2350 0.1.0"), None);
}

/// The error of a run whose bridge drops the link and comes back with
/// `firmware` as its HELLO's firmware text: a link error, never the
/// board's failure.
fn restarted_as(firmware: &str) -> String {
    let mut t = BridgeTarget::open(MemLink::new(), quick()).expect("healthy");
    t.link.fail_sends = 1;
    t.link.panic_on_reopen = Some(firmware.into());
    let e = t.execute(&[Op::ReadStatus]).expect_err("restarted");
    assert_eq!(e.kind, TargetErrorKind::Link, "not the board's failure");
    e.to_string()
}

/// Issue 43, defect 2: a bridge whose watchdog fired (a loop stopped
/// feeding it) says so in its next HELLO; the run ends in an
/// infrastructure error naming the hang, not a plain new session.
#[test]
fn a_bridge_that_hung_is_an_infrastructure_error_naming_the_hang() {
    let e = restarted_as(
        "ppmc-bridge-rp2350 0.1.0; restarted after a hang (the watchdog's timer ran out)",
    );
    assert!(
        e.contains(
            "the bridge restarted (session 00000001 -> 00000003) after a hang (the watchdog's timer ran out)"
        ),
        "{e}"
    );
}

/// A bridge that reboots while the port stays open (a UART bridge, a
/// network link) keeps answering, but its clock starts again at 0: the
/// run ends as a link error, never as a device failure on a reset chip.
#[test]
fn a_bridge_that_restarts_behind_an_open_port_is_caught_by_its_clock() {
    let mut t = BridgeTarget::open(MemLink::new(), quick()).expect("healthy");
    let ms = |n| Op::Delay(crate::time::Duration::from_millis(n));
    t.execute(&[ms(5), Op::ReadStatus]).expect("runs");
    // A reset of the host's own moves the clock back, rightly.
    t.execute(&[Op::Reset, Op::ReadStatus])
        .expect("a reset is fine");
    t.execute(&[ms(5)]).expect("runs");
    t.link.server = MemLink::bridge(1);
    let e = t.execute(&[Op::ReadStatus]).expect_err("restarted");
    assert_eq!(e.kind, TargetErrorKind::Link);
    assert!(
        e.to_string().contains(
            "the bridge's clock went back from 5000.000us to 0.000us without a chip reset"
        ),
        "{e}"
    );
}

#[test]
fn a_bridge_of_another_protocol_version_is_refused() {
    // A bridge that answers hello with the next protocol version.
    #[derive(Debug)]
    struct V2(Vec<u8>);
    impl Link for V2 {
        fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
            let mut d = FrameDecoder::new();
            d.extend(bytes);
            if let Ok(Some(p)) = d.decode() {
                let seq = p[0];
                let hello = Response::Hello(Box::new(Hello {
                    version: PROTOCOL_VERSION + 1,
                    session: 1,
                    timer_hz: 1_000_000_000,
                    max_batch_ops: 1,
                    max_payload: 64,
                    capture_capacity: 0,
                    inputs_wired: 0,
                    virtual_time: true,
                    firmware: "future".into(),
                    straps: Straps::default(),
                    resumed: false,
                    serial: String::new(),
                    uncertainty: Default::default(),
                }));
                self.0
                    .extend(frame::encode(&hello.encode(seq, Timer::NANOS)));
            }
            Ok(())
        }
        fn recv(&mut self, buf: &mut [u8], _: WallDuration) -> io::Result<usize> {
            let n = self.0.len().min(buf.len());
            buf[..n].copy_from_slice(&self.0[..n]);
            self.0.drain(..n);
            Ok(n)
        }
        fn reopen(&mut self) -> io::Result<()> {
            Ok(())
        }
        fn name(&self) -> String {
            "v2".into()
        }
    }
    let e = BridgeTarget::open(V2(Vec::new()), quick()).expect_err("version");
    assert!(
        matches!(
            e,
            BridgeError::Version { theirs, ours, .. }
                if theirs == PROTOCOL_VERSION + 1 && ours == PROTOCOL_VERSION
        ),
        "{e}"
    );
}

/// A bridge in virtual time that runs every request but a batch at once,
/// and says WORKING about a batch for ever: `creep` ns more of its clock
/// each time (10 ms of the host's), never a reply.
#[derive(Debug)]
struct Working {
    server: BridgeEngine<EmuBus>,
    out: Vec<u8>,
    /// The batch it is "running", and its clock so far.
    batch: Option<(u8, u64)>,
    creep: u64,
    /// Batches are held (after the health check at open).
    hold: bool,
}

impl Link for Working {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        let mut d = FrameDecoder::new();
        d.extend(bytes);
        while let Ok(Some(p)) = d.decode() {
            let (seq, kind) = (p[0], p.get(1).copied().unwrap_or(0));
            if self.hold && (kind == 0x02 || kind == 0x05) {
                let clock = self.batch.map_or(0, |(_, c)| c);
                self.batch = Some((seq, clock));
            } else {
                let mut f = frame::encode(&p);
                f.insert(0, 0);
                self.out.extend(self.server.on_bytes(&f));
            }
        }
        Ok(())
    }
    fn recv(&mut self, buf: &mut [u8], wait: WallDuration) -> io::Result<usize> {
        if self.out.is_empty() {
            let Some((seq, clock)) = self.batch.as_mut() else {
                std::thread::sleep(wait);
                return Ok(0);
            };
            std::thread::sleep(wait.min(WallDuration::from_millis(10)));
            *clock += self.creep;
            let elapsed = Duration::from_nanos(*clock);
            self.out.extend(frame::encode(
                &Response::Working { elapsed }.encode(*seq, Timer::NANOS),
            ));
        }
        let n = self.out.len().min(buf.len());
        buf[..n].copy_from_slice(&self.out[..n]);
        self.out.drain(..n);
        Ok(n)
    }
    fn reopen(&mut self) -> io::Result<()> {
        Ok(())
    }
    fn name(&self) -> String {
        "working".into()
    }
}

#[test]
fn a_bridge_that_says_working_for_ever_is_given_up() {
    // docs/bridge-protocol.md section 5: the host waits by a WORKING
    // bridge's clock, up to the request's bound in that clock, and no
    // longer than that bound run at 1/200 of real time. A bridge whose
    // clock runs (1 ms of it per WORKING) passes the bound and is given
    // up; one whose clock creeps (1 ns per WORKING, for ever) is given up
    // at the wall-clock cap. Either way the request ends, as a link error.
    let opts = BridgeOptions {
        reply_timeout: WallDuration::from_millis(2),
        retries: 0,
        ..quick()
    };
    for (creep, says) in [(1_000_000, "past the"), (1, "no valid reply")] {
        let link = Working {
            server: MemLink::bridge(7),
            out: Vec::new(),
            batch: None,
            creep,
            hold: false,
        };
        let mut t = BridgeTarget::open(link, opts.clone()).expect("hello");
        t.link.hold = true;
        let e = t.execute(&[Op::ReadStatus]).expect_err("no reply");
        assert_eq!(e.kind, TargetErrorKind::Link, "{e}");
        assert!(e.to_string().contains(says), "{e}");
        assert!(t.stats.working > 0, "{:?}", t.stats);
    }
}

/// Issue 44: a long differential fuzz against a bridge grew without end
/// (9 MB at 1 minute to 21 MB at 5, the bridge 8 to 14 MB): the host kept
/// the whole capture since the chip's reset and copied it on every fetch,
/// and the bridge kept it all too. Now what the run has compared is let
/// go on both sides: after 20,000 actions (whose whole record would be
/// several times the bound) each holds a window.
#[test]
fn a_long_differential_run_holds_a_window_of_the_capture_on_both_sides() {
    use crate::fuzzing::differential::{program, run, DiffSettings};
    use ppmc_core::bus::Bus;
    let mut t = BridgeTarget::open(MemLink::new(), quick()).expect("healthy");
    let s = DiffSettings {
        straps: t.straps(),
        ..DiffSettings::default()
    };
    let mut seen = 0;
    let d = run(&mut t, program(5).take(20_000), &s, |n| {
        seen = n.actions;
        true
    });
    assert_eq!(d.expect("runs"), None);
    assert_eq!(seen, 20_000);
    let held = |r: &crate::protocol::OutputRecord| r.runs.len() + r.pins.len() + r.moves.len();
    let (host, bridge) = (held(&t.captured), held(t.link.server.bus().record()));
    assert!(host <= 2_000, "the host holds {host} records");
    assert!(bridge <= 2_000, "the bridge holds {bridge} records");
}

/// Recovery by power: a bridge that fell silent is let go of, its power
/// cycled, and reached again as a new session; the same board or none.
#[test]
fn a_silent_bridge_is_reached_again_after_its_power_cycle_as_the_same_board() {
    let boot = WallDuration::from_millis(300);
    let mut t = BridgeTarget::open(MemLink::new(), quick()).expect("healthy");
    t.link.mute = true;
    let e = t.execute(&[Op::ReadStatus]).expect_err("silent");
    assert!(e
        .get_ref()
        .downcast_ref::<BridgeError>()
        .is_some_and(BridgeError::is_silence));
    let mut cycles = 0;
    t.power_cycle(
        &mut || {
            cycles += 1;
            Ok(())
        },
        boot,
    )
    .expect("back");
    assert_eq!(cycles, 1);
    assert_eq!(t.hello().session, 9, "a new session");
    let replies = t
        .execute(&[Op::Reset, Op::ReadStatus])
        .expect("answers again");
    assert!(matches!(replies[1], Reply::Status { status, .. } if status.0 == 0));

    // Another board behind the link after the cycle.
    let mut t = BridgeTarget::open(MemLink::new(), quick()).expect("healthy");
    t.link.straps_after_cycle = Straps {
        sysclk_hz: 12_000_000,
        ..Straps::default()
    };
    let e = t
        .power_cycle(&mut || Ok(()), boot)
        .expect_err("another board");
    assert!(e.to_string().contains("another board answers"), "{e}");

    // A port that does not come back, and a switch that fails.
    let mut t = BridgeTarget::open(MemLink::new(), quick()).expect("healthy");
    t.link.fail_reopens = u32::MAX;
    let e = t.power_cycle(&mut || Ok(()), boot).expect_err("not back");
    assert!(
        e.to_string()
            .contains("not back within 300ms of its power cycle (no such port)"),
        "{e}"
    );
    let e = t
        .power_cycle(&mut || Err("relay 3 is off line".into()), boot)
        .expect_err("switch");
    assert!(
        e.to_string()
            .contains("its power cycle failed: relay 3 is off line"),
        "{e}"
    );
}

//! The flags an ABORT raises (`docs/bridge-protocol.md` section 5),
//! shared by a bridge's receive path (an `AbortWatch`, in `abort.rs`), its
//! engine and its bus's waits (`Bus::watch_abort`). No more than atomics,
//! so that the bus can hold it without knowing the wire format.

use alloc::sync::Arc;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// Whether a HELLO of host session `host` takes the bridge over from the
/// host of the last HELLO, `last` (`docs/bridge-protocol.md` section 3):
/// another session, or 0, which is nobody's and always new. The engine
/// then clears its cache; the receive path stops what runs.
pub fn takes_over(last: u32, host: u32) -> bool {
    host == 0 || host != last
}

/// A request's sequence number, tagged so that 0 means none.
const fn tag(seq: u8) -> u32 {
    0x100 | seq as u32
}

/// What the receive path and the engine share: which request an ABORT
/// named, whether a new host took over, and which request runs. Cheap to
/// clone (both ends hold one) and to check (three atomic loads).
#[derive(Debug, Clone, Default)]
pub struct AbortLine(Arc<Flags>);

#[derive(Debug, Default)]
struct Flags {
    /// The request the newest ABORT named (tagged; 0: none).
    named: AtomicU32,
    /// A HELLO of another host session arrived: stop whatever runs.
    any: AtomicBool,
    /// The request the engine runs (tagged; 0: none).
    running: AtomicU32,
}

impl AbortLine {
    pub fn new() -> AbortLine {
        AbortLine::default()
    }

    /// The receive path read an ABORT naming request `seq`.
    pub fn raise(&self, seq: u8) {
        self.0.named.store(tag(seq), Ordering::Release);
    }

    /// The receive path read a HELLO of another host session.
    pub fn raise_any(&self) {
        self.0.any.store(true, Ordering::Release);
    }

    /// The engine begins request `seq`; `runs_ops` when it is one that
    /// drives the chip (a batch, a self-test). An ABORT that named another
    /// request is then stale (a host has one such request out at a time,
    /// and the one it named has ended or never came) and is forgotten, so
    /// that a later request that reuses the number runs.
    pub fn begin(&self, seq: u8, runs_ops: bool) {
        if runs_ops {
            let _ = self
                .0
                .named
                .fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| {
                    (n != tag(seq) && n != 0).then_some(0)
                });
        }
        self.0.running.store(tag(seq), Ordering::Release);
    }

    /// The engine has answered the request it ran.
    pub fn end(&self) {
        self.0.running.store(0, Ordering::Release);
    }

    /// Whether the request running is to stop at its next step.
    pub fn pending(&self) -> bool {
        let running = self.0.running.load(Ordering::Acquire);
        running != 0
            && (self.0.any.load(Ordering::Acquire)
                || self.0.named.load(Ordering::Acquire) == running)
    }

    /// The engine has stopped the request running: what it does now
    /// (stopping the chip) must not be cut short by the same abort.
    pub fn acknowledge(&self) {
        let running = self.0.running.load(Ordering::Acquire);
        let _ = self
            .0
            .named
            .compare_exchange(running, 0, Ordering::AcqRel, Ordering::Acquire);
        self.0.any.store(false, Ordering::Release);
    }

    /// The engine has read, in its turn, the ABORT that named `seq`: a
    /// later request that happens to reuse the number runs.
    pub fn read_abort(&self, seq: u8) {
        let _ = self
            .0
            .named
            .compare_exchange(tag(seq), 0, Ordering::AcqRel, Ordering::Acquire);
    }

    /// The engine has read, in its turn, a HELLO of another host session:
    /// the new host's own requests run.
    pub fn read_takeover(&self) {
        self.0.any.store(false, Ordering::Release);
    }
}

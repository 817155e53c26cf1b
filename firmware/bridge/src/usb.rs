//! Core 0's side of the RP2350 bridge: USB packets to and from the engine
//! on core 1, through two pipes, and nothing else. The engine's long ops
//! (a delay, a wait for a status or for pulses, seconds long) run on core 1,
//! so they never keep core 0 from its USB stack (until issue 28 the engine
//! ran inside this loop, in the task beside `usb.run()`: a port opened
//! during a long op timed out, defect 6); and every packet written has a
//! deadline, so a host that stops reading ends the connection instead of
//! hanging the bridge.
//!
//! The image runs [`serve_connection`] over embassy-usb's CDC ACM class,
//! embassy-sync's pipes and embassy-time's timeout (`firmware/rp2350`);
//! the tests run it over stand-ins, against the structure it replaced.

use core::future::Future;
use embassy_futures::select::{select, Either};

/// A packet endpoint pair of the USB serial port.
pub trait Packets {
    /// The next packet from the host, or an error when the connection
    /// ended.
    fn read_packet<'a>(
        &'a mut self,
        buf: &'a mut [u8],
    ) -> impl Future<Output = Result<usize, ()>> + 'a;
    /// Sends a packet to the host; an error when the connection ended.
    fn write_packet<'a>(&'a mut self, data: &'a [u8]) -> impl Future<Output = Result<(), ()>> + 'a;
}

/// The two pipes between the cores.
pub trait Pipes {
    /// Writes some of `data` towards the engine; how many bytes.
    fn to_engine<'a>(&'a self, data: &'a [u8]) -> impl Future<Output = usize> + 'a;
    /// Reads some of the engine's reply bytes into `buf`; how many.
    fn replies<'a>(&'a self, buf: &'a mut [u8]) -> impl Future<Output = usize> + 'a;
    /// Nothing more from the engine is waiting.
    fn replies_empty(&self) -> bool;
    /// Forgets the bytes the engine has not taken yet.
    fn forget_to_engine(&self);
    /// Sees a packet as it arrives, before any of it goes towards the
    /// engine: where the image watches for ABORT
    /// (`docs/bridge-protocol.md` section 5), so that the engine cannot
    /// read a frame before the watch has seen it.
    fn arrived(&self, _packet: &[u8]) {}
}

/// A clock that bounds a future.
pub trait Deadline {
    /// `f`'s output, or `None` when it did not finish within the write
    /// deadline.
    fn within<F: Future>(&self, f: F) -> impl Future<Output = Option<F::Output>>;
}

/// The largest packet (full-speed bulk).
pub const PACKET: usize = 64;

/// Serves one connection until it ends (the host closed the port, or left
/// a packet unread past the deadline): bytes from the host go to the
/// engine, the engine's replies to the host, each as soon as it can.
///
/// While the engine is slow to take bytes (a long op), its replies keep
/// going out, or neither core would move again.
pub async fn serve_connection<U: Packets, P: Pipes, D: Deadline>(
    usb: &mut U,
    pipes: &P,
    deadline: &D,
) {
    let (mut rx, mut tx) = ([0u8; PACKET], [0u8; PACKET]);
    loop {
        match select(usb.read_packet(&mut rx), pipes.replies(&mut tx)).await {
            Either::First(Ok(n)) => {
                pipes.arrived(&rx[..n]);
                let mut rest = &rx[..n];
                while !rest.is_empty() {
                    match select(pipes.to_engine(rest), pipes.replies(&mut tx)).await {
                        Either::First(k) => rest = &rest[k..],
                        Either::Second(m) => {
                            if deadline.within(usb.write_packet(&tx[..m])).await != Some(Ok(())) {
                                return;
                            }
                        }
                    }
                }
            }
            Either::First(Err(())) => return,
            Either::Second(n) => {
                if deadline.within(usb.write_packet(&tx[..n])).await != Some(Ok(())) {
                    return;
                }
                if n == PACKET && pipes.replies_empty() {
                    // A full last packet: end the transfer.
                    let _ = deadline.within(usb.write_packet(&[])).await;
                }
            }
        }
    }
}

/// Between two connections, until `next` (the next connection) is ready:
/// what the host that left sent and the engine has not taken is
/// forgotten, and what the engine still writes for it is thrown away as it
/// comes. Core 1 so never stays blocked on a full pipe that nobody reads,
/// and the next host gets no byte of an old reply (but for one the engine
/// is still writing when it opens the port: its frame decoder drops the
/// broken frame).
pub async fn between_connections<P: Pipes, F: Future>(pipes: &P, next: F) -> F::Output {
    pipes.forget_to_engine();
    let mut next = core::pin::pin!(next);
    let mut buf = [0u8; PACKET];
    loop {
        match select(next.as_mut(), pipes.replies(&mut buf)).await {
            Either::First(v) => return v,
            // Meant for the host that left.
            Either::Second(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::pin::Pin;
    use core::task::{Context, Poll};
    use std::cell::RefCell;
    use std::collections::VecDeque;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::{Arc, Mutex};
    use std::time::{Duration, Instant};
    use std::vec::Vec;

    /// A future that is ready once its closure says so; it asks to be
    /// polled again at once (embassy-futures' `block_on` polls in a loop).
    struct Until<F>(F);

    impl<T, F: FnMut() -> Option<T> + Unpin> Future for Until<F> {
        type Output = T;
        fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<T> {
            match (self.0)() {
                Some(v) => Poll::Ready(v),
                None => {
                    cx.waker().wake_by_ref();
                    Poll::Pending
                }
            }
        }
    }

    /// The host's side of the port: packets it sends, bytes it read.
    #[derive(Default)]
    struct Host {
        to_bridge: VecDeque<Vec<u8>>,
        from_bridge: Vec<u8>,
        /// It stopped reading (a hung host).
        deaf: bool,
        /// It closed the port.
        closed: bool,
    }

    struct Usb(Arc<Mutex<Host>>);

    impl Packets for Usb {
        fn read_packet<'a>(
            &'a mut self,
            buf: &'a mut [u8],
        ) -> impl Future<Output = Result<usize, ()>> + 'a {
            let host = self.0.clone();
            Until(move || {
                let mut h = host.lock().expect("host");
                if let Some(p) = h.to_bridge.pop_front() {
                    buf[..p.len()].copy_from_slice(&p);
                    return Some(Ok(p.len()));
                }
                h.closed.then_some(Err(()))
            })
        }

        fn write_packet<'a>(
            &'a mut self,
            data: &'a [u8],
        ) -> impl Future<Output = Result<(), ()>> + 'a {
            let host = self.0.clone();
            Until(move || {
                let mut h = host.lock().expect("host");
                if h.deaf {
                    return None;
                }
                h.from_bridge.extend_from_slice(data);
                Some(Ok(()))
            })
        }
    }

    /// The pipes, and core 1 on a thread of its own: an engine that echoes
    /// each byte after `op` of work (a long op), `busy` meanwhile.
    struct TwoCores {
        to_engine: Arc<Mutex<VecDeque<u8>>>,
        from_engine: Arc<Mutex<VecDeque<u8>>>,
    }

    impl TwoCores {
        fn start(op: Duration, busy: Arc<AtomicBool>) -> TwoCores {
            let to_engine = Arc::new(Mutex::new(VecDeque::new()));
            let from_engine = Arc::new(Mutex::new(VecDeque::new()));
            let (i, o) = (to_engine.clone(), from_engine.clone());
            std::thread::spawn(move || loop {
                let b = i.lock().expect("pipe").pop_front();
                match b {
                    Some(b) => {
                        busy.store(true, Ordering::SeqCst);
                        std::thread::sleep(op);
                        busy.store(false, Ordering::SeqCst);
                        o.lock().expect("pipe").push_back(b);
                    }
                    None => std::thread::sleep(Duration::from_micros(100)),
                }
                // The test is over.
                if Arc::strong_count(&i) == 1 {
                    return;
                }
            });
            TwoCores {
                to_engine,
                from_engine,
            }
        }
    }

    impl Pipes for TwoCores {
        fn to_engine<'a>(&'a self, data: &'a [u8]) -> impl Future<Output = usize> + 'a {
            let q = self.to_engine.clone();
            Until(move || {
                let mut q = q.lock().expect("pipe");
                let n = data.len().min(8usize.saturating_sub(q.len()));
                q.extend(&data[..n]);
                (n > 0).then_some(n)
            })
        }

        fn replies<'a>(&'a self, buf: &'a mut [u8]) -> impl Future<Output = usize> + 'a {
            let q = self.from_engine.clone();
            Until(move || {
                let mut q = q.lock().expect("pipe");
                let n = q.len().min(buf.len());
                for b in buf.iter_mut().take(n) {
                    *b = q.pop_front().unwrap_or(0);
                }
                (n > 0).then_some(n)
            })
        }

        fn replies_empty(&self) -> bool {
            self.from_engine.lock().expect("pipe").is_empty()
        }

        fn forget_to_engine(&self) {
            self.to_engine.lock().expect("pipe").clear();
        }
    }

    /// The write deadline on the wall clock.
    struct Wall(Duration);

    impl Deadline for Wall {
        async fn within<F: Future>(&self, f: F) -> Option<F::Output> {
            let end = Instant::now() + self.0;
            let timeout = Until(move || (Instant::now() >= end).then_some(()));
            match select(f, timeout).await {
                Either::First(v) => Some(v),
                Either::Second(()) => None,
            }
        }
    }

    /// `usb.run()`'s stand-in: the USB stack's own task, which must be
    /// polled to answer the host's control requests (a port opened, DTR):
    /// counts its polls while the engine is in a long op, until `done`.
    async fn usb_stack(busy: &AtomicBool, polls_in_ops: &RefCell<u64>, done: &RefCell<bool>) {
        Until(move || {
            if busy.load(Ordering::SeqCst) {
                *polls_in_ops.borrow_mut() += 1;
            }
            done.borrow().then_some(())
        })
        .await
    }

    /// Runs `serve` beside the USB stack's stand-in until it returns; how
    /// often the stack was polled while the engine was in a long op.
    fn beside_the_stack(busy: &AtomicBool, serve: impl Future<Output = ()>) -> u64 {
        let (polls, done) = (RefCell::new(0), RefCell::new(false));
        embassy_futures::block_on(embassy_futures::join::join(
            usb_stack(busy, &polls, &done),
            async {
                serve.await;
                *done.borrow_mut() = true;
            },
        ));
        polls.into_inner()
    }

    /// The loop before issue 28, reduced to its structure: the engine ran
    /// inside it, on the bytes it read, before it read again.
    async fn serve_with_the_engine_inline(usb: &mut Usb, op: Duration, busy: &AtomicBool) {
        let mut rx = [0u8; PACKET];
        while let Ok(n) = usb.read_packet(&mut rx).await {
            for _ in 0..n {
                // The engine's long op, in this task.
                busy.store(true, Ordering::SeqCst);
                std::thread::sleep(op);
                busy.store(false, Ordering::SeqCst);
            }
            let reply = rx[..n].to_vec();
            let _ = usb.write_packet(&reply).await;
        }
    }

    fn host_sends(packets: usize) -> Arc<Mutex<Host>> {
        let mut h = Host::default();
        for i in 0..packets {
            h.to_bridge.push_back(std::vec![i as u8; 4]);
        }
        Arc::new(Mutex::new(h))
    }

    /// A host that sends one packet, `packet`.
    fn host_sending(packet: std::vec::Vec<u8>) -> Arc<Mutex<Host>> {
        let mut h = Host::default();
        h.to_bridge.push_back(packet);
        Arc::new(Mutex::new(h))
    }

    #[test]
    fn defect_6_a_long_op_kept_the_usb_stack_waiting_and_on_core_1_it_does_not() {
        // Counted, not timed: whether the USB stack was polled at all
        // while the engine was in one of its long ops.
        let op = Duration::from_millis(50);
        // Before: the engine's ops ran in the serving task, and the USB
        // stack beside it was not polled once while they ran.
        let busy = AtomicBool::new(false);
        let host = host_sends(2);
        host.lock().expect("host").closed = true;
        let mut usb = Usb(host.clone());
        let before = beside_the_stack(&busy, serve_with_the_engine_inline(&mut usb, op, &busy));
        assert_eq!(
            before, 0,
            "the stack was polled {before} times during the ops"
        );
        assert_eq!(
            host.lock().expect("host").from_bridge.len(),
            8,
            "it did answer"
        );
        // Now: the engine on its own core; the stack is polled while it
        // works, and every byte comes back.
        let busy = Arc::new(AtomicBool::new(false));
        let host = host_sends(2);
        let mut usb = Usb(host.clone());
        let cores = TwoCores::start(op, busy.clone());
        let watcher = host.clone();
        std::thread::spawn(move || {
            // The host closes the port once it has every byte back.
            while watcher.lock().expect("host").from_bridge.len() < 8 {
                std::thread::sleep(Duration::from_millis(5));
            }
            watcher.lock().expect("host").closed = true;
        });
        let deadline = Wall(Duration::from_millis(500));
        let now = beside_the_stack(&busy, serve_connection(&mut usb, &cores, &deadline));
        assert!(now > 0, "the stack was not polled while the engine worked");
        assert_eq!(
            host.lock().expect("host").from_bridge,
            [0, 0, 0, 0, 1, 1, 1, 1]
        );
    }

    #[test]
    fn a_host_that_stops_reading_ends_the_connection_at_the_write_deadline() {
        // Before issue 28 `write_packet` had no deadline: a hung host hung
        // the bridge.
        let host = host_sends(1);
        host.lock().expect("host").deaf = true;
        let mut usb = Usb(host);
        let cores = TwoCores::start(Duration::ZERO, Arc::new(AtomicBool::new(false)));
        let started = Instant::now();
        let deadline = Wall(Duration::from_millis(100));
        embassy_futures::block_on(serve_connection(&mut usb, &cores, &deadline));
        let took = started.elapsed();
        assert!(
            took >= Duration::from_millis(100) && took < Duration::from_secs(10),
            "{took:?}"
        );
    }

    /// Issue 43, defect 5: a host that closes the port while the engine is
    /// still answering it. The next host gets its own replies and nothing
    /// of the old one's, and nothing the old host sent reaches the engine
    /// after it left.
    #[test]
    fn defect_5_the_next_host_gets_no_byte_meant_for_the_last() {
        // The engine echoes each byte after 20 ms; the first host sends
        // eight and is gone before the first echo.
        let cores = TwoCores::start(Duration::from_millis(20), Arc::new(AtomicBool::new(false)));
        let first = host_sending(std::vec![1; 8]);
        first.lock().expect("host").closed = true;
        let deadline = Wall(Duration::from_millis(500));
        embassy_futures::block_on(serve_connection(&mut Usb(first.clone()), &cores, &deadline));
        // The next host opens the port 300 ms later (the engine long done
        // with whatever it took), sends four bytes and reads four back.
        let opened = Instant::now() + Duration::from_millis(300);
        let next = Until(move || (Instant::now() >= opened).then_some(()));
        embassy_futures::block_on(between_connections(&cores, next));
        let second = host_sending(std::vec![9; 4]);
        let watcher = second.clone();
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(400));
            watcher.lock().expect("host").closed = true;
        });
        embassy_futures::block_on(serve_connection(
            &mut Usb(second.clone()),
            &cores,
            &deadline,
        ));
        assert_eq!(second.lock().expect("host").from_bridge, [9, 9, 9, 9]);
        assert!(cores.to_engine.lock().expect("pipe").is_empty());
    }
}

//! `ppmc chaos-proxy`: a misbehaving TCP server in front of a bridge, to
//! qualify a lab's network and bridge the way CI qualifies ppmc's link
//! layer (`docs/detection.md`, "The link under attack").

use crate::{usage, CliError};
use clap::Args;
use ppmc::chaos::{Behaviour, ChaosProxy, Upstream};
use std::io::Write;
use std::sync::atomic::Ordering;

#[derive(Debug, Args)]
pub struct ChaosProxyArgs {
    /// The bridge: `serial:<path>` (a board's port, a `ppmc bridge-sim`
    /// pseudo-terminal) or `tcp://<host>:<port>` (ser2net in raw mode).
    #[arg(long, value_name = "BRIDGE")]
    to: String,
    /// What the proxy does to the traffic: clean, drop-every=N, drop-at=K,
    /// drop-both-every=N, drop-random-byte=N, stall=N, accept-close,
    /// flood-after=N,
    /// flood-random, flood-ff, endless-frame, trickle, wrong-seq,
    /// error-only, option-storm, duplicate=N, reorder=N, half-open=N
    /// (N counts frames, or bytes for drop-random-byte).
    #[arg(long, value_name = "BEHAVIOUR", default_value = "clean")]
    behaviour: String,
    /// Where to listen; point `--target tcp://ADDR` (or `rfc2217://ADDR`
    /// for option-storm) at it.
    #[arg(long, default_value = "127.0.0.1:0")]
    listen: String,
    /// Seed of the random draws, so that a run can be repeated.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

pub fn run(args: ChaosProxyArgs) -> Result<(), CliError> {
    let behaviour: Behaviour = args.behaviour.parse().map_err(usage)?;
    let upstream: Upstream = args.to.parse().map_err(usage)?;
    let stop = super::signals::stop_requested();
    let proxy = ChaosProxy::start(&args.listen, upstream, behaviour, args.seed)
        .map_err(|e| CliError::Infrastructure(format!("{} or {}: {e}", args.listen, args.to)))?;
    let mut out = std::io::stdout();
    let _ = writeln!(
        out,
        "chaos-proxy: {behaviour} on {}, in front of {}",
        proxy.addr(),
        args.to
    );
    let _ = out.flush();
    while !stop.load(Ordering::Relaxed) {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let s = proxy.stop();
    let _ = writeln!(
        out,
        "chaos-proxy: {} connections, {} cut, {} frames passed on",
        s.connections, s.cuts, s.frames
    );
    Ok(())
}

//! One bus abstraction, many backends.
//!
//! Everything that drives a chip (the console, the scenario runner, the
//! fuzzer) talks to a [`Target`] through batches of [`Op`]s. A batch runs
//! back to back on the target's own clock and comes back as one [`Reply`]
//! per op, each stamped with the target's time. On the emulator a batch
//! costs nothing; on a board behind the serial bus bridge it costs one
//! round trip, which is why waiting (for IBF, OBF, BUSY) is an op the
//! target performs, never a host-side polling loop.
//!
//! A target is named by a [`TargetSpec`] (`emu`, `serial:/dev/ttyACM0`,
//! `tcp://host:port`, `rfc2217://host:port`, `labgrid:place`, each with
//! options of that board alone) and opened by [`open`], which checks a
//! board's health and its straps on the way:
//!
//! ```
//! # use ppmc::chaos::{Behaviour, ChaosProxy, Upstream};
//! # use ppmc::bridge::sim::{LinkFaults, PtyBridge};
//! # use ppmc::{emu::ModelConfig, protocol::Straps};
//! # let bridge = PtyBridge::start(ppmc::bus::EmuBus::new(Straps::default(), ModelConfig::default())?, LinkFaults::default())?;
//! # let server = ChaosProxy::start("127.0.0.1:0", Upstream::Serial(bridge.path().into()), Behaviour::Clean, 0)?;
//! # let port = server.addr().port();
//! use ppmc::backend::{open, OpenOptions, Op, TargetSpec};
//!
//! // A bridge's serial port served on the lab network (ser2net in raw
//! // mode), labelled for the reports.
//! let spec: TargetSpec = format!("tcp://127.0.0.1:{port},name=bench-1").parse()?;
//! let mut board = open(&spec, &OpenOptions::default())?;
//! let status = board.execute_one(Op::ReadStatus)?;
//! println!("{}: {status}", spec.label());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! A new way to reach a bridge is a file under `link/` with its [`Link`]
//! and its [`LinkDriver`], and a line in [`link::DRIVERS`]; the protocol,
//! retries, reconnects and verdicts come with [`BridgeTarget`].

mod bridged;
mod command;
mod emu;
pub mod link;
mod open;
pub mod power;
mod spec;
mod target;

pub use self::bridged::{
    restart_cause, AbortOutcome, BridgeError, BridgeOptions, BridgeTarget, LinkStats, MAX_GIVE_UPS,
};
pub use self::emu::EmuTarget;
pub use self::link::labgrid::{parse_labgrid, LabgridLink, Place};
pub use self::link::rfc2217::{parse_rfc2217, Rfc2217Link};
pub use self::link::serial::{parse_serial_address, SerialLink};
pub use self::link::tcp::{parse_tcp, TcpLink};
pub use self::link::{Link, LinkDriver, DRIVERS};
pub use self::open::{check, open, OpenError, OpenOptions};
pub use self::power::{Hub, Power, PowerOptions, PowerSwitch};
pub use self::spec::{forms, Address, SpecError, StrapOptions, TargetSpec};
pub use self::target::{
    Op, Reply, SelfTestPlan, SelfTestReply, SelfTestRun, Target, TargetError, TargetErrorKind,
    TargetInfo, Uncertainty,
};

pub(crate) use self::link::timed_out;

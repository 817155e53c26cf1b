//! The serial bus bridge: the link protocol a bridge microcontroller speaks
//! (specified in `docs/bridge-protocol.md`), implemented once and shared by
//! the host driver ([`crate::target::SerialTarget`]) and the bridge
//! simulator ([`server`]).

pub mod frame;
pub mod server;
pub mod sim;
pub mod wire;

//! The invariant checks of `docs/invariants.md`: what must hold of the
//! chip after every bus op, whatever the ops. The fuzz targets run them on
//! the emulator; a reproducer or a regression scenario runs them on any
//! target.
//!
//! - [`oracle`]: the judge and the oracle on the emulator.
//! - [`replay`]: bus ops replayed on any target and judged by the same
//!   rules, and the body of a regression scenario.

pub mod oracle;
pub mod replay;

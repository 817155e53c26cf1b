//! The invariant checks of `docs/invariants.md`: what must hold of the
//! chip after every bus op, whatever the ops. The fuzz targets run them on
//! the emulator; a reproducer or a regression scenario runs them on any
//! target.
//!
//! - [`ids`]: the invariants by name, [`Invariant`](ids::Invariant), one
//!   per row of `docs/invariants.md`.
//! - [`rules`]: the invariants checked op by op from what the host sees,
//!   and at the end from the capture ([`Rules`](rules::Rules)); a break
//!   is a [`Violation`](rules::Violation).
//! - [`capture`]: the checks that read the capture alone.
//! - [`oracle`]: the rules on the emulator's chip, the fuzz targets'
//!   oracle.
//! - [`replay`]: bus ops replayed on any target and judged by the same
//!   rules, and the body of a regression scenario.

pub mod capture;
pub mod ids;
pub mod oracle;
pub mod replay;
pub mod rules;

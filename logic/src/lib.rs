//! Logic-analyzer recordings of the chip's bus and pins (issue 30): the
//! readers of each file format (VCD, Saleae Logic 2, sigrok), all
//! producing the stream of level changes of [`source`], and [`open`],
//! which picks the reader; then what knows the chip's bus: which channel
//! carries which signal ([`map`]) and the bus decoded into register
//! accesses ([`decode`]). Judging a board from a capture is
//! `ppmc_capture::judge`.

pub mod decode;
pub mod map;
pub mod open;
pub mod saleae;
pub mod saleae_csv;
pub mod sigrok;
pub mod source;
pub mod vcd;
mod vcd_header;

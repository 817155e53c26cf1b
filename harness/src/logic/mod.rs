//! Logic-analyzer recordings of the chip's bus and pins (issue 30): the
//! readers of each file format, one file each, all producing the stream of
//! level changes of [`source`]. Nothing here knows the chip: mapping
//! channels to its signals, decoding its bus and judging it come on top.

pub mod sigrok;
pub mod source;

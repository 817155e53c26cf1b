//! A capture opened by what it is: a sigrok session (`.sr`), a VCD, a
//! Saleae Logic 2 export (its CSV, or its binary export: one
//! `digital_N.bin` per channel, or the folder holding them). The name's
//! extension says which; a file without a known one is told by its first
//! bytes (a ZIP is a sigrok session, `<SALEAE>` a Saleae binary, `$` a
//! VCD).

use super::saleae::SaleaeBinary;
use super::saleae_csv::SaleaeCsv;
use super::sigrok::SigrokReader;
use super::source::{LogicError, LogicSource};
use super::vcd::VcdReader;
use std::io::Read;
use std::path::Path;

/// Opens `path` as a capture.
pub fn open(path: &Path) -> Result<Box<dyn LogicSource>, LogicError> {
    if path.is_dir() {
        return Ok(Box::new(SaleaeBinary::open(path)?));
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("sr") => return Ok(Box::new(SigrokReader::open(path)?)),
        Some("vcd") => return Ok(Box::new(VcdReader::open(path)?)),
        Some("csv") => return Ok(Box::new(SaleaeCsv::open(path)?)),
        Some("bin") => return Ok(Box::new(SaleaeBinary::open(path)?)),
        _ => {}
    }
    let mut head = [0u8; 8];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .map_err(|e| LogicError::new(path, "", format!("cannot read: {e}")))?;
    let head = &head[..n];
    if head.starts_with(b"PK\x03\x04") {
        Ok(Box::new(SigrokReader::open(path)?))
    } else if head.starts_with(b"<SALEAE>") {
        Ok(Box::new(SaleaeBinary::open(path)?))
    } else if head.trim_ascii_start().starts_with(b"$") {
        Ok(Box::new(VcdReader::open(path)?))
    } else {
        Err(LogicError::new(
            path,
            "",
            "not a capture ppmc reads: give a sigrok session (.sr), a VCD (.vcd) or a Saleae Logic 2 export (.csv, or its binary export's .bin files or folder)",
        ))
    }
}

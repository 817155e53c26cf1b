//! `ppmc-fwtool`: what `firmware/build` needs on the host, without a
//! toolchain of its own.
//!
//! ```text
//! ppmc-fwtool uf2 ELF OUT --family rp2350   # UF2 of ELF's loadable segments
//! ppmc-fwtool size ELF --flash 0x10000000:4M --ram 0x20000000:512K
//! ```
//!
//! Both read a 32-bit little-endian ELF (what the Cortex-M targets link)
//! and refuse anything else with a message that says where it stopped.

use ppmc_fwtool::{elf, uf2};

use std::process::ExitCode;

const USAGE: &str = "usage:
  ppmc-fwtool uf2 ELF OUT --family rp2350|rp2040|0xNNNNNNNN
  ppmc-fwtool size ELF --flash ORIGIN:LEN --ram ORIGIN:LEN   (LEN in bytes, or with K or M)";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(out) => {
            print!("{out}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("ppmc-fwtool: {e}");
            ExitCode::from(2)
        }
    }
}

fn run(args: &[String]) -> Result<String, String> {
    match args.first().map(String::as_str) {
        Some("uf2") => {
            let [_, elf, out, flag, family] = args else {
                return Err(USAGE.into());
            };
            if flag != "--family" {
                return Err(USAGE.into());
            }
            let family = uf2::family(family)?;
            let image = elf::Elf::parse(&read(elf)?).map_err(|e| format!("{elf}: {e}"))?;
            let bytes = uf2::from_segments(&image.loadable(), family)?;
            write_new(out, &bytes)?;
            Ok(format!("{out}: {} blocks\n", bytes.len() / uf2::BLOCK))
        }
        Some("size") => {
            let [_, elf, f, flash, r, ram] = args else {
                return Err(USAGE.into());
            };
            if f != "--flash" || r != "--ram" {
                return Err(USAGE.into());
            }
            let (flash, ram) = (region(flash)?, region(ram)?);
            let image = elf::Elf::parse(&read(elf)?).map_err(|e| format!("{elf}: {e}"))?;
            let used_flash: u64 = image
                .loadable()
                .iter()
                .filter(|s| within(s.addr, flash))
                .map(|s| s.data.len() as u64)
                .sum();
            let used_ram: u64 = image
                .sections
                .iter()
                .filter(|s| s.alloc && within(s.addr, ram))
                .map(|s| u64::from(s.size))
                .sum();
            let pct = |used: u64, (_, len): (u32, u32)| used as f64 * 100.0 / f64::from(len.max(1));
            Ok(format!(
                "{elf}: flash {used_flash} of {} bytes ({:.1} %), RAM {used_ram} of {} bytes ({:.1} %)\n",
                flash.1,
                pct(used_flash, flash),
                ram.1,
                pct(used_ram, ram)
            ))
        }
        _ => Err(USAGE.into()),
    }
}

fn read(path: &str) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("{path}: {e}"))
}

/// Writes `bytes` to `path` through a temporary beside it, so that a
/// reader never sees half an image.
fn write_new(path: &str, bytes: &[u8]) -> Result<(), String> {
    let tmp = format!("{path}.tmp-{}", std::process::id());
    std::fs::write(&tmp, bytes).map_err(|e| format!("{tmp}: {e}"))?;
    std::fs::rename(&tmp, path).map_err(|e| format!("{path}: {e}"))
}

fn within(addr: u32, (origin, len): (u32, u32)) -> bool {
    addr >= origin && u64::from(addr) < u64::from(origin) + u64::from(len)
}

/// `ORIGIN:LEN`, e.g. `0x10000000:4M`.
fn region(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("`{s}`: write ORIGIN:LEN, e.g. 0x20000000:512K");
    let (o, l) = s.split_once(':').ok_or_else(bad)?;
    let origin = o
        .strip_prefix("0x")
        .map_or_else(|| o.parse(), |h| u32::from_str_radix(h, 16))
        .map_err(|_| bad())?;
    let (num, mul) = match l.as_bytes().last() {
        Some(b'K') => (&l[..l.len() - 1], 1024),
        Some(b'M') => (&l[..l.len() - 1], 1024 * 1024),
        _ => (l, 1),
    };
    let len = num
        .parse::<u32>()
        .ok()
        .and_then(|n| n.checked_mul(mul))
        .ok_or_else(bad)?;
    Ok((origin, len))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_read_as_written() {
        assert_eq!(region("0x20000000:512K"), Ok((0x2000_0000, 512 * 1024)));
        assert_eq!(region("0:4M"), Ok((0, 4 << 20)));
        assert!(region("0x20000000").is_err());
        assert!(region("0x20000000:8192M").is_err());
    }

    #[test]
    fn bad_arguments_give_the_usage() {
        assert_eq!(run(&["frob".into()]), Err(USAGE.into()));
        assert_eq!(run(&["uf2".into(), "a".into()]), Err(USAGE.into()));
    }
}

//! Just enough of a 32-bit little-endian ELF: loadable segments (at their
//! load addresses) and allocated sections, every offset checked.

/// Bytes to place at `addr` (a segment's physical, load, address).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Segment {
    pub addr: u32,
    pub data: Vec<u8>,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Section {
    pub addr: u32,
    pub size: u32,
    /// Occupies memory at run time (SHF_ALLOC).
    pub alloc: bool,
}

#[derive(Debug)]
pub struct Elf {
    segments: Vec<Segment>,
    pub sections: Vec<Section>,
}

const PT_LOAD: u32 = 1;
const SHF_ALLOC: u32 = 2;

fn u16_at(b: &[u8], at: usize) -> Result<u16, String> {
    b.get(at..at + 2)
        .map(|s| u16::from_le_bytes([s[0], s[1]]))
        .ok_or_else(|| format!("truncated at byte {at}"))
}

fn u32_at(b: &[u8], at: usize) -> Result<u32, String> {
    b.get(at..at + 4)
        .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
        .ok_or_else(|| format!("truncated at byte {at}"))
}

impl Elf {
    pub fn parse(b: &[u8]) -> Result<Elf, String> {
        if b.get(..4) != Some(b"\x7fELF".as_slice()) {
            return Err("not an ELF file".into());
        }
        if b.get(4) != Some(&1) || b.get(5) != Some(&1) {
            return Err("not a 32-bit little-endian ELF (a Cortex-M image is)".into());
        }
        let (phoff, phsize, phnum) = (
            u32_at(b, 0x1C)? as usize,
            usize::from(u16_at(b, 0x2A)?),
            usize::from(u16_at(b, 0x2C)?),
        );
        let (shoff, shsize, shnum) = (
            u32_at(b, 0x20)? as usize,
            usize::from(u16_at(b, 0x2E)?),
            usize::from(u16_at(b, 0x30)?),
        );
        let mut segments = Vec::new();
        for i in 0..phnum {
            let h = phoff + i * phsize;
            if u32_at(b, h)? != PT_LOAD {
                continue;
            }
            let (offset, paddr, filesz) = (
                u32_at(b, h + 4)? as usize,
                u32_at(b, h + 12)?,
                u32_at(b, h + 16)? as usize,
            );
            if filesz == 0 {
                continue;
            }
            let data = b
                .get(offset..offset + filesz)
                .ok_or_else(|| format!("segment {i} runs past the end of the file"))?;
            segments.push(Segment {
                addr: paddr,
                data: data.to_vec(),
            });
        }
        let mut sections = Vec::new();
        for i in 0..shnum {
            let h = shoff + i * shsize;
            sections.push(Section {
                alloc: u32_at(b, h + 8)? & SHF_ALLOC != 0,
                addr: u32_at(b, h + 12)?,
                size: u32_at(b, h + 20)?,
            });
        }
        Ok(Elf { segments, sections })
    }

    /// The loadable segments that carry bytes, in address order.
    pub fn loadable(&self) -> Vec<Segment> {
        let mut s = self.segments.clone();
        s.sort_by_key(|s| s.addr);
        s
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A minimal ELF: one loadable segment of `data` at `addr`, one
    /// allocated section of `bss` bytes at `ram`.
    pub(crate) fn tiny(addr: u32, data: &[u8], ram: u32, bss: u32) -> Vec<u8> {
        let mut b = vec![0u8; 0x34];
        b[..4].copy_from_slice(b"\x7fELF");
        b[4] = 1; // 32-bit
        b[5] = 1; // little endian
        let phoff = 0x34u32;
        let shoff = phoff + 32;
        let data_at = shoff + 2 * 40;
        b[0x1C..0x20].copy_from_slice(&phoff.to_le_bytes());
        b[0x20..0x24].copy_from_slice(&shoff.to_le_bytes());
        b[0x2A..0x2C].copy_from_slice(&32u16.to_le_bytes());
        b[0x2C..0x2E].copy_from_slice(&1u16.to_le_bytes());
        b[0x2E..0x30].copy_from_slice(&40u16.to_le_bytes());
        b[0x30..0x32].copy_from_slice(&2u16.to_le_bytes());
        let mut ph = vec![0u8; 32];
        ph[..4].copy_from_slice(&PT_LOAD.to_le_bytes());
        ph[4..8].copy_from_slice(&data_at.to_le_bytes());
        ph[8..12].copy_from_slice(&addr.to_le_bytes());
        ph[12..16].copy_from_slice(&addr.to_le_bytes());
        ph[16..20].copy_from_slice(&(data.len() as u32).to_le_bytes());
        ph[20..24].copy_from_slice(&(data.len() as u32).to_le_bytes());
        b.extend(ph);
        for (a, size) in [(addr, data.len() as u32), (ram, bss)] {
            let mut sh = vec![0u8; 40];
            sh[8..12].copy_from_slice(&SHF_ALLOC.to_le_bytes());
            sh[12..16].copy_from_slice(&a.to_le_bytes());
            sh[20..24].copy_from_slice(&size.to_le_bytes());
            b.extend(sh);
        }
        b.extend_from_slice(data);
        b
    }

    #[test]
    fn reads_segments_and_sections() {
        let e = Elf::parse(&tiny(0x1000_0000, b"abcdef", 0x2000_0000, 64)).expect("parses");
        assert_eq!(
            e.loadable(),
            vec![Segment {
                addr: 0x1000_0000,
                data: b"abcdef".to_vec()
            }]
        );
        assert_eq!(e.sections.len(), 2);
        assert_eq!((e.sections[1].addr, e.sections[1].size), (0x2000_0000, 64));
    }

    #[test]
    fn refuses_what_it_cannot_read() {
        assert!(Elf::parse(b"MZ").is_err());
        let mut e = tiny(0, b"x", 0, 0);
        e[4] = 2;
        assert!(Elf::parse(&e).expect_err("64-bit").contains("32-bit"));
        let e = tiny(0, b"xyz", 0, 0);
        let cut = &e[..e.len() - 2];
        assert!(Elf::parse(cut).expect_err("cut").contains("past the end"));
    }
}

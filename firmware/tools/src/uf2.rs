//! UF2, the drag-and-drop flashing format of the RP2040/RP2350 boot ROM:
//! 512-byte blocks, each carrying 256 bytes for one flash address.

use crate::elf::Segment;

pub const BLOCK: usize = 512;
const PAYLOAD: usize = 256;
const MAGIC_START0: u32 = 0x0A32_4655;
const MAGIC_START1: u32 = 0x9E5D_5157;
const MAGIC_END: u32 = 0x0AB1_6F30;
const FLAG_FAMILY_ID: u32 = 0x0000_2000;

/// The family ID a board's boot ROM accepts.
pub fn family(name: &str) -> Result<u32, String> {
    match name {
        // RP2350, Arm cores, secure image (what an embassy-rp image is).
        "rp2350" => Ok(0xE48B_FF59),
        "rp2040" => Ok(0xE48B_FF56),
        hex => hex
            .strip_prefix("0x")
            .and_then(|h| u32::from_str_radix(h, 16).ok())
            .ok_or_else(|| format!("family `{hex}`: rp2350, rp2040 or 0xNNNNNNNN")),
    }
}

/// The UF2 image of `segments`: 256-byte pages, each page's unused bytes
/// zero, in address order.
pub fn from_segments(segments: &[Segment], family: u32) -> Result<Vec<u8>, String> {
    // Pages touched, with their contents.
    let mut pages: std::collections::BTreeMap<u32, [u8; PAYLOAD]> = Default::default();
    for s in segments {
        for (i, byte) in s.data.iter().enumerate() {
            let addr = s
                .addr
                .checked_add(i as u32)
                .ok_or("a segment runs past the 4 GiB address space")?;
            let page = addr & !(PAYLOAD as u32 - 1);
            pages.entry(page).or_insert([0; PAYLOAD])[(addr - page) as usize] = *byte;
        }
    }
    if pages.is_empty() {
        return Err("the ELF has no loadable bytes".into());
    }
    let n = pages.len() as u32;
    let mut out = Vec::with_capacity(pages.len() * BLOCK);
    for (i, (addr, data)) in pages.into_iter().enumerate() {
        let words = [
            MAGIC_START0,
            MAGIC_START1,
            FLAG_FAMILY_ID,
            addr,
            PAYLOAD as u32,
            i as u32,
            n,
            family,
        ];
        for w in words {
            out.extend_from_slice(&w.to_le_bytes());
        }
        out.extend_from_slice(&data);
        out.resize(out.len() + (476 - PAYLOAD), 0);
        out.extend_from_slice(&MAGIC_END.to_le_bytes());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::elf::{tests::tiny, Elf};

    fn word(b: &[u8], block: usize, i: usize) -> u32 {
        let at = block * BLOCK + i * 4;
        u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
    }

    #[test]
    fn blocks_carry_each_page_once_in_order() {
        // 300 bytes from 0x1000_0080: pages 0x1000_0000 and 0x1000_0100.
        let data: Vec<u8> = (0..300u32).map(|i| (i % 251) as u8 + 1).collect();
        let elf = Elf::parse(&tiny(0x1000_0080, &data, 0x2000_0000, 0)).expect("parses");
        let b = from_segments(&elf.loadable(), family("rp2350").expect("known")).expect("uf2");
        assert_eq!(b.len(), 2 * BLOCK);
        assert_eq!(&b[..4], b"UF2\n");
        for blk in 0..2 {
            assert_eq!(word(&b, blk, 0), MAGIC_START0);
            assert_eq!(word(&b, blk, 1), MAGIC_START1);
            assert_eq!(word(&b, blk, 2), FLAG_FAMILY_ID);
            assert_eq!(word(&b, blk, 4), 256);
            assert_eq!(word(&b, blk, 5), blk as u32);
            assert_eq!(word(&b, blk, 6), 2);
            assert_eq!(word(&b, blk, 7), 0xE48B_FF59);
            assert_eq!(word(&b, blk, 127), MAGIC_END);
        }
        assert_eq!((word(&b, 0, 3), word(&b, 1, 3)), (0x1000_0000, 0x1000_0100));
        // The first page: 128 zero bytes, then the data.
        assert_eq!(&b[32..32 + 128], &[0u8; 128][..]);
        assert_eq!(&b[32 + 128..32 + 256], &data[..128]);
        assert_eq!(&b[BLOCK + 32..BLOCK + 32 + 172], &data[128..]);
    }

    #[test]
    fn families_and_empty_images() {
        assert_eq!(family("0x12345678"), Ok(0x1234_5678));
        assert!(family("rp9999").is_err());
        assert!(from_segments(&[], 1).is_err());
    }
}

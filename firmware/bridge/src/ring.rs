//! The capture's DMA rings: a DMA channel per edge counter moves each word
//! the counter pushes from its RX FIFO into a ring in RAM, endlessly
//! (RP2350 datasheet, DMA chapter: the write address wrapped by
//! `RING_SIZE`, the channel re-triggering itself every ring's worth), so
//! that the counter never waits on a full FIFO and the CPU drains at its
//! leisure, up to a ring's worth.
//!
//! The CPU sees where the DMA writes next and keeps where it reads next.
//! On the RP2350 "where the DMA writes next" is read from the channel's
//! transfer count, not its `WRITE_ADDR`: with the write address wrapped
//! by `RING_SIZE`, the datasheet says `WRITE_ADDR` is not held back for
//! writes still in flight (12.6.1, RP2040-E12), so it can be ahead of the
//! data in RAM; the count moves as each write completes. A ring the DMA
//! came round on before the CPU read it is told by the word the CPU read
//! last: the DMA overwrote it on its way round ([`Reader::next`]); and,
//! before a first word is read, by [`CANARY`], which the CPU puts where
//! the DMA wrote last when it starts reading. Two words of a counter are
//! never equal (each carries a count that only goes down, through 2^31
//! ticks), and none is [`CANARY`], so an overwritten word always differs.

/// Words a ring holds: 1 KiB, aligned to its size as `RING_SIZE` needs.
pub const RING_WORDS: usize = 256;

/// `RING_SIZE` of the DMA channel: log2 of a ring's bytes.
pub const RING_BITS: u8 = 10;
const _: () = assert!(1 << RING_BITS == RING_WORDS * 4);

/// What the CPU writes where the DMA wrote last when it starts reading a
/// ring ([`Reader::at`]): no counter pushes it (a counter's count has gone
/// down at least twice when it pushes, so its low 31 bits are at most
/// 0x7FFF_FFFD).
pub const CANARY: u32 = u32::MAX;

/// The DMA came round the ring past words the CPU had not read: the
/// capture lost some.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Lapped;

/// The CPU's side of a ring.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Reader {
    /// The next word to read.
    read: usize,
    /// The word read last, as it was ([`CANARY`] before the first).
    last: Option<u32>,
}

impl Reader {
    /// A reader at the ring's start that has read nothing (as `Default`,
    /// in a `const`).
    pub const fn new() -> Reader {
        Reader {
            read: 0,
            last: None,
        }
    }

    /// Reads from where the DMA writes next, `write`: what the ring holds
    /// is dropped. The caller writes [`CANARY`] at [`Reader::canary_slot`]
    /// first, while the DMA is idle, so that a lap before the first word
    /// is read is told too.
    pub fn at(write: usize) -> Reader {
        Reader {
            read: write % RING_WORDS,
            last: Some(CANARY),
        }
    }

    /// Where [`CANARY`] goes for a reader starting at `write`: the slot
    /// the DMA wrote last.
    pub fn canary_slot(write: usize) -> usize {
        (write % RING_WORDS + RING_WORDS - 1) % RING_WORDS
    }

    /// The ring index `k` words past the next to read.
    pub fn at_offset(&self, k: usize) -> usize {
        (self.read + k) % RING_WORDS
    }

    /// Words written and not yet read (a full ring reads as empty: the
    /// next [`Reader::next`] tells them apart).
    pub fn level(&self, write: usize) -> usize {
        (write % RING_WORDS + RING_WORDS - self.read) % RING_WORDS
    }

    /// The next word, `word(i)` reading the ring's word `i`, `write` being
    /// where the DMA writes next; `None` when every word written is read.
    pub fn next(
        &mut self,
        mut word: impl FnMut(usize) -> u32,
        write: usize,
    ) -> Result<Option<u32>, Lapped> {
        let unread = self.read != write % RING_WORDS;
        // The word first, then the check: the DMA writes in order, so had
        // it overwritten this word it would have overwritten the one read
        // last before it.
        let w = unread.then(|| word(self.read));
        // The word read last is where it was, or the DMA came round.
        if let Some(last) = self.last {
            if word((self.read + RING_WORDS - 1) % RING_WORDS) != last {
                return Err(Lapped);
            }
        }
        if let Some(w) = w {
            self.read = (self.read + 1) % RING_WORDS;
            self.last = Some(w);
        }
        Ok(w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// A DMA writing words `from..to` (each word its own number, as
    /// counts never repeat) into `ring`; where it writes next.
    fn dma(ring: &mut [u32; RING_WORDS], from: u32, to: u32) -> usize {
        for w in from..to {
            ring[w as usize % RING_WORDS] = w;
        }
        to as usize % RING_WORDS
    }

    /// A ring and a reader started at `write`, the canary in place.
    fn fresh(write: usize) -> ([u32; RING_WORDS], Reader) {
        let mut ring = [0u32; RING_WORDS];
        ring[Reader::canary_slot(write)] = CANARY;
        (ring, Reader::at(write))
    }

    #[test]
    fn every_word_is_read_once_in_order_across_the_wrap() {
        let (mut ring, mut r) = fresh(0);
        let mut got = Vec::new();
        let mut at = 0;
        for chunk in [10u32, 200, 255, 1, 0, 256 - 1, 37] {
            let write = dma(&mut ring, at, at + chunk);
            at += chunk;
            assert_eq!(r.level(write), chunk as usize % RING_WORDS);
            while let Some(w) = r.next(|i| ring[i], write).expect("never lapped") {
                got.push(w);
            }
        }
        assert_eq!(got, (0..at).collect::<Vec<_>>());
    }

    #[test]
    fn a_ring_the_dma_came_round_on_is_told_whatever_the_lap() {
        for extra in [1u32, 5, RING_WORDS as u32, 3 * RING_WORDS as u32 + 7] {
            let (mut ring, mut r) = fresh(0);
            let write = dma(&mut ring, 0, 3);
            assert_eq!(r.next(|i| ring[i], write), Ok(Some(0)));
            // The DMA writes a whole ring and more before the CPU looks.
            let write = dma(&mut ring, 3, RING_WORDS as u32 + extra);
            assert_eq!(
                r.next(|i| ring[i], write),
                Err(Lapped),
                "{extra} over a ring"
            );
        }
        // Exactly a ring's worth unread is told too (the ring cannot say
        // full from empty): a word early, never late.
        let (mut ring, mut r) = fresh(0);
        let write = dma(&mut ring, 0, 1);
        assert_eq!(r.next(|i| ring[i], write), Ok(Some(0)));
        let write = dma(&mut ring, 1, 1 + RING_WORDS as u32);
        assert_eq!(r.next(|i| ring[i], write), Err(Lapped));
        // A lap before the first word is read: the canary is gone.
        let (mut ring, mut r) = fresh(7);
        let write = dma(&mut ring, 7, 7 + RING_WORDS as u32 + 2);
        assert_eq!(r.next(|i| ring[i], write), Err(Lapped));
    }

    #[test]
    fn a_lap_while_the_word_is_read_is_told() {
        // 255 words unread; as the CPU reads word `read`, the DMA writes two
        // more: over the word read last, then over `read`. The word read
        // is the newer one, but the check after it sees the lap.
        let (mut ring, mut r) = fresh(0);
        let write = dma(&mut ring, 0, 1);
        assert_eq!(r.next(|i| ring[i], write), Ok(Some(0)));
        let write = dma(&mut ring, 1, 256);
        let ring = std::cell::RefCell::new(ring);
        let got = r.next(
            |i| {
                let mut ring = ring.borrow_mut();
                if i == 1 && ring[0] == 0 {
                    // The DMA, as the CPU reads: words 256 and 257.
                    ring[0] = 256;
                    ring[1] = 257;
                }
                ring[i]
            },
            write,
        );
        assert_eq!(got, Err(Lapped));
    }
}

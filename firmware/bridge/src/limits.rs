//! The bridge's memory: one heap size and one capture capacity for every
//! image (the RP2350 board, the QEMU virtual board and the board twin), and
//! the arithmetic that makes the capture fill before the heap does.
//!
//! A failed allocation is a panic: the board restarts (its watchdog) and
//! the run loses its session. The capture is the only part of the heap
//! that grows with what the chip does; everything else the bridge holds is
//! bounded by the protocol ([`ENGINE_BYTES`]). So the capture gets what is
//! left, counted at its worst, and [`CAPTURE_RECORDS`] is what that holds:
//! past it the engine answers CAPTURE_OVERRUN
//! (`BridgeEngine::with_capture_capacity`) and stops a batch before its
//! next op, so the capture grows past it by at most what one op adds
//! ([`OP_RECORDS`]).
//!
//! On the Cortex-M targets a pulse run takes [`RUN_BYTES`], a pin change
//! [`PIN_BYTES`] and a move record [`MOVE_BYTES`] (checked when the images
//! are built), each kind in a `Vec` of its own that doubles as it fills.
//! While a `Vec` grows the heap holds its new block, its old block and the
//! blocks it outgrew before (the heap's first-fit allocator cannot fit the
//! new block into the smaller ones it left): at most twice the new
//! capacity, which is at most twice the length reached (and at least 4).
//! `n` records, all of the largest kind at worst, so take at most
//! `2 x 4 x (32 + 16 + 32) + 2 x 2 x 32 x n = 640 + 128 n` bytes
//! ([`capture_bytes`]). With the board's 256 KiB heap:
//!
//! ```text
//!   262,144  heap (HEAP_BYTES)
//! -  73,728  the engine's buffers at their worst (ENGINE_BYTES)
//! -   8,192  the chip's side (CHIP_BYTES)
//! -  16,384  margin, for fragmentation beyond what is counted (MARGIN_BYTES)
//! = 163,840  for the capture: (163,840 - 640) / 128 = 1,275 records
//! -     527  what one op may add past the capacity (OP_RECORDS)
//! =     748  records the capture holds (CAPTURE_RECORDS)
//! ```
//!
//! The capacity it replaces, 4,096 records, did not fit: the pulse runs
//! alone took the heap past its end as their `Vec` grew from 2,048 to
//! 4,096 (131,072 bytes), with 2,049 runs in the capture, half the
//! capacity. `harness/tests/it/firmware_qemu.rs` shows it on the QEMU board,
//! which keeps this heap and capacity: there the capture's largest growth
//! (its runs' `Vec` to 2,048) takes the heap to about 155 KB of its
//! 256 KiB.

/// The widest the board code lets the bracket grow in which it stamps a
/// change of an output it samples (S1..S5, AUXO0..3, DIR): from the last
/// sight of the old levels to the first of the new, in ns. It samples them
/// at every poll (between ops, in every wait's loop, while it waits for the
/// host) and at every pin read; a stamp is halfway, so within half of this
/// (HELLO_REPLY's `sampled` uncertainty). The twin's tests hold the board
/// code to it under the suite's busiest loads.
pub const SAMPLE_BRACKET_NS: u64 = 10_000;

/// The most pin samples the board code reads in one loop
/// (`Board::sample_run`): five SAMPLE ops of 512, more than the three
/// periods of stop switching the scenarios of Section 3-5-1 sample 250 ns
/// apart (2,086 reads). Kept outside the heap: on the RP2350 in a static
/// of 8 bytes a read (20 KiB).
pub const GRID_SAMPLES: usize = 5 * 512;

/// The heap: the RP2350 board's, and the QEMU board's with it, so that the
/// virtual board runs out where the board does. The board has 512 KiB of
/// RAM for data; the rest is its stack and statics.
pub const HEAP_BYTES: usize = 256 * 1024;

/// A pulse run (`ppmc_core::protocol::PulseRun`) on the Cortex-M targets:
/// three 64-bit times, a count and a direction, 8-byte aligned.
pub const RUN_BYTES: usize = 32;

/// A pin change (`PinEvent`): a 64-bit time, the pin and its value.
pub const PIN_BYTES: usize = 16;

/// A move record (`MoveStart`).
pub const MOVE_BYTES: usize = 32;

/// The most records one op can add: the engine looks at the capture
/// between ops only. A wait adds what the chip does meanwhile, at most one
/// move (a move starts only on a command an op writes): its pulse runs, one
/// per period of its ramp up and down (at most 254 rates each way, the
/// chip's rate grid) and its cruise, 510 with the first pulse; its move
/// record; 16 pin changes (BUSY, HOLD, DIR, INT*, switching and phases,
/// each at most twice). The longest ramp, RL 254 to RH 20 over PA 11,220
/// pulses, makes 469 runs in the model.
///
/// A chip that pulses at random intervals would make a run of every pulse,
/// without end within one op: the board code stops recording at
/// [`CAPTURE_RECORDS`] + `OP_RECORDS` (`board/capture.rs`), and the engine answers
/// CAPTURE_OVERRUN.
pub const OP_RECORDS: usize = 2 * 254 + 2 + 1 + 16;

/// What the bridge engine (`ppmc_core::bridge::engine`) holds at its worst
/// besides the capture: while it runs a batch and answers it with a
/// capture chunk, each figure the most the protocol allows.
///
/// | what | bytes |
/// |---|---|
/// | the frame decoder's buffer: `MAX_ENCODED` and a 64-byte packet, grown to 8,192 with the blocks it outgrew | 16,384 |
/// | the request's payload | 4,096 |
/// | the QEMU board's receive buffer; the cached answer to a HELLO | 4,396 |
/// | the batch's wire ops: 128 of 24 bytes (a SAMPLE op stays one) | 3,072 |
/// | its reply as it is written: `MAX_REPLY` and one SAMPLES entry | 15,333 |
/// | the larger of the reply's run of samples (512 of 10 bytes, with the blocks outgrown: 10,200) and the capture chunk (300 runs, 300 pin changes, 60 moves: 16,320) with its 11,955 bytes | 28,275 |
/// | total | 71,556 |
///
/// The rest of a request's life holds less: the cached answer (payload and
/// 255 fragments, 20,416) is freed before a batch runs, the reply before
/// its frames are encoded (14,790 for 255 fragments).
pub const ENGINE_BYTES: usize = 72 * 1024;

/// The total of [`ENGINE_BYTES`]'s table.
const ENGINE_COUNTED: usize = 71_556;
const _: () = assert!(ENGINE_BYTES >= ENGINE_COUNTED);

/// What the chip's side holds on the heap besides the capture: on the
/// QEMU board the reference model (its timers, ramp steps and settings;
/// about 4 KB), on the RP2350 board the board code's pin changes not yet
/// in the capture and its trackers.
pub const CHIP_BYTES: usize = 8 * 1024;

/// Room for what the bounds above do not count: the heap's fragmentation
/// beyond the blocks each `Vec` outgrew.
pub const MARGIN_BYTES: usize = 16 * 1024;

const fn max(a: usize, b: usize) -> usize {
    if a > b {
        a
    } else {
        b
    }
}

/// The largest record.
const LARGEST: usize = max(RUN_BYTES, max(PIN_BYTES, MOVE_BYTES));

/// The most heap a capture of `records` records can take, its `Vec`s
/// growing at their worst: `640 + 128 x records` bytes on the board.
pub const fn capture_bytes(records: usize) -> usize {
    2 * 4 * (RUN_BYTES + PIN_BYTES + MOVE_BYTES) + 2 * 2 * LARGEST * records
}

/// The records a capture may be given on a heap of `heap` bytes: with
/// [`OP_RECORDS`] more, at their worst, it still fits beside the engine,
/// the chip's side and the margin. Zero when nothing fits.
pub const fn capture_records(heap: usize) -> u32 {
    let Some(room) = heap.checked_sub(ENGINE_BYTES + CHIP_BYTES + MARGIN_BYTES + capture_bytes(0))
    else {
        return 0;
    };
    let records = room / (2 * 2 * LARGEST);
    if records <= OP_RECORDS {
        return 0;
    }
    (records - OP_RECORDS) as u32
}

/// Records the capture holds between chip resets: pulse runs, pin changes
/// and move records (HELLO_REPLY's `capture_capacity`). The suite's
/// busiest scenario needs 367 pulse runs and pin changes.
pub const CAPTURE_RECORDS: u32 = capture_records(HEAP_BYTES);

// Room for the suite's busiest scenario and its moves, or the heap is too
// small for the bridge.
const _: () = assert!(CAPTURE_RECORDS > 367 + 100);

// The sizes above are the Cortex-M targets' (32-bit, 64-bit values 8-byte
// aligned); a change to a record type that makes it larger fails the build.
#[cfg(all(target_arch = "arm", target_pointer_width = "32"))]
const _: () = {
    use core::mem::size_of;
    use ppmc_core::protocol::{MoveStart, PinEvent, PulseRun};
    assert!(size_of::<PulseRun>() <= RUN_BYTES);
    assert!(size_of::<PinEvent>() <= PIN_BYTES);
    assert!(size_of::<MoveStart>() <= MOVE_BYTES);
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_capacity_is_the_arithmetic_of_the_module_doc() {
        assert_eq!(OP_RECORDS, 527);
        assert_eq!(capture_bytes(1), 640 + 128);
        assert_eq!(
            16_384 + 4_096 + 4_396 + 3_072 + 15_333 + 28_275,
            ENGINE_COUNTED,
            "the table of ENGINE_BYTES"
        );
        assert_eq!(CAPTURE_RECORDS, 748);
        // It and one op's records fit beside the rest; one more would not.
        let used = |c: u32| {
            ENGINE_BYTES + CHIP_BYTES + MARGIN_BYTES + capture_bytes(c as usize + OP_RECORDS)
        };
        assert!(used(CAPTURE_RECORDS) <= HEAP_BYTES);
        assert!(used(CAPTURE_RECORDS + 1) > HEAP_BYTES);
    }

    #[test]
    fn a_heap_too_small_for_anything_holds_no_capture() {
        assert_eq!(capture_records(0), 0);
        assert_eq!(capture_records(ENGINE_BYTES + CHIP_BYTES + MARGIN_BYTES), 0);
        assert!(capture_records(2 * HEAP_BYTES) > 2 * CAPTURE_RECORDS);
    }

    #[test]
    fn the_old_capacity_did_not_fit_the_heap() {
        // 4,096 runs: a 131,072-byte Vec, grown from 65,536 with the
        // 65,408 bytes it outgrew before: 262,016 of the heap's 262,144
        // for the runs alone, as the Vec grows.
        let growing = 32
            * (4_096
                + 2_048
                + (4..2_048)
                    .filter(|c: &usize| c.is_power_of_two())
                    .sum::<usize>());
        assert_eq!(growing, 262_016);
        assert!(ENGINE_BYTES + growing > HEAP_BYTES);
        assert!(capture_bytes(4_096) > HEAP_BYTES);
        assert!(capture_records(HEAP_BYTES) < 4_096);
    }
}

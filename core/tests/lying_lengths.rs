//! A bridge's reply whose CRC is right but whose lengths lie: every count
//! and length the host reads is checked against what the payload can hold
//! and the protocol's own limits (`docs/bridge-protocol.md`: 512 samples an
//! entry, `MAX_BATCH_OPS` ops a batch, 12,240-byte responses, 48-byte
//! fragments) before anything is allocated for it. Each decode here must
//! fail, and with the error of the check that comes before the allocation:
//! a lie caught only later (the bytes running out, the runs not adding up)
//! means the host had already reserved or expanded what it promised.

use ppmc_core::bridge::wire::{
    kind, parse_fragment, Response, Timer, WireError, FRAGMENT_DATA, MAX_REPLY,
};

/// Decodes `payload`, which must be refused.
fn refused(payload: &[u8], what: &str) -> WireError {
    match Response::decode(payload, Timer::NANOS) {
        Err(e) => e,
        Ok(r) => panic!("{what}: decoded as {r:?}"),
    }
}

/// A BATCH_REPLY header with `count` entries.
fn batch_reply(count: u16) -> Vec<u8> {
    let mut p = vec![1, kind::BATCH_REPLY];
    p.extend_from_slice(&count.to_le_bytes());
    p
}

/// A SAMPLES entry's head: code, t0, step, samples, runs.
fn samples_head(p: &mut Vec<u8>, samples: u16, runs: u16) {
    p.push(0x0F);
    p.extend_from_slice(&0u64.to_le_bytes());
    p.extend_from_slice(&1_000u64.to_le_bytes());
    p.extend_from_slice(&samples.to_le_bytes());
    p.extend_from_slice(&runs.to_le_bytes());
}

#[test]
fn a_reply_count_past_the_bytes_is_refused_before_reserving() {
    // 65,535 entries promised, 1,100 DELAYED entries (9 bytes) given:
    // reserving for the promise would take megabytes.
    let mut p = batch_reply(u16::MAX);
    for _ in 0..1_100 {
        p.push(0x06);
        p.extend_from_slice(&5u64.to_le_bytes());
    }
    let e = refused(&p, "count 65535");
    assert!(
        matches!(e, WireError::BadValue { field: "count", .. }),
        "{e}"
    );
}

#[test]
fn a_samples_run_longer_than_its_entry_is_refused_before_expanding() {
    // 512 samples, one run that claims 65,535 of them: expanding it would
    // push 131,070 replies.
    let mut p = batch_reply(1);
    samples_head(&mut p, 512, 1);
    p.extend_from_slice(&u16::MAX.to_le_bytes());
    p.extend_from_slice(&[0, 0, 0, 0]);
    let e = refused(&p, "a run of 65535");
    assert!(
        matches!(
            e,
            WireError::BadValue {
                field: "sample run length",
                ..
            }
        ),
        "{e}"
    );
    // A run of no samples, and more runs than samples, are lies too.
    let mut p = batch_reply(1);
    samples_head(&mut p, 2, 1);
    p.extend_from_slice(&0u16.to_le_bytes());
    p.extend_from_slice(&[0, 0, 0, 0]);
    refused(&p, "a run of 0");
    let mut p = batch_reply(1);
    samples_head(&mut p, 2, 3);
    for _ in 0..3 {
        p.extend_from_slice(&1u16.to_le_bytes());
        p.extend_from_slice(&[0, 0, 0, 0]);
    }
    refused(&p, "3 runs of 2 samples");
}

#[test]
fn a_reply_standing_for_more_ops_than_a_batch_holds_is_refused() {
    // 453 entries of 512 samples fit 12,240 bytes: 463,872 replies, where
    // a batch of MAX_BATCH_OPS SAMPLE ops has at most 131,072.
    let entries = 453u16;
    let mut p = batch_reply(entries);
    for _ in 0..entries {
        samples_head(&mut p, 512, 1);
        p.extend_from_slice(&512u16.to_le_bytes());
        p.extend_from_slice(&[0, 0, 0, 0]);
    }
    assert!(p.len() <= MAX_REPLY);
    let r = Response::decode(&p, Timer::NANOS);
    assert!(
        matches!(
            r,
            Err(WireError::BadValue {
                field: "samples (more replies than a batch can ask for)",
                ..
            })
        ),
        "{r:?}"
    );
}

#[test]
fn capture_counts_past_the_bytes_are_refused() {
    // CAPTURE_REPLY: 65,535 pulse runs promised in a short payload, then
    // the same for pin changes and move starts after an empty run list.
    let mut p = vec![1, kind::CAPTURE_REPLY];
    p.extend_from_slice(&u16::MAX.to_le_bytes());
    p.extend_from_slice(&[0; 200]);
    refused(&p, "65535 runs");
    for skip in [1, 2] {
        let mut p = vec![1, kind::CAPTURE_REPLY];
        for _ in 0..skip {
            p.extend_from_slice(&0u16.to_le_bytes());
        }
        p.extend_from_slice(&u16::MAX.to_le_bytes());
        p.extend_from_slice(&[0; 200]);
        refused(&p, "65535 pins or moves");
    }
}

#[test]
fn a_response_longer_than_the_protocol_allows_is_refused() {
    let mut p = batch_reply(0);
    p.resize(MAX_REPLY + 1, 0);
    let e = refused(&p, "12,241 bytes");
    assert!(
        matches!(
            e,
            WireError::BadValue {
                field: "response length",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn a_fragment_longer_than_a_fragment_is_not_one() {
    let mut f = vec![1, kind::FRAGMENT, 0, 255];
    f.resize(4 + FRAGMENT_DATA, 7);
    assert!(parse_fragment(&f).is_some());
    // 255 frames of 4 KiB would be a megabyte held for one reply.
    f.resize(4 + 4_000, 7);
    assert_eq!(parse_fragment(&f), None);
}

//! Does nothing with its input: libFuzzer's own cost per input on this
//! machine, the ceiling the other targets are measured against
//! (`scripts/fuzz-figures`). Not fuzzed in CI: there is nothing to find.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    std::hint::black_box(data);
});

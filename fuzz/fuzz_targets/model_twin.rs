#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| ppmc::fuzzing::targets::model_twin(data));

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| thm_fuzz::checks::eos_csv(data));

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| thm_fuzz::checks::packing_csv(data));

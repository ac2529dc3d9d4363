#![no_main]
//! Fuzz target `log_reader`: the body lives in `vrpn::fuzzing::log_reader`, which tests/fuzz_corpus.rs
//! also runs over the corpus and deterministic mutations.

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    vrpn::fuzzing::log_reader(data);
});

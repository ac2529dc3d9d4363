#![no_main]
//! Fuzz target `config`: the body lives in `vrpn::fuzzing::config`, which tests/fuzz_corpus.rs
//! also runs over the corpus and deterministic mutations.

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    vrpn::fuzzing::config(data);
});

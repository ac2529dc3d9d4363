#![no_main]
//! Fuzz target `handshake`: the body lives in `vrpn::fuzzing::handshake`, which tests/fuzz_corpus.rs
//! also runs over the corpus and deterministic mutations.

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    vrpn::fuzzing::handshake(data);
});

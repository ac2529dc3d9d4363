#![no_main]
//! Fuzz target `wire_stream`: the body lives in `vrpn::fuzzing::wire_stream`, which tests/fuzz_corpus.rs
//! also runs over the corpus and deterministic mutations.

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    vrpn::fuzzing::wire_stream(data);
});

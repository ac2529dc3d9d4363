#![no_main]
//! Fuzz target `wire_datagram`: the body lives in `vrpn::fuzzing::wire_datagram`, which tests/fuzz_corpus.rs
//! also runs over the corpus and deterministic mutations.

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    vrpn::fuzzing::wire_datagram(data);
});

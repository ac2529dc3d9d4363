//! Comparing what a client heard from a change-reporting device (buttons, analog channels
//! sent when they change) with what its simulator sent, for the end-to-end driver tests.
//!
//! The simulator gives the reports a client must receive, each with the record that causes
//! it (`None` for a report no record causes, such as a time-out's). What the client heard
//! must be one contiguous run of them, each stamped with the arrival of its record's first
//! byte. After a start-up or a reopen, the first record the driver reads is reported against
//! the state the driver had, not the state the simulator's previous (unread) record left:
//! `skip_first` drops the reports of that first record (all carry the same stamp).
#![allow(dead_code)]

use std::fmt::Debug;
use std::time::{Duration, Instant};

use vrpn::sim::rig::{assert_first_byte_stamps, assert_run_of};
use vrpn::{Now, TimeVal};

/// Checks `got` (reports heard, with their stamps) against `want` (reports the simulator's
/// log implies, with their records) from `want[after..]` on; `sent_at[i]` is when record
/// `i`'s first byte left the simulator. Returns how many reports were compared.
pub fn check_run<T: PartialEq + Debug + Clone>(
    got: &[(T, TimeVal)],
    want: &[(T, Option<usize>)],
    sent_at: &[Instant],
    after: usize,
    skip_first: bool,
    t0: Now,
    what: &str,
) -> usize {
    let skip = if skip_first {
        got.iter().take_while(|g| g.1 == got[0].1).count()
    } else {
        0
    };
    let got = &got[skip..];
    let values: Vec<T> = got.iter().map(|g| g.0.clone()).collect();
    let wanted: Vec<T> = want.iter().map(|w| w.0.clone()).collect();
    let runs = assert_run_of(&values, &wanted, after, what);
    let start = runs[0];
    let (stamps, at): (Vec<TimeVal>, Vec<Instant>) = got
        .iter()
        .zip(&want[start..])
        .filter_map(|(g, w)| w.1.map(|r| (g.1, sent_at[r])))
        .unzip();
    if !stamps.is_empty() {
        assert_first_byte_stamps(&stamps, &at, t0, Duration::from_millis(250), what);
    }
    values.len()
}

/// The index in `want` of the first report caused by record `record` or a later one.
pub fn first_from<T>(want: &[(T, Option<usize>)], record: usize) -> usize {
    want.iter()
        .position(|w| w.1.is_some_and(|r| r >= record))
        .unwrap_or(want.len())
}

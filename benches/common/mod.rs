//! A tiny benchmark harness shared by the benches (no criterion): run a closure N times, keep
//! every per-iteration time in nanoseconds, print median / p99 / max.

#![allow(dead_code)]

use std::time::{Duration, Instant};

/// Per-iteration timings of one measurement, sorted, in nanoseconds.
pub struct Samples {
    pub name: String,
    sorted: Vec<u64>,
}

impl Samples {
    pub fn from_ns(name: &str, mut ns: Vec<u64>) -> Samples {
        assert!(!ns.is_empty(), "{name}: no samples");
        ns.sort_unstable();
        Samples {
            name: name.to_string(),
            sorted: ns,
        }
    }

    /// The value below which `q` (0..=1) of the samples lie.
    pub fn quantile(&self, q: f64) -> u64 {
        let i = ((self.sorted.len() - 1) as f64 * q).round() as usize;
        self.sorted[i]
    }

    pub fn median(&self) -> u64 {
        self.quantile(0.5)
    }

    pub fn p99(&self) -> u64 {
        self.quantile(0.99)
    }

    pub fn max(&self) -> u64 {
        *self.sorted.last().unwrap()
    }

    pub fn len(&self) -> usize {
        self.sorted.len()
    }

    /// One line: name, count, median, p99, max in microseconds.
    pub fn print_us(&self) {
        println!(
            "{:<44} n={:<6} p50 {:>8.2} µs   p99 {:>8.2} µs   max {:>9.2} µs",
            self.name,
            self.len(),
            self.median() as f64 / 1e3,
            self.p99() as f64 / 1e3,
            self.max() as f64 / 1e3
        );
    }

    /// One line: name, count, median, p99, max in nanoseconds.
    pub fn print_ns(&self) {
        println!(
            "{:<44} n={:<6} p50 {:>8.1} ns   p99 {:>8.1} ns   max {:>9.1} ns",
            self.name,
            self.len(),
            self.median() as f64,
            self.p99() as f64,
            self.max() as f64
        );
    }
}

/// Runs `warmup` untimed iterations, then `n` timed ones; `f` returns nothing useful.
pub fn run(name: &str, warmup: usize, n: usize, mut f: impl FnMut()) -> Samples {
    for _ in 0..warmup {
        f();
    }
    let mut ns = Vec::with_capacity(n);
    for _ in 0..n {
        let t = Instant::now();
        f();
        ns.push(t.elapsed().as_nanos() as u64);
    }
    Samples::from_ns(name, ns)
}

/// Like [`run`], but each timed iteration does `batch` calls and records the mean per call.
pub fn run_batched(
    name: &str,
    warmup_batches: usize,
    batches: usize,
    batch: usize,
    mut f: impl FnMut(),
) -> Samples {
    for _ in 0..warmup_batches * batch {
        f();
    }
    let mut ns = Vec::with_capacity(batches);
    for _ in 0..batches {
        let t = Instant::now();
        for _ in 0..batch {
            f();
        }
        ns.push(t.elapsed().as_nanos() as u64 / batch as u64);
    }
    Samples::from_ns(name, ns)
}

/// Prints the median ratio of `what` to `baseline` and whether it meets `target`.
pub fn print_ratio(what: &Samples, baseline: &Samples, target: f64) {
    let r = what.median() as f64 / baseline.median() as f64;
    let verdict = if r <= target { "meets" } else { "MISSES" };
    println!(
        "    ratio p50 {} / {} = {:.2}×  ({verdict} target {:.2}×)",
        what.name, baseline.name, r, target
    );
}

/// Spins `f` until it returns true, panicking after `limit` (a stuck benchmark must not hang).
#[inline]
pub fn spin_until(limit: Duration, mut f: impl FnMut() -> bool) {
    let start = Instant::now();
    let mut spins = 0u32;
    while !f() {
        spins = spins.wrapping_add(1);
        if spins % 4096 == 0 && start.elapsed() > limit {
            panic!("benchmark stalled for {limit:?}");
        }
    }
}

/// Prints a rate in messages per second.
pub fn print_rate(name: &str, count: u64, elapsed: Duration, extra: &str) {
    let rate = count as f64 / elapsed.as_secs_f64();
    println!(
        "{:<44} {:>12.0} reports/s   ({count} in {:.3} s){extra}",
        name,
        rate,
        elapsed.as_secs_f64()
    );
}

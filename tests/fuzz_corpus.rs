//! The fuzz targets of `fuzz/` as plain tests: every corpus file, then deterministic
//! pseudo-random mutations of each (bit flips, truncations, length-field edits, splices), so CI
//! exercises the same bodies (`vrpn::fuzzing`) without libFuzzer or a nightly toolchain.
//!
//! `VRPN_FUZZ_MUTATIONS=N` sets the mutations per target (default below).

use std::path::Path;

/// xorshift64*: small, deterministic, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
}

fn corpus(target: &str) -> Vec<Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(target);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    let out: Vec<Vec<u8>> = files.iter().map(|p| std::fs::read(p).unwrap()).collect();
    assert!(!out.is_empty(), "empty corpus for {target}");
    out
}

/// Offsets where a VRPN message header (length field) is likely: after the cookie, every
/// header found by walking the lengths. Used to aim length-field edits.
fn header_offsets(data: &[u8], start: usize) -> Vec<usize> {
    let mut out = Vec::new();
    let mut at = start;
    while at + 24 <= data.len() && out.len() < 256 {
        out.push(at);
        let len = u32::from_be_bytes([data[at], data[at + 1], data[at + 2], data[at + 3]]) as usize;
        if len < 24 {
            break;
        }
        at += (len + 7) & !7;
    }
    out
}

fn mutate(rng: &mut Rng, seed: &[u8], others: &[Vec<u8>], header_start: usize) -> Vec<u8> {
    let mut d = seed.to_vec();
    let rounds = 1 + rng.below(4);
    for _ in 0..rounds {
        match rng.below(8) {
            0 | 1 => {
                // bit flips
                for _ in 0..1 + rng.below(8) {
                    if !d.is_empty() {
                        let i = rng.below(d.len());
                        d[i] ^= 1 << rng.below(8);
                    }
                }
            }
            2 => {
                // truncation
                let n = rng.below(d.len() + 1);
                d.truncate(n);
            }
            3 | 4 => {
                // length-field edit at a header
                let hs = header_offsets(&d, header_start);
                if !hs.is_empty() {
                    let at = hs[rng.below(hs.len())];
                    let v: u32 = match rng.below(7) {
                        0 => 0,
                        1 => 23,
                        2 => 24,
                        3 => u32::MAX,
                        4 => 64_008 + 24,
                        5 => 64_008 + 25,
                        _ => rng.next() as u32 % 70_000,
                    };
                    d[at..at + 4].copy_from_slice(&v.to_be_bytes());
                } else if d.len() >= 4 {
                    let at = rng.below(d.len() - 3);
                    d[at..at + 4].copy_from_slice(&(rng.next() as u32).to_be_bytes());
                }
            }
            5 => {
                // interesting byte values
                if !d.is_empty() {
                    let i = rng.below(d.len());
                    d[i] = [0, 0xff, 0x7f, 0x80, b' ', b'\n', b'#', b'\\'][rng.below(8)];
                }
            }
            6 => {
                // splice with another corpus entry
                let o = &others[rng.below(others.len())];
                if !o.is_empty() {
                    let a = rng.below(o.len());
                    let b = a + rng.below(o.len() - a + 1);
                    let at = rng.below(d.len() + 1);
                    d.splice(at..at, o[a..b].iter().copied());
                }
            }
            _ => {
                // duplicate or delete a range
                if d.len() > 1 {
                    let a = rng.below(d.len());
                    let b = (a + 1 + rng.below(64)).min(d.len());
                    if rng.below(2) == 0 {
                        let chunk = d[a..b].to_vec();
                        d.splice(a..a, chunk);
                    } else {
                        d.drain(a..b);
                    }
                }
            }
        }
    }
    d
}

fn mutations(default: usize) -> usize {
    std::env::var("VRPN_FUZZ_MUTATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Runs `f` over the corpus, then over `n` mutations; on a panic, names the input.
fn run(target: &str, n: usize, header_start: usize, f: fn(&[u8])) {
    let seeds = corpus(target);
    for (i, s) in seeds.iter().enumerate() {
        check(target, &format!("corpus #{i}"), s, f);
    }
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ target.len() as u64);
    for k in 0..n {
        let seed = &seeds[k % seeds.len()];
        let input = mutate(&mut rng, seed, &seeds, header_start);
        check(target, &format!("mutation #{k}"), &input, f);
    }
    eprintln!(
        "{target}: {} corpus inputs + {n} mutations, no panic",
        seeds.len()
    );
}

fn check(target: &str, what: &str, input: &[u8], f: fn(&[u8])) {
    let r = std::panic::catch_unwind(|| f(input));
    if r.is_err() {
        let path = std::env::temp_dir().join(format!("vrpn-fuzz-{target}-crash.bin"));
        let _ = std::fs::write(&path, input);
        panic!(
            "{target} panicked on {what} ({} bytes), saved to {}",
            input.len(),
            path.display()
        );
    }
}

#[test]
fn wire_stream() {
    // Byte 0 is the split seed, bytes 1..25 the cookie.
    run(
        "wire_stream",
        mutations(4000),
        25,
        vrpn::fuzzing::wire_stream,
    );
}

#[test]
fn wire_datagram() {
    run(
        "wire_datagram",
        mutations(4000),
        0,
        vrpn::fuzzing::wire_datagram,
    );
}

#[test]
fn log_reader() {
    run("log_reader", mutations(3000), 24, vrpn::fuzzing::log_reader);
}

#[test]
fn config() {
    run("config", mutations(3000), 0, vrpn::fuzzing::config);
}

#[test]
fn handshake() {
    // Each input is a real server and socket: keep the count small.
    let n = std::env::var("VRPN_FUZZ_MUTATIONS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .map(|v| v / 10)
        .unwrap_or(150);
    run("handshake", n, 25, vrpn::fuzzing::handshake);
}

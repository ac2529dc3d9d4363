//! A fake parallel port for the Python box's tests: a [`StatusSource`] whose status register
//! the test sets, that can bounce, refuse to open and fail reads, and that logs every value
//! set with its time (to compute what a client must receive, and when).
//!
//! It stands in for `ppdev`; the ioctls themselves are not exercised by it.

use std::io;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, AtomicU8, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use super::source::StatusSource;

/// The status register with every button released (SELECT, PAPER-OUT, ERROR and ACK high,
/// BUSY's register bit low).
pub const RELEASED: u8 = 0x78;

#[derive(Debug, Default)]
struct Shared {
    status: AtomicU8,
    bounce_reads: AtomicU32,
    fail_open: AtomicBool,
    fail_read: AtomicBool,
    reads: AtomicU64,
    opens: AtomicU64,
    log: Mutex<Vec<(Instant, u8)>>,
}

/// A fake port; clones share it (one for the device, one for the test, across threads).
#[derive(Clone, Debug)]
pub struct FakeParport {
    shared: Arc<Shared>,
    open: bool,
    path: String,
}

impl FakeParport {
    /// A port at `path` with every button released.
    pub fn new(path: &str) -> FakeParport {
        let shared = Shared::default();
        shared.status.store(RELEASED, Ordering::SeqCst);
        FakeParport {
            shared: Arc::new(shared),
            open: false,
            path: path.to_owned(),
        }
    }

    /// Sets the status register at `at` (logged).
    pub fn set_at(&self, status: u8, at: Instant) {
        self.shared.status.store(status, Ordering::SeqCst);
        if let Ok(mut log) = self.shared.log.lock() {
            log.push((at, status));
        }
    }

    /// Sets the status register now.
    pub fn set(&self, status: u8) {
        self.set_at(status, Instant::now());
    }

    /// The next `reads` reads alternate between the register and the register with SELECT
    /// flipped (a bouncing contact).
    pub fn bounce(&self, reads: u32) {
        self.shared.bounce_reads.store(reads, Ordering::SeqCst);
    }

    /// Opening fails (NotFound) while true: the port is gone.
    pub fn fail_opens(&self, on: bool) {
        self.shared.fail_open.store(on, Ordering::SeqCst);
    }

    /// Reads fail (EIO) while true.
    pub fn fail_reads(&self, on: bool) {
        self.shared.fail_read.store(on, Ordering::SeqCst);
    }

    /// Every value set, with its time.
    pub fn log(&self) -> Vec<(Instant, u8)> {
        self.shared
            .log
            .lock()
            .map(|l| l.clone())
            .unwrap_or_default()
    }

    /// Reads so far.
    pub fn reads(&self) -> u64 {
        self.shared.reads.load(Ordering::SeqCst)
    }

    /// Successful opens so far.
    pub fn opens(&self) -> u64 {
        self.shared.opens.load(Ordering::SeqCst)
    }
}

impl StatusSource for FakeParport {
    fn open(&mut self) -> io::Result<()> {
        if self.shared.fail_open.load(Ordering::SeqCst) {
            return Err(io::Error::from(io::ErrorKind::NotFound));
        }
        self.open = true;
        self.shared.opens.fetch_add(1, Ordering::SeqCst);
        Ok(())
    }

    fn read_status(&mut self) -> io::Result<u8> {
        if !self.open {
            return Err(io::Error::from(io::ErrorKind::NotConnected));
        }
        if self.shared.fail_read.load(Ordering::SeqCst) {
            return Err(io::Error::from_raw_os_error(nix::libc::EIO));
        }
        let n = self.shared.reads.fetch_add(1, Ordering::SeqCst);
        let s = self.shared.status.load(Ordering::SeqCst);
        let bouncing = self
            .shared
            .bounce_reads
            .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |b| b.checked_sub(1))
            .is_ok();
        Ok(if bouncing && n % 2 == 1 { s ^ 0x10 } else { s })
    }

    fn close(&mut self) {
        self.open = false;
    }

    fn path(&self) -> &str {
        &self.path
    }
}

/// The buttons a client must see pressed for a status register value: button 0 while
/// SELECT (bit 4) is low, 1 while BUSY's register bit (7) is high, 2 while PAPER-OUT (5) is
/// low, 3 while ERROR (3) is low, 4 while ACK (6) is low.
pub fn expected_buttons(status: u8) -> [bool; 5] {
    let bit = |n: u8| status >> n & 1 == 1;
    [!bit(4), bit(7), !bit(5), !bit(3), !bit(6)]
}

/// The changes a client must receive for the values in `log` (from all released):
/// (index in `log`, button, pressed).
pub fn expected_changes(log: &[(Instant, u8)]) -> Vec<(usize, usize, bool)> {
    let mut state = [false; 5];
    let mut out = Vec::new();
    for (i, &(_, s)) in log.iter().enumerate() {
        let next = expected_buttons(s);
        for b in 0..5 {
            if next[b] != state[b] {
                out.push((i, b, next[b]));
            }
        }
        state = next;
    }
    out
}

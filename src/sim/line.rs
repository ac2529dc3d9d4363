//! A virtual serial line for tests: a [`SerialDriver`] on one end, a [`DeviceModel`] (a device
//! simulator) on the other, both on a virtual clock, with faults on demand. [`VirtualLines`]
//! runs several such lines on one clock, for devices whose ports cooperate.
//!
//! Nothing here sleeps or reads a clock, so a test runs a device through its whole reset
//! sequence, a watchdog time-out and a reopen in microseconds of real time, and the same seed
//! gives the same run. The same device models also run on real pseudo-terminals in the
//! end-to-end tests.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::serial::{PortOp, PortOps, SerialDriver};
use crate::time::Now;

/// The device end of a serial line: what a simulator implements.
pub trait DeviceModel {
    /// Bytes the host wrote reach the device.
    fn receive(&mut self, bytes: &[u8], now: Now);
    /// The host set RTS.
    fn set_rts(&mut self, _on: bool, _now: Now) {}
    /// The host set DTR.
    fn set_dtr(&mut self, _on: bool, _now: Now) {}
    /// The host changed the line's speed (a device told to switch its own rate checks that
    /// the host followed; bytes at a mismatched rate are garbage to either end).
    fn set_baud(&mut self, _baud: u32, _now: Now) {}
    /// Appends to `out` what the device sends at or before `now` (streamed records, replies).
    fn transmit(&mut self, now: Now, out: &mut Vec<u8>);
    /// When the device next has something to send by itself (streaming), if ever.
    fn next_deadline(&self) -> Option<Instant>;
}

/// A small deterministic generator (xorshift64*), so faults are repeatable from a seed.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from `seed` (0 is replaced by a fixed non-zero value).
    pub fn new(seed: u64) -> Rng {
        Rng(if seed == 0 {
            0x9E37_79B9_7F4A_7C15
        } else {
            seed
        })
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// A number in `0..n` (`n` > 0).
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n.max(1)
    }
}

/// A driver and a device model joined by a virtual serial line.
///
/// Bytes the device sends reach the driver `latency` later, in reads that are split at random
/// points when [`split_reads`](Self::split_reads) is on (so parsers see records in pieces).
/// Bytes the driver writes reach the device at once.
pub struct VirtualLine<D: SerialDriver, M: DeviceModel> {
    /// The driver under test.
    pub driver: D,
    /// The simulated device.
    pub device: M,
    now: Now,
    ops: PortOps,
    to_host: VecDeque<(Instant, u8)>,
    scratch: Vec<u8>,
    read_buf: Vec<u8>,
    /// Delay from the device sending a byte to the host's poll waking for it.
    pub latency: Duration,
    /// Deliver device output in randomly split reads.
    pub split_reads: bool,
    /// A slow reader (a loaded machine): the poll wakes for a byte, the read comes this much
    /// later and takes everything that arrived by then, all stamped with the wake time.
    pub read_lag: Duration,
    rng: Rng,
    /// Device output is lost while true (a silent or unplugged device).
    pub silent: bool,
    open: bool,
    reopen_at: Option<Instant>,
    /// Time the line takes to come back after [`close`](Self::close).
    pub reopen_delay: Duration,
    /// Every write the driver made, in order, with its time (for asserting reset sequences).
    pub written: Vec<(Instant, Vec<u8>)>,
    /// Times the port was opened (the first open included).
    pub opens: usize,
}

impl<D: SerialDriver, M: DeviceModel> VirtualLine<D, M> {
    /// Joins `driver` and `device`, opens the port at `start` and calls the driver's `opened`.
    pub fn new(driver: D, device: M, start: Now, seed: u64) -> VirtualLine<D, M> {
        let mut line = VirtualLine {
            driver,
            device,
            now: start,
            ops: PortOps::new(),
            to_host: VecDeque::new(),
            scratch: Vec::new(),
            read_buf: Vec::new(),
            latency: Duration::from_micros(50),
            split_reads: false,
            read_lag: Duration::ZERO,
            rng: Rng::new(seed),
            silent: false,
            open: false,
            reopen_at: None,
            reopen_delay: Duration::from_millis(500),
            written: Vec::new(),
            opens: 0,
        };
        line.open_port();
        line
    }

    /// The virtual time.
    pub fn now(&self) -> Now {
        self.now
    }

    /// True while the port is open.
    pub fn is_open(&self) -> bool {
        self.open
    }

    fn open_port(&mut self) {
        self.open = true;
        self.opens += 1;
        self.to_host.clear();
        self.driver.opened(self.now, &mut self.ops);
        self.carry_out();
    }

    /// Closes the port as an unplugged device would; it comes back after `reopen_delay`.
    pub fn close(&mut self) {
        if !self.open {
            return;
        }
        self.open = false;
        self.to_host.clear();
        self.driver.closed(self.now);
        self.reopen_at = Some(self.now.mono + self.reopen_delay);
    }

    /// Puts `bytes` on the line towards the host now, as line noise would.
    pub fn inject(&mut self, bytes: &[u8]) {
        let at = self.now.mono + self.latency;
        self.to_host.extend(bytes.iter().map(|&b| (at, b)));
    }

    fn carry_out(&mut self) {
        let mut reopen = false;
        for op in self.ops.ops().iter().copied() {
            match op {
                PortOp::Write { start, len } => {
                    let bytes = self.ops.write_bytes(start, len).to_vec();
                    if self.open {
                        self.device.receive(&bytes, self.now);
                    }
                    self.written.push((self.now.mono, bytes));
                }
                PortOp::FlushInput => {
                    let now = self.now.mono;
                    self.to_host.retain(|&(at, _)| at > now);
                }
                PortOp::FlushOutput => {}
                PortOp::SetRts(on) => self.device.set_rts(on, self.now),
                PortOp::SetDtr(on) => self.device.set_dtr(on, self.now),
                PortOp::SetBaud(baud) => self.device.set_baud(baud, self.now),
                PortOp::Reopen => reopen = true,
            }
        }
        self.ops.clear();
        if reopen && self.open {
            self.open_port();
        }
    }

    fn collect_device_output(&mut self) {
        self.scratch.clear();
        self.device.transmit(self.now, &mut self.scratch);
        if self.silent || !self.open {
            return;
        }
        let at = self.now.mono + self.latency;
        for &b in &self.scratch {
            self.to_host.push_back((at, b));
        }
    }

    fn deliver_due(&mut self) {
        loop {
            let Some(&(at, _)) = self.to_host.front() else {
                return;
            };
            if at + self.read_lag > self.now.mono || !self.open {
                return;
            }
            // Everything that arrived by the read is what it returns; a split read returns
            // only a prefix of it.
            let read_at = at + self.read_lag;
            let ready = self
                .to_host
                .iter()
                .take_while(|(t, _)| *t <= read_at)
                .count();
            let n = if self.split_reads && ready > 1 {
                1 + self.rng.below(ready as u64) as usize
            } else {
                ready
            };
            self.read_buf.clear();
            self.read_buf
                .extend(self.to_host.drain(..n).map(|(_, b)| b));
            let arrived = self.at(at);
            let bytes = std::mem::take(&mut self.read_buf);
            self.driver.received(&bytes, arrived, &mut self.ops);
            self.read_buf = bytes;
            self.carry_out();
        }
    }

    /// `at` (not later than now) as a reading of both virtual clocks.
    fn at(&self, at: Instant) -> Now {
        let behind = self.now.mono.saturating_duration_since(at);
        Now {
            mono: at,
            wall: self.now.wall.plus_secs(-behind.as_secs_f64()),
        }
    }

    /// The earliest moment anything on the line needs attention.
    fn next_event(&self) -> Option<Instant> {
        [
            self.driver.next_deadline(),
            self.device.next_deadline(),
            self.to_host.front().map(|&(t, _)| t + self.read_lag),
            self.reopen_at,
        ]
        .into_iter()
        .flatten()
        .min()
    }

    /// Runs everything due at the current time: a pending reopen, the device's output, the
    /// reads that arrived, the driver's deadline.
    fn run_due(&mut self) {
        if self.reopen_at.is_some_and(|t| t <= self.now.mono) {
            self.reopen_at = None;
            self.open_port();
        }
        self.collect_device_output();
        self.deliver_due();
        if self
            .driver
            .next_deadline()
            .is_some_and(|d| d <= self.now.mono)
        {
            self.driver.poll(self.now, &mut self.ops);
            self.carry_out();
        }
    }

    /// Moves the virtual clock to `t` (not earlier than now).
    fn advance_to(&mut self, t: Instant) {
        if t > self.now.mono {
            self.now = self.now.plus(t - self.now.mono);
        }
    }

    /// Runs everything due at the current time, then moves the clock to the next event (but
    /// not past `limit`). Returns false when nothing is scheduled before `limit`.
    pub fn step(&mut self, limit: Instant) -> bool {
        self.run_due();
        match self.next_event() {
            Some(t) if t <= limit => {
                // Always make progress, even when an event is already due.
                let t = t.max(self.now.mono + Duration::from_micros(1));
                if t > limit {
                    return false;
                }
                self.now = self.now.plus(t - self.now.mono);
                true
            }
            _ => false,
        }
    }

    /// Runs the line for `d` of virtual time.
    pub fn run_for(&mut self, d: Duration) {
        let limit = self.now.mono + d;
        while self.step(limit) {}
        if self.now.mono < limit {
            self.now = self.now.plus(limit - self.now.mono);
            self.step(limit);
        }
    }

    /// Runs until `done` holds or `max` of virtual time passes; returns whether `done` held.
    pub fn run_until(&mut self, max: Duration, mut done: impl FnMut(&mut Self) -> bool) -> bool {
        let limit = self.now.mono + max;
        loop {
            if done(self) {
                return true;
            }
            if !self.step(limit) {
                if self.now.mono >= limit {
                    return done(self);
                }
                self.now = self.now.plus(limit - self.now.mono);
            }
        }
    }
}

/// Several virtual lines on one virtual clock, for devices that need cooperating ports (a
/// master line and one line per receiver, say).
///
/// Each line keeps its own faults ([`VirtualLine::split_reads`], [`VirtualLine::silent`],
/// [`VirtualLine::inject`], [`VirtualLine::close`], …); time moves for all of them together,
/// so drivers (and device models) that share state see one consistent clock. At each moment
/// every line runs what is due, in index order, and again while one line's work made another
/// due at the same moment. Move time only through these methods (not a line's own
/// [`VirtualLine::run_for`]), or the lines' clocks part.
pub struct VirtualLines<D: SerialDriver, M: DeviceModel> {
    /// The lines, in the order given to [`new`](Self::new).
    pub lines: Vec<VirtualLine<D, M>>,
    now: Now,
}

impl<D: SerialDriver, M: DeviceModel> VirtualLines<D, M> {
    /// Joins each driver to its device model and opens the ports at `start`, in order (line
    /// `i` draws its random faults from `seed + i`).
    pub fn new(pairs: impl IntoIterator<Item = (D, M)>, start: Now, seed: u64) -> Self {
        let lines = pairs
            .into_iter()
            .enumerate()
            .map(|(i, (driver, device))| {
                VirtualLine::new(driver, device, start, seed.wrapping_add(i as u64))
            })
            .collect();
        VirtualLines { lines, now: start }
    }

    /// The virtual time.
    pub fn now(&self) -> Now {
        self.now
    }

    /// Line `i`.
    pub fn line(&mut self, i: usize) -> &mut VirtualLine<D, M> {
        &mut self.lines[i]
    }

    fn earliest_event(&self) -> Option<Instant> {
        self.lines.iter().filter_map(VirtualLine::next_event).min()
    }

    /// Runs everything due now on every line, then moves the clock to the next event on any
    /// line (but not past `limit`). Returns false when nothing is scheduled before `limit`.
    pub fn step(&mut self, limit: Instant) -> bool {
        // A driver's work may make another line due at this same moment (shared state); a
        // few passes settle that without moving the clock.
        for _ in 0..4 {
            for line in &mut self.lines {
                line.run_due();
            }
            if !self.earliest_event().is_some_and(|t| t <= self.now.mono) {
                break;
            }
        }
        match self.earliest_event() {
            Some(t) if t <= limit => {
                let t = t.max(self.now.mono + Duration::from_micros(1));
                if t > limit {
                    return false;
                }
                self.advance_to(t);
                true
            }
            _ => false,
        }
    }

    fn advance_to(&mut self, t: Instant) {
        if t > self.now.mono {
            self.now = self.now.plus(t - self.now.mono);
        }
        for line in &mut self.lines {
            line.advance_to(t);
        }
    }

    /// Runs all lines for `d` of virtual time.
    pub fn run_for(&mut self, d: Duration) {
        let limit = self.now.mono + d;
        while self.step(limit) {}
        if self.now.mono < limit {
            self.advance_to(limit);
            self.step(limit);
        }
    }

    /// Runs until `done` holds or `max` of virtual time passes; returns whether `done` held.
    pub fn run_until(&mut self, max: Duration, mut done: impl FnMut(&mut Self) -> bool) -> bool {
        let limit = self.now.mono + max;
        loop {
            if done(self) {
                return true;
            }
            if !self.step(limit) {
                if self.now.mono >= limit {
                    return done(self);
                }
                self.advance_to(limit);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::serial::{PortKind, PortSettings};
    use crate::time::TimeVal;

    /// Writes `R` when opened; records each byte with its arrival time.
    struct Recorder {
        got: Vec<(u8, Instant)>,
        closed: usize,
    }

    impl SerialDriver for Recorder {
        fn name(&self) -> &str {
            "rec"
        }
        fn port_kind(&self) -> PortKind {
            PortKind::Serial(PortSettings::n81(9600))
        }
        fn opened(&mut self, _now: Now, port: &mut PortOps) {
            port.write(b"R");
        }
        fn received(&mut self, bytes: &[u8], arrived: Now, _port: &mut PortOps) {
            self.got.extend(bytes.iter().map(|&b| (b, arrived.mono)));
        }
        fn poll(&mut self, _now: Now, _port: &mut PortOps) {}
        fn next_deadline(&self) -> Option<Instant> {
            None
        }
        fn closed(&mut self, _now: Now) {
            self.closed += 1;
        }
    }

    /// Answers `R` with `ok`, then streams `abc` every 10 ms.
    struct Streamer {
        next: Option<Instant>,
        reply: bool,
    }

    impl DeviceModel for Streamer {
        fn receive(&mut self, bytes: &[u8], now: Now) {
            if bytes.contains(&b'R') {
                self.reply = true;
                self.next = Some(now.mono + Duration::from_millis(10));
            }
        }
        fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
            if std::mem::take(&mut self.reply) {
                out.extend_from_slice(b"ok");
            }
            while let Some(t) = self.next.filter(|&t| t <= now.mono) {
                out.extend_from_slice(b"abc");
                self.next = Some(t + Duration::from_millis(10));
            }
        }
        fn next_deadline(&self) -> Option<Instant> {
            self.next
        }
    }

    fn line(seed: u64) -> VirtualLine<Recorder, Streamer> {
        let start = Now {
            mono: Instant::now(),
            wall: TimeVal::new(1_000_000, 0),
        };
        VirtualLine::new(
            Recorder {
                got: Vec::new(),
                closed: 0,
            },
            Streamer {
                next: None,
                reply: false,
            },
            start,
            seed,
        )
    }

    #[test]
    fn streams_with_latency_and_reopens() {
        let mut l = line(1);
        let t0 = l.now().mono;
        l.run_for(Duration::from_millis(35));
        let text: Vec<u8> = l.driver.got.iter().map(|g| g.0).collect();
        assert_eq!(text, b"okabcabcabc");
        // The first streamed byte arrives 10 ms + latency after the reset.
        let first_a = l.driver.got[2].1;
        assert_eq!(first_a - t0, Duration::from_millis(10) + l.latency);
        l.close();
        assert_eq!(l.driver.closed, 1);
        l.run_for(Duration::from_millis(600));
        assert_eq!(l.opens, 2);
        assert_eq!(l.written.len(), 2);
    }

    #[test]
    fn lines_share_one_clock_and_keep_their_own_faults() {
        let start = Now {
            mono: Instant::now(),
            wall: TimeVal::new(1_000_000, 0),
        };
        let pair = || {
            (
                Recorder {
                    got: Vec::new(),
                    closed: 0,
                },
                Streamer {
                    next: None,
                    reply: false,
                },
            )
        };
        let mut lines = VirtualLines::new([pair(), pair(), pair()], start, 5);
        lines.line(1).silent = true;
        lines.run_for(Duration::from_millis(15));
        lines.line(2).close();
        lines.run_for(Duration::from_millis(20));
        let t = lines.now().mono;
        assert_eq!(t - start.mono, Duration::from_millis(35));
        for l in &lines.lines {
            assert_eq!(l.now(), lines.now());
        }
        let text = |l: &VirtualLine<Recorder, Streamer>| -> Vec<u8> {
            l.driver.got.iter().map(|g| g.0).collect()
        };
        assert_eq!(text(&lines.lines[0]), b"okabcabcabc");
        assert_eq!(text(&lines.lines[1]), b"");
        // Closed at 15 ms, after one record; still closed.
        assert_eq!(text(&lines.lines[2]), b"okabc");
        assert_eq!(lines.lines[2].driver.closed, 1);
        // Both running lines saw the same byte at the same moment.
        assert_eq!(
            lines.lines[0].driver.got[2].1,
            start.mono + Duration::from_millis(10) + lines.lines[0].latency
        );
        assert!(lines.run_until(Duration::from_secs(1), |ls| ls.lines[2].opens == 2));
        // Reopened 500 ms after the close (the check runs after the step that reopened).
        let reopened = lines.now().mono - start.mono;
        assert!(reopened >= Duration::from_millis(515) && reopened < Duration::from_millis(516));
    }

    #[test]
    fn split_reads_keep_bytes_in_order() {
        let mut l = line(7);
        l.split_reads = true;
        l.inject(b"zz");
        l.run_for(Duration::from_millis(100));
        let text: Vec<u8> = l.driver.got.iter().map(|g| g.0).collect();
        assert!(
            text.starts_with(b"zzokabc"),
            "{:?}",
            String::from_utf8_lossy(&text)
        );
        // Records at 10, 20, …, 90 ms have arrived; the one sent at 100 ms is still on the line.
        assert_eq!(text.len(), 2 + 2 + 3 * 9);
    }
}

//! A simulated inertia mouse: the device's end of its serial line, for tests and for a
//! simulator on a pseudo-terminal.
//!
//! Every [`SimConfig::period`] it sends a `D` record (record `k` holds [`words(k)`](words):
//! channels in order, with channels 4 and 5 swapped in every third record); every
//! [`SimConfig::button_every`] records a `B` record toggling button 0 (so that the
//! integration of channels 0-3 runs half the time). It hears nothing. With
//! [`SimConfig::keep_log`], what a client must receive is logged ([`InertiaSim::sent`]): the
//! six channels after each record that changed them, and each button change, with the time
//! the record's first byte left. The expected channels come from C++'s formulas as
//! [`MouseState`] implements them (checked against hand-computed values in `record`'s
//! tests).

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::record::{encode_data, Applied, MouseState, CHANNELS};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `inertiamouse`.
pub static SIMULATOR: Simulator = Simulator {
    name: "inertiamouse",
    about: "Inertia mouse: streams known channel values and button changes",
    baud: 115200,
    line: "vrpn_inertiamouse Mouse0 {PATH} {BAUD}",
    make: |baud| Box::new(InertiaSim::new(SimConfig::new(baud))),
};

/// With [`SimConfig::wait_for_host`], the first record leaves this long after the host set
/// the line's speed: a driver that flushes its input while opening the port (after setting
/// the speed) would otherwise lose it on a loaded machine, and with it every later value
/// (the filters carry the whole history).
const HOST_SETTLE: Duration = Duration::from_millis(100);

/// How the simulated mouse behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed.
    pub baud: u32,
    /// Time between `D` records.
    pub period: Duration,
    /// A `B` record after every this many `D` records.
    pub button_every: u64,
    /// Sends nothing until the host sets the line's speed (on a pseudo-terminal: opens the
    /// port), so that the driver sees the first record: the filters make every later value
    /// depend on all the records before it.
    pub wait_for_host: bool,
    /// Log what a client must receive.
    pub keep_log: bool,
}

impl SimConfig {
    /// A mouse at `baud`: a `D` record every 10 ms (longer where the line is too slow), a
    /// `B` record every 25, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            period: Duration::from_millis(10),
            button_every: 25,
            wait_for_host: false,
            keep_log: false,
        }
    }
}

/// Record `k`'s channel words: (channel, 10-bit acceleration). Channel 5's acceleration has
/// a zero low nibble (the LF carries it).
pub fn words(k: u64) -> [(u8, u16); CHANNELS] {
    let a = |mul: u64, add: u64| ((k * mul + add) % 1024) as u16;
    let mut w = [
        (0, a(37, 100)),
        (1, a(101, 900)),
        (2, a(7, 300)),
        (3, a(513, 0)),
        (4, a(11, 17)),
        (5, a(97, 5) & 0x3F0),
    ];
    if k % 3 == 2 {
        w.swap(4, 5);
    }
    w
}

/// What a client must receive.
#[derive(Clone, Debug, PartialEq)]
pub enum Sent {
    /// An Analog report: all six channels.
    Analog([f64; CHANNELS], Instant),
    /// A button change.
    Button(usize, bool, Instant),
}

/// The simulated mouse. See the module documentation.
pub struct InertiaSim {
    cfg: SimConfig,
    count: u64,
    button: bool,
    next: Option<Instant>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    state: MouseState,
    reported: [f64; CHANNELS],
    sent: Vec<Sent>,
    /// When the host set the line's speed (opened the port).
    host_seen: Option<Instant>,
}

impl InertiaSim {
    /// A mouse behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> InertiaSim {
        InertiaSim {
            cfg,
            count: 0,
            button: false,
            next: None,
            out: VecDeque::new(),
            line_free: None,
            state: MouseState::default(),
            reported: [0.0; CHANNELS],
            sent: Vec::new(),
            host_seen: None,
        }
    }

    /// What a client must have received (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[Sent] {
        &self.sent
    }

    fn byte_time(&self) -> Duration {
        let b = u64::from(self.cfg.baud.max(1));
        Duration::from_micros((10_000_000 + b / 2) / b)
    }

    fn queue_at(&mut self, bytes: &[u8], at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        let step = self.byte_time();
        for (i, &b) in bytes.iter().enumerate() {
            self.out.push_back((start + step * i as u32, b));
        }
        self.line_free = Some(start + step * bytes.len() as u32);
        start
    }

    fn send_record(&mut self, rec: &[u8], at: Instant) {
        let first = self.queue_at(rec, at);
        let before = self.state.buttons;
        if self.state.apply(rec) != Applied::Report || !self.cfg.keep_log {
            return;
        }
        if self.state.channels != self.reported {
            self.reported = self.state.channels;
            self.sent.push(Sent::Analog(self.reported, first));
        }
        for (i, (was, is)) in before.iter().zip(self.state.buttons).enumerate() {
            if *was != is {
                self.sent.push(Sent::Button(i, is, first));
            }
        }
    }
}

impl DeviceModel for InertiaSim {
    fn receive(&mut self, _bytes: &[u8], _now: Now) {}

    fn set_baud(&mut self, _baud: u32, now: Now) {
        self.host_seen.get_or_insert(now.mono);
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if self.cfg.wait_for_host
            && !self
                .host_seen
                .is_some_and(|seen| now.mono >= seen + HOST_SETTLE)
        {
            return;
        }
        let period = self.cfg.period.max(self.byte_time() * 40);
        let next = *self.next.get_or_insert(now.mono);
        if next <= now.mono {
            let k = self.count;
            self.count += 1;
            self.send_record(&encode_data(words(k)), next);
            if k % self.cfg.button_every.max(1) == self.cfg.button_every.max(1) - 1 {
                self.button = !self.button;
                let rec = [b'B', u8::from(self.button), 0, b'\n'];
                self.send_record(&rec, next);
            }
            self.next = Some(next + period);
        }
        while let Some(&(t, b)) = self.out.front() {
            if t > now.mono {
                break;
            }
            self.out.pop_front();
            out.push(b);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        [self.out.front().map(|&(t, _)| t), self.next]
            .into_iter()
            .flatten()
            .min()
    }
}

//! A simulated serial mouse: the mouse's end of its serial line, for tests and for a
//! simulator on a pseudo-terminal.
//!
//! Every [`SimConfig::period`] (unless [`SimConfig::idle`]) it sends packet `k`
//! ([`packet(kind, k)`](packet)): its buttons change in slow rhythms, it moves a little, and
//! in `3button` mode every seventh packet moves left (its first byte then carries motion
//! bits, so a driver reads nothing from it). Bytes leave at the line's rate. With
//! [`SimConfig::keep_log`] it logs each packet with the time its first byte left;
//! [`expected`] turns the log into the button changes a client must receive, by the rules
//! of the two protocols, written here apart from the driver.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::packet::{MouseType, BUTTONS};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// For `vrpn_device_sim`: a 3-button (Microsoft) mouse.
pub static SIMULATOR: Simulator = Simulator {
    name: "serialmouse",
    about: "serial mouse (Microsoft 3-button): a packet every 40 ms, buttons in slow rhythms",
    baud: 1200,
    line: "vrpn_Button_SerialMouse Mouse0 {PATH} 3button",
    make: |baud| {
        let mut cfg = SimConfig::new(MouseType::ThreeButton);
        cfg.baud = baud;
        Box::new(SerialMouseSim::new(cfg))
    },
};

/// How the simulated mouse behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Its protocol.
    pub kind: MouseType,
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Time between packets.
    pub period: Duration,
    /// Sends nothing while true.
    pub idle: bool,
    /// Log every packet sent.
    pub keep_log: bool,
}

impl SimConfig {
    /// A mouse of `kind` at 1200 baud: a packet every 40 ms (`3button`, 3 bytes take 25 ms)
    /// or 60 ms (`mousesystems`, 5 bytes take 42 ms); no log.
    pub fn new(kind: MouseType) -> SimConfig {
        SimConfig {
            kind,
            baud: 1200,
            period: Duration::from_millis(match kind {
                MouseType::ThreeButton => 40,
                MouseType::MouseSystems => 60,
            }),
            idle: false,
            keep_log: false,
        }
    }
}

/// Packet `k`'s bytes (3 or 5).
pub fn packet(kind: MouseType, k: u64) -> Vec<u8> {
    let left = (k / 3) % 2 == 1;
    let middle = (k / 4) % 2 == 1;
    let right = (k / 5) % 2 == 1;
    match kind {
        MouseType::ThreeButton => {
            let dx: i8 = if k % 7 == 6 { -5 } else { (k % 10) as i8 + 1 };
            let dy: i8 = (k % 4) as i8;
            let (dx, dy) = (dx as u8, dy as u8);
            // As read at 8N1: the stop bit in bit 7, the sync bit in bit 6 of the first byte.
            vec![
                0xC0 | u8::from(left) << 5
                    | u8::from(right) << 4
                    | ((dy >> 6) & 3) << 2
                    | ((dx >> 6) & 3),
                0x80 | (dx & 0x3F),
                0x80 | (dy & 0x3F),
            ]
        }
        MouseType::MouseSystems => {
            let dx = ((k % 20) as i8 - 10) as u8;
            let dy = ((k % 9) as i8 - 4) as u8;
            vec![
                0x80 | u8::from(!left) << 2 | u8::from(!middle) << 1 | u8::from(!right),
                dx,
                dy,
                0,
                0,
            ]
        }
    }
}

/// A packet put on the line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SentPacket {
    /// When its first byte left the mouse.
    pub first_byte: Instant,
    /// Its bytes.
    pub bytes: Vec<u8>,
}

/// A button change a client must receive, and the packet (index in the log) it comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Change {
    /// Button (0 left, 1 middle, 2 right).
    pub button: usize,
    /// Pressed.
    pub pressed: bool,
    /// Its packet.
    pub packet: usize,
}

/// The button changes a client connected from the start must receive for the packets in
/// `log`, read by a driver that saw them all from the first on.
pub fn expected(kind: MouseType, log: &[SentPacket]) -> Vec<Change> {
    let mut out = Vec::new();
    let mut state = [false; BUTTONS];
    // 3button: the middle button after the previous packet, `true` before the first (so the
    // first packet without a change clears it).
    let mut middle_before = true;
    for (i, p) in log.iter().enumerate() {
        let b = p.bytes[0];
        let new = match kind {
            MouseType::MouseSystems => [b & 4 == 0, b & 2 == 0, b & 1 == 0],
            MouseType::ThreeButton => {
                // Only first bytes without motion bits carry the buttons.
                if b & 0x0F != 0 {
                    continue;
                }
                let (l, r) = (b & 0x20 != 0, b & 0x10 != 0);
                let m = if l == state[0] && r == state[2] {
                    !middle_before
                } else {
                    state[1]
                };
                middle_before = m;
                [l, m, r]
            }
        };
        for (button, (&was, &now)) in state.iter().zip(&new).enumerate() {
            if was != now {
                out.push(Change {
                    button,
                    pressed: now,
                    packet: i,
                });
            }
        }
        state = new;
    }
    out
}

/// The simulated mouse. See the module documentation.
pub struct SerialMouseSim {
    cfg: SimConfig,
    count: u64,
    next: Option<Instant>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    sent: Vec<SentPacket>,
}

impl SerialMouseSim {
    /// A mouse behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> SerialMouseSim {
        SerialMouseSim {
            cfg,
            count: 0,
            next: None,
            out: VecDeque::new(),
            line_free: None,
            sent: Vec::new(),
        }
    }

    /// The packets sent so far (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentPacket] {
        &self.sent
    }

    /// Stops or resumes sending.
    pub fn set_idle(&mut self, idle: bool) {
        self.cfg.idle = idle;
    }

    fn send_packet(&mut self, at: Instant) {
        let bytes = packet(self.cfg.kind, self.count);
        self.count += 1;
        let byte_time =
            Duration::from_micros((10e6 / f64::from(self.cfg.baud.max(1))).round() as u64);
        let mut t = self.line_free.map_or(at, |f| f.max(at));
        let first = t;
        for &b in &bytes {
            self.out.push_back((t, b));
            t += byte_time;
        }
        self.line_free = Some(t);
        if self.cfg.keep_log {
            self.sent.push(SentPacket {
                first_byte: first,
                bytes,
            });
        }
    }
}

impl DeviceModel for SerialMouseSim {
    fn receive(&mut self, _bytes: &[u8], _now: Now) {}

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        let next = *self.next.get_or_insert(now.mono);
        if next <= now.mono {
            if !self.cfg.idle {
                self.send_packet(next);
            }
            self.next = Some(next + self.cfg.period);
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

//! A simulated Spaceball: the device end of its serial line, for tests and for a simulator on
//! a pseudo-terminal.
//!
//! What it does:
//!
//! * Each command line the host writes (up to a carriage return) that names a set-up command
//!   (`C`, `N`, `F`, `P`, `M`, `Z`) is answered after [`SimConfig::reply_delay`] by a packet
//!   of that kind (the command's letters, padded to the packet's length). Every byte received
//!   is kept ([`SpaceballSim::heard`]) with its arrival time ([`SpaceballSim::heard_at`]).
//! * While [`SimConfig::touching`], the ball is being moved and its keys pressed: one packet
//!   every [`SimConfig::period`], every fourth a key packet (the 4000 FLX sends a `.` packet
//!   followed by the compatible `K` packet), the others displacement packets. Packet `k`
//!   holds [`sample(k)`](sample); key packet `j` toggles button `j` modulo the model's button
//!   count. What a client must receive for each is computed here ([`Event`]), independently
//!   of the driver.
//! * Data bytes are escaped as the device escapes them (`^Q`, `^S`, `^M`, `^^`), bytes leave
//!   at the line's baud rate, and with [`SimConfig::keep_log`] every reported packet is logged
//!   with the time its first byte left ([`SpaceballSim::sent`]).
//! * Faults: [`SpaceballSim::inject`] puts bytes on the line; [`SpaceballSim::banner`] sends a
//!   reset banner as the device does after a hard reset.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::packet::{kind, Length, AXES, BUTTONS, NULL_RADIUS};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// The simulator `vrpn_device_sim` runs as `spaceball`.
pub static SIMULATOR: Simulator = Simulator {
    name: "spaceball",
    about: "Spaceball 4000 FLX: sends known ball and key packets",
    baud: 9600,
    line: "vrpn_Spaceball Spaceball0 {PATH} {BAUD}",
    make: |baud| Box::new(SpaceballSim::new(SimConfig::new(baud))),
};

/// Which Spaceball.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// A 2003 or 3003 FLX: nine buttons in `K` packets.
    Sb2003,
    /// A 4000 FLX: twelve buttons in `.` packets, each followed by a `K` packet.
    Sb4000,
}

/// How the simulated Spaceball behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Line speed, for the byte pacing.
    pub baud: u32,
    /// Which model.
    pub model: Model,
    /// Time between packets while touched.
    pub period: Duration,
    /// Time from a command to its answer.
    pub reply_delay: Duration,
    /// The ball is being moved (packets stream).
    pub touching: bool,
    /// Log every reported packet.
    pub keep_log: bool,
}

impl SimConfig {
    /// A 4000 FLX at `baud`, touched, a packet every 20 ms, answers after 2 ms, no log.
    pub fn new(baud: u32) -> SimConfig {
        SimConfig {
            baud,
            model: Model::Sb4000,
            period: Duration::from_millis(20),
            reply_delay: Duration::from_millis(2),
            touching: true,
            keep_log: false,
        }
    }

    fn byte_offset(&self, i: usize) -> Duration {
        Duration::from_micros((i as f64 * 10e6 / f64::from(self.baud.max(1))).round() as u64)
    }
}

/// The raw axis values of packet `k`: large values of both signs, some within the null
/// radius, and bytes that need escaping now and then.
pub fn sample(k: u64) -> [i16; AXES] {
    let mul = [977u64, 1553, 2909, 4099, 6007, 7919];
    let mut raw = [0i16; AXES];
    for (i, r) in raw.iter_mut().enumerate() {
        *r = if (k + i as u64) % 11 == 0 {
            (k % 17) as i16 - 8
        } else {
            ((k * mul[i] + 13 * i as u64) % 65_536) as u16 as i16
        };
    }
    raw
}

/// What a client must receive for a packet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// The six channels: raw / 32768, zero within the null radius, Z axes negated.
    Axes([f64; AXES]),
    /// Every button's state after the packet.
    Buttons([bool; BUTTONS]),
}

impl Event {
    /// The channels a displacement packet with `raw` values must produce.
    pub fn axes(raw: [i16; AXES]) -> Event {
        let mut v = raw.map(|r| {
            if r.unsigned_abs() <= NULL_RADIUS as u16 {
                0.0
            } else {
                f64::from(r) / 32768.0
            }
        });
        v[2] = -v[2];
        v[5] = -v[5];
        Event::Axes(v)
    }
}

/// A packet put on the line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SentPacket {
    /// When its first byte left the device.
    pub first_byte: Instant,
    /// What a client must receive for it.
    pub event: Event,
}

/// The simulated Spaceball. See the module documentation.
pub struct SpaceballSim {
    cfg: SimConfig,
    next_packet: Option<Instant>,
    count: u64,
    key_packets: u64,
    buttons: [bool; BUTTONS],
    command: Vec<u8>,
    answers: VecDeque<(Instant, Vec<u8>)>,
    out: VecDeque<(Instant, u8)>,
    line_free: Option<Instant>,
    sent: Vec<SentPacket>,
    heard: Vec<u8>,
    heard_at: Vec<Instant>,
}

impl SpaceballSim {
    /// A Spaceball behaving as `cfg` says.
    pub fn new(cfg: SimConfig) -> SpaceballSim {
        SpaceballSim {
            cfg,
            next_packet: None,
            count: 0,
            key_packets: 0,
            buttons: [false; BUTTONS],
            command: Vec::new(),
            answers: VecDeque::new(),
            out: VecDeque::new(),
            line_free: None,
            sent: Vec::new(),
            heard: Vec::new(),
            heard_at: Vec::new(),
        }
    }

    /// Packets logged (with [`SimConfig::keep_log`]).
    pub fn sent(&self) -> &[SentPacket] {
        &self.sent
    }

    /// Forgets the log.
    pub fn clear_log(&mut self) {
        self.sent.clear();
    }

    /// Every byte the host wrote.
    pub fn heard(&self) -> &[u8] {
        &self.heard
    }

    /// When each byte of [`heard`](Self::heard) arrived.
    pub fn heard_at(&self) -> &[Instant] {
        &self.heard_at
    }

    /// Starts or stops moving the ball.
    pub fn set_touching(&mut self, on: bool) {
        self.cfg.touching = on;
        if !on {
            self.next_packet = None;
        }
    }

    /// Puts `bytes` on the line at `now` (line noise), after what is queued.
    pub fn inject(&mut self, bytes: &[u8], now: Instant) {
        self.queue(bytes, now);
    }

    /// Sends the banner the device sends after a hard reset.
    pub fn banner(&mut self, now: Instant) {
        self.queue(b"\r@1 Spaceball alive and well after a reset.\r", now);
    }

    fn queue(&mut self, bytes: &[u8], at: Instant) -> Instant {
        let start = self.line_free.map_or(at, |f| f.max(at));
        for (i, &b) in bytes.iter().enumerate() {
            self.out.push_back((start + self.cfg.byte_offset(i), b));
        }
        self.line_free = Some(start + self.cfg.byte_offset(bytes.len()));
        start
    }

    /// `letter`, the escaped `data`, and a carriage return.
    fn packet(letter: u8, data: &[u8]) -> Vec<u8> {
        let mut p = vec![letter];
        for &b in data {
            match b {
                0x0D | 0x11 | 0x13 => p.extend_from_slice(&[b'^', b | 0x40]),
                b'^' => p.extend_from_slice(b"^^"),
                _ => p.push(b),
            }
        }
        p.push(b'\r');
        p
    }

    fn log(&mut self, first_byte: Instant, event: Event) {
        if self.cfg.keep_log {
            self.sent.push(SentPacket { first_byte, event });
        }
    }

    fn make_packet(&mut self, at: Instant) {
        let k = self.count;
        self.count += 1;
        if k % 4 != 3 {
            let raw = sample(k);
            let mut data = vec![(k >> 8) as u8, k as u8];
            for r in raw {
                data.extend_from_slice(&r.to_be_bytes());
            }
            let first = self.queue(&Self::packet(b'D', &data), at);
            self.log(first, Event::axes(raw));
            return;
        }
        let n = match self.cfg.model {
            Model::Sb2003 => 9,
            Model::Sb4000 => BUTTONS,
        };
        let b = (self.key_packets % n as u64) as usize;
        self.key_packets += 1;
        self.buttons[b] = !self.buttons[b];
        let s = self.buttons;
        let bit = |i: usize, v: u8| if s[i] { v } else { 0 };
        // The 2003 layout (the 4000 sends it too, after its own packet).
        let k_lo = bit(0, 0x01) | bit(1, 0x02) | bit(2, 0x04) | bit(3, 0x08);
        let k_hi = bit(4, 0x01) | bit(5, 0x02) | bit(6, 0x04) | bit(7, 0x08) | bit(8, 0x10);
        let compat = Self::packet(b'K', &[k_hi, k_lo]);
        let first = match self.cfg.model {
            Model::Sb2003 => self.queue(&compat, at),
            Model::Sb4000 => {
                let lo = (0..6).fold(bit(6, 0x80), |a, i| a | bit(i, 1 << i));
                let hi = (0..5).fold(0x20, |a, i| a | bit(7 + i, 1 << i));
                let first = self.queue(&Self::packet(b'.', &[hi, lo]), at);
                self.queue(&compat, at);
                first
            }
        };
        self.log(first, Event::Buttons(s));
    }

    fn answer(&mut self, now: Instant) {
        let cmd = std::mem::take(&mut self.command);
        let Some(&letter) = cmd.first() else { return };
        if !b"CNFPMZ".contains(&letter) {
            return;
        }
        let Some((_, Length::Fixed(len))) = kind(letter) else {
            return;
        };
        let mut a: Vec<u8> = cmd.iter().copied().take(len - 1).collect();
        a.resize(len - 1, b'@');
        a.push(b'\r');
        self.answers.push_back((now + self.cfg.reply_delay, a));
    }
}

impl DeviceModel for SpaceballSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        for &b in bytes {
            self.heard.push(b);
            self.heard_at.push(now.mono);
            if b == b'\r' {
                self.answer(now.mono);
            } else {
                self.command.push(b);
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        if self.cfg.touching && self.next_packet.is_none() {
            self.next_packet = Some(now.mono);
        }
        while let Some(&(t, _)) = self.answers.front() {
            if t > now.mono {
                break;
            }
            if let Some((t, a)) = self.answers.pop_front() {
                self.queue(&a, t);
            }
        }
        while let Some(t) = self.next_packet.filter(|&t| t <= now.mono) {
            self.make_packet(t);
            self.next_packet = Some(t + self.cfg.period);
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
        [
            self.out.front().map(|&(t, _)| t),
            self.next_packet,
            self.answers.front().map(|&(t, _)| t),
        ]
        .into_iter()
        .flatten()
        .min()
    }
}

/// Turns what a client heard back into one [`Event`] per packet, to compare with
/// [`SpaceballSim::sent`]: each analog report is one packet; the button changes of one key
/// packet share its time stamp and follow an analog report or another time stamp.
#[derive(Clone, Debug, Default)]
pub struct Listener {
    buttons: [bool; BUTTONS],
    /// The events heard, with their time stamps.
    pub events: Vec<(Event, crate::TimeVal)>,
}

impl Listener {
    /// An analog report.
    pub fn analog(&mut self, channels: &[f64], time: crate::TimeVal) {
        let mut v = [f64::NAN; AXES];
        for (d, s) in v.iter_mut().zip(channels) {
            *d = *s;
        }
        self.events.push((Event::Axes(v), time));
    }

    /// A button change.
    pub fn button(&mut self, button: usize, pressed: bool, time: crate::TimeVal) {
        if let Some(b) = self.buttons.get_mut(button) {
            *b = pressed;
        }
        match self.events.last_mut() {
            Some((Event::Buttons(s), t)) if *t == time => *s = self.buttons,
            _ => self.events.push((Event::Buttons(self.buttons), time)),
        }
    }
}

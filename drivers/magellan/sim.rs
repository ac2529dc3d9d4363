//! A simulated Magellan / SpaceMouse: the device end of the serial line.
//!
//! It takes CR-terminated commands and answers each with a record, as the device does: `z`
//! (zero), `m<n>` (mode), `c<n><n>` (compression), `n<n>` (null radius), `b<n>` (beep, answered
//! `b`), `p<n><n>` (periods), `q<n><n>` (sensitivity), and the queries `mQ`, `nQ`, `kQ`
//! (key state) and `dQ` (axis data). Unknown commands are ignored.
//!
//! Once a command has put it in 3-D mode, and while the puck is "moving", it sends a record
//! every [`SimConfig::period`]: key records (every fourth) and axis records whose values are
//! known functions of a record count ([`axes`], [`keys`]), so a test can compute what a client
//! must receive. Every streamed record is logged with the time it left ([`MagellanSim::log`]).
//!
//! Faults: [`SimConfig::min_byte_gap`] makes it lose characters that come too close together
//! (the reason the driver writes slowly), [`MagellanSim::set_silent`] hangs it, and
//! [`MagellanSim::send_raw`] puts any bytes (garbage, a mouse-mode record) on the line.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::record::{
    encode_axes, encode_keys, nibble, nibble_char, AXES, CR, MAX_RECORD, MOUSE_MODE,
};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// `vrpn_device_sim magellan PATH`: a Magellan whose puck keeps moving.
pub static SIMULATOR: Simulator = Simulator {
    name: "magellan",
    about: "Logitech/3Dconnexion Magellan: a puck that keeps moving, keys that change",
    baud: 9600,
    line: "vrpn_Magellan Magellan0 {PATH} {BAUD}",
    make: |_| Box::new(MagellanSim::new(SimConfig::default())),
};

/// Records kept in [`MagellanSim::log`].
pub const LOG_CAP: usize = 100_000;

/// How the simulated device behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Time between streamed records while the puck moves.
    pub period: Duration,
    /// Delay before an answer to a command leaves.
    pub reply_delay: Duration,
    /// Characters that arrive sooner than this after the previous one are lost.
    pub min_byte_gap: Option<Duration>,
    /// Stream from power-on, before any command (the puck is touched during the reset).
    pub stream_at_power_on: bool,
    /// The second half of each streamed record leaves this long after the first (at 9600
    /// baud, 13 bytes take 13.5 ms), so records reach the host in two reads.
    pub second_half_after: Duration,
    /// An older unit: it ignores the compression (`c`) and beep (`b`) commands, so only the
    /// alternative reset works with it.
    pub old_unit: bool,
}

impl Default for SimConfig {
    /// A record every 20 ms in two halves 13.5 ms apart, answers after 1 ms, no lost
    /// characters, quiet until set up.
    fn default() -> SimConfig {
        SimConfig {
            period: Duration::from_millis(20),
            reply_delay: Duration::from_millis(1),
            min_byte_gap: None,
            stream_at_power_on: false,
            second_half_after: Duration::from_micros(13_500),
            old_unit: false,
        }
    }
}

/// Raw axis values of streamed record `seq` (within ±7000, some inside the null radius).
pub fn axes(seq: u64) -> [i32; AXES] {
    let mut v = [0i32; AXES];
    for (i, a) in v.iter_mut().enumerate() {
        let i64_ = i as u64;
        *a = if (seq + i64_) % 7 == 0 {
            (seq % 17) as i32 - 8
        } else {
            ((seq * (97 + 31 * i64_) + 1000 * i64_) % 14_001) as i32 - 7000
        };
    }
    v
}

/// Button mask (nine buttons) of streamed record `seq`.
pub fn keys(seq: u64) -> u16 {
    ((seq / 4 * 37 + 5) % 512) as u16
}

/// Whether streamed record `seq` is a key record (else an axis record).
pub fn is_key_record(seq: u64) -> bool {
    seq % 4 == 3
}

/// What one streamed record carried.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sent {
    /// An axis record with these raw values.
    Axes([i32; AXES]),
    /// A key record with this button mask.
    Keys(u16),
}

/// One record the simulator streamed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SentRecord {
    /// Record count since power-on.
    pub seq: u64,
    /// When it left.
    pub at: Instant,
    /// What it carried.
    pub sent: Sent,
}

/// The simulated device.
#[derive(Debug)]
pub struct MagellanSim {
    cfg: SimConfig,
    line: Vec<u8>,
    last_rx: Option<Instant>,
    /// Everything to send, in order: due time, bytes, and the record whose first byte they
    /// are (logged when it leaves).
    pending: VecDeque<(Instant, Vec<u8>, Option<SentRecord>)>,
    mode: u8,
    null_radius: u8,
    three_d: bool,
    moving: bool,
    silent: bool,
    next_record: Option<Instant>,
    seq: u64,
    lost_chars: u64,
    /// Every command received, without its CR, in order.
    pub commands: Vec<Vec<u8>>,
    /// When the first byte from the host arrived (the port was opened and reset).
    pub first_byte_at: Option<Instant>,
    /// When the last command was complete.
    pub last_command_at: Option<Instant>,
    /// Every streamed record, with the time its first byte left (the last [`LOG_CAP`]).
    pub log: VecDeque<SentRecord>,
}

impl MagellanSim {
    /// A device just powered on.
    pub fn new(cfg: SimConfig) -> MagellanSim {
        let three_d = cfg.stream_at_power_on;
        MagellanSim {
            cfg,
            line: Vec::with_capacity(32),
            last_rx: None,
            pending: VecDeque::new(),
            mode: 3,
            null_radius: 8,
            three_d,
            moving: true,
            silent: false,
            next_record: None,
            seq: 0,
            lost_chars: 0,
            commands: Vec::new(),
            first_byte_at: None,
            last_command_at: None,
            log: VecDeque::new(),
        }
    }

    /// Hangs the device (true): it neither reads nor sends, and what it would have sent is
    /// lost. Woken (false), it carries on.
    pub fn set_silent(&mut self, silent: bool) {
        self.silent = silent;
    }

    /// Starts or stops the puck's motion at `now` (no records while it rests).
    pub fn set_moving(&mut self, moving: bool, now: Now) {
        self.moving = moving;
        self.schedule(now);
    }

    /// Puts the next streamed record one period ahead, if streaming and none is due.
    fn schedule(&mut self, now: Now) {
        if self.three_d && self.moving {
            self.next_record.get_or_insert(now.mono + self.cfg.period);
        } else {
            self.next_record = None;
        }
    }

    /// Sends `bytes` as they are, at `now`.
    pub fn send_raw(&mut self, bytes: &[u8], now: Now) {
        self.pending.push_back((now.mono, bytes.to_vec(), None));
    }

    /// Characters lost because they came too fast.
    pub fn lost_chars(&self) -> u64 {
        self.lost_chars
    }

    /// Times the device was zeroed (`z` commands), a count of resets.
    pub fn zeroed(&self) -> usize {
        self.commands
            .iter()
            .filter(|c| c.as_slice() == b"z")
            .count()
    }

    /// Forgets the streamed-record log.
    pub fn clear_log(&mut self) {
        self.log.clear();
    }

    fn reply(&mut self, now: Now, bytes: &[u8]) {
        self.pending
            .push_back((now.mono + self.cfg.reply_delay, bytes.to_vec(), None));
    }

    fn command(&mut self, now: Now) {
        let cmd = std::mem::take(&mut self.line);
        match cmd.as_slice() {
            [b'z'] => self.reply(now, b"z\r"),
            [b'm', b'Q'] => self.reply(now, &[b'm', nibble_char(self.mode), CR]),
            [b'm', c] => {
                self.mode = nibble(*c);
                self.three_d = self.mode & MOUSE_MODE == 0;
                self.schedule(now);
                self.reply(now, &[b'm', *c, CR]);
            }
            [b'n', b'Q'] => self.reply(now, &[b'n', nibble_char(self.null_radius), CR]),
            [b'n', c] => {
                self.null_radius = nibble(*c);
                self.reply(now, &[b'n', *c, CR]);
            }
            [b'b' | b'c', ..] if self.cfg.old_unit => {}
            [b'b', _] => self.reply(now, b"b\r"),
            [l @ (b'c' | b'p' | b'q'), a, b] => self.reply(now, &[*l, *a, *b, CR]),
            [b'k', b'Q'] => self.reply(now, &encode_keys(keys(self.seq))),
            [b'd', b'Q'] => self.reply(now, &encode_axes(&axes(self.seq))),
            _ => {}
        }
        self.commands.push(cmd);
        self.last_command_at = Some(now.mono);
    }

    /// Queues the records due by `now`: a UART sends everything in order, so a record waits
    /// behind answers queued before it, and nothing comes between its halves.
    fn stream(&mut self, now: Now) {
        if !(self.three_d && self.moving) {
            self.next_record = None;
            return;
        }
        let mut t = *self.next_record.get_or_insert(now.mono + self.cfg.period);
        while t <= now.mono {
            let seq = self.seq;
            self.seq += 1;
            let sent = if is_key_record(seq) {
                Sent::Keys(keys(seq))
            } else {
                Sent::Axes(axes(seq))
            };
            if !self.silent {
                let mut bytes = [0u8; MAX_RECORD];
                let len = match sent {
                    Sent::Keys(k) => {
                        bytes[..5].copy_from_slice(&encode_keys(k));
                        5
                    }
                    Sent::Axes(a) => {
                        bytes = encode_axes(&a);
                        MAX_RECORD
                    }
                };
                let half = len / 2;
                let rec = SentRecord { seq, at: t, sent };
                self.pending
                    .push_back((t, bytes[..half].to_vec(), Some(rec)));
                self.pending.push_back((
                    t + self.cfg.second_half_after,
                    bytes[half..len].to_vec(),
                    None,
                ));
            }
            t += self.cfg.period;
        }
        self.next_record = Some(t);
    }
}

impl DeviceModel for MagellanSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        if self.silent {
            return;
        }
        self.first_byte_at.get_or_insert(now.mono);
        for &b in bytes {
            if let (Some(gap), Some(last)) = (self.cfg.min_byte_gap, self.last_rx) {
                if now.mono < last + gap {
                    self.lost_chars += 1;
                    continue;
                }
            }
            self.last_rx = Some(now.mono);
            if b == CR {
                self.command(now);
            } else if self.line.len() < 32 {
                self.line.push(b);
            }
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        self.stream(now);
        while self.pending.front().is_some_and(|(t, ..)| *t <= now.mono) {
            let Some((_, bytes, rec)) = self.pending.pop_front() else {
                break;
            };
            if self.silent {
                continue;
            }
            out.extend_from_slice(&bytes);
            if let Some(mut rec) = rec {
                // It leaves now, which is later than planned if answers went first.
                rec.at = now.mono;
                if self.log.len() == LOG_CAP {
                    self.log.pop_front();
                }
                self.log.push_back(rec);
            }
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let reply = self.pending.front().map(|(t, ..)| *t);
        let record = if self.three_d && self.moving {
            self.next_record
        } else {
            None
        };
        reply.into_iter().chain(record).min()
    }
}

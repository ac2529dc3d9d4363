//! A simulated BG Systems CerealBox: the device end of the serial line.
//!
//! It answers `T` with its 44-character banner, a configuration command (`c`, eight
//! characters, LF) with `a` LF, and each `pE` with one record laid out as the last
//! configuration asked ([`Layout::from_config_command`]). Record values are known functions
//! of a record count ([`buttons`], [`analog`], [`encoder`]) so a test can compute what a
//! client must receive; every record is logged with the time it left ([`CerealSim::log`]).
//! A record leaves in two halves [`SimConfig::second_half_after`] apart, so the host reads it
//! in pieces.
//!
//! Faults: [`CerealSim::set_silent`] hangs the box (it neither reads nor sends),
//! [`SimConfig::version`] gives it another EEPROM version, [`CerealSim::send_raw`] puts any
//! bytes on the line, and [`CerealSim::ignore_requests`] makes it drop record requests.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::record::{Layout, BANNER_LEN, BANNER_PREFIX, LF, MAX_RECORD};
use crate::sim::{DeviceModel, Simulator};
use crate::time::Now;

/// `vrpn_device_sim cerealbox PATH`: a CerealBox with every input.
pub static SIMULATOR: Simulator = Simulator {
    name: "cerealbox",
    about: "BG Systems CerealBox (EEPROM 3.07): 24 buttons, 8 sliders, 8 encoders",
    baud: 19200,
    line: "vrpn_CerealBox Cereal0 {PATH} {BAUD} 24 8 8",
    make: |_| Box::new(CerealSim::new(SimConfig::default())),
};

/// Records kept in [`CerealSim::log`].
pub const LOG_CAP: usize = 100_000;

/// How the simulated box behaves.
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Delay from a request's last byte to the answer's first.
    pub reply_delay: Duration,
    /// The second half of a record leaves this long after the first.
    pub second_half_after: Duration,
    /// EEPROM version in the banner, as its four characters.
    pub version: [u8; 4],
    /// The box type letter in the banner.
    pub box_type: u8,
}

impl Default for SimConfig {
    /// Answers after 1 ms, records in halves 5 ms apart, EEPROM 3.07, type `L`.
    fn default() -> SimConfig {
        SimConfig {
            reply_delay: Duration::from_millis(1),
            second_half_after: Duration::from_millis(5),
            version: *b"3.07",
            box_type: b'L',
        }
    }
}

/// Button mask (24 buttons) of record `seq`.
pub fn buttons(seq: u64) -> u32 {
    ((seq / 3).wrapping_mul(0x9E37) ^ (seq / 5) << 11) as u32 & 0xFF_FFFF
}

/// Raw value (0..=4095) of analog `i` in record `seq`.
pub fn analog(seq: u64, i: usize) -> u16 {
    ((seq * (37 + 11 * i as u64) + 500 * i as u64) % 4096) as u16
}

/// Ticks encoder `i` turned before record `seq` (0 for some, negative for others).
pub fn encoder(seq: u64, i: usize) -> i32 {
    match (seq + i as u64) % 5 {
        0 => 0,
        1 => -((seq % 300) as i32) - 1,
        2 => 8_388_607 - (seq % 7) as i32,
        _ => (seq as i32 % 1000) * (i as i32 + 1),
    }
}

/// One record the box sent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SentRecord {
    /// Record count since power-on.
    pub seq: u64,
    /// When its first byte left.
    pub at: Instant,
    /// The layout it had.
    pub layout: Layout,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Rx {
    Idle,
    Config(usize),
    Request,
}

/// The simulated box.
#[derive(Debug)]
pub struct CerealSim {
    cfg: SimConfig,
    rx: Rx,
    command: [u8; 10],
    layout: Option<Layout>,
    /// Everything to send, in order: due time, bytes, and the record whose first byte they
    /// are (logged when it leaves).
    pending: VecDeque<(Instant, Vec<u8>, Option<SentRecord>)>,
    silent: bool,
    ignore: u32,
    seq: u64,
    banners: u32,
    requests: u64,
    /// Every record sent (the last [`LOG_CAP`]).
    pub log: VecDeque<SentRecord>,
    /// When the first byte from the host arrived (the port was opened and reset).
    pub first_byte_at: Option<Instant>,
    /// When the first record request arrived (the reset was over).
    pub first_request_at: Option<Instant>,
}

impl CerealSim {
    /// A box just powered on.
    pub fn new(cfg: SimConfig) -> CerealSim {
        CerealSim {
            cfg,
            rx: Rx::Idle,
            command: [0; 10],
            layout: None,
            pending: VecDeque::new(),
            silent: false,
            ignore: 0,
            seq: 0,
            banners: 0,
            requests: 0,
            log: VecDeque::new(),
            first_byte_at: None,
            first_request_at: None,
        }
    }

    /// The banner this box sends.
    pub fn banner(&self) -> [u8; BANNER_LEN] {
        let mut b = [b' '; BANNER_LEN];
        b[..BANNER_PREFIX.len()].copy_from_slice(BANNER_PREFIX);
        b[26..37].copy_from_slice(b"1998 EEPROM");
        b[38..42].copy_from_slice(&self.cfg.version);
        b[42] = self.cfg.box_type;
        b[43] = LF;
        b
    }

    /// The layout the last configuration command asked for.
    pub fn layout(&self) -> Option<Layout> {
        self.layout
    }

    /// Banners sent (one per reset attempt that reached the box).
    pub fn banners(&self) -> u32 {
        self.banners
    }

    /// Record requests received.
    pub fn requests(&self) -> u64 {
        self.requests
    }

    /// Hangs the box (true): it neither reads nor sends, and pending output is lost.
    pub fn set_silent(&mut self, silent: bool) {
        self.silent = silent;
        if silent {
            self.pending.clear();
        }
    }

    /// Drops the next `n` record requests unanswered.
    pub fn ignore_requests(&mut self, n: u32) {
        self.ignore = n;
    }

    /// Sends `bytes` as they are, at `now`.
    pub fn send_raw(&mut self, bytes: &[u8], now: Now) {
        self.pending.push_back((now.mono, bytes.to_vec(), None));
    }

    /// Forgets the record log.
    pub fn clear_log(&mut self) {
        self.log.clear();
    }

    fn reply(&mut self, at: Instant, bytes: &[u8]) {
        self.pending.push_back((at, bytes.to_vec(), None));
    }

    fn record(&mut self, now: Now) {
        self.requests += 1;
        self.first_request_at.get_or_insert(now.mono);
        if self.ignore > 0 {
            self.ignore -= 1;
            return;
        }
        let Some(layout) = self.layout else { return };
        let seq = self.seq;
        self.seq += 1;
        let analogs: [u16; 8] = std::array::from_fn(|i| analog(seq, i));
        let encoders: [i32; 8] = std::array::from_fn(|i| encoder(seq, i));
        let (bytes, len): ([u8; MAX_RECORD], usize) =
            layout.encode(buttons(seq), &analogs, &encoders);
        let at = now.mono + self.cfg.reply_delay;
        let half = len / 2;
        let rec = SentRecord { seq, at, layout };
        self.pending
            .push_back((at, bytes[..half].to_vec(), Some(rec)));
        self.reply(at + self.cfg.second_half_after, &bytes[half..len]);
    }
}

impl DeviceModel for CerealSim {
    fn receive(&mut self, bytes: &[u8], now: Now) {
        if self.silent {
            return;
        }
        self.first_byte_at.get_or_insert(now.mono);
        for &b in bytes {
            self.rx = match (self.rx, b) {
                (Rx::Config(n), b) => {
                    self.command[n] = b;
                    if n + 1 < self.command.len() {
                        Rx::Config(n + 1)
                    } else {
                        if b == LF {
                            self.layout = Some(Layout::from_config_command(&self.command));
                            self.reply(now.mono + self.cfg.reply_delay, b"a\n");
                        }
                        Rx::Idle
                    }
                }
                (Rx::Request, b'E') => {
                    self.record(now);
                    Rx::Idle
                }
                (_, b'T') => {
                    self.banners += 1;
                    let banner = self.banner();
                    self.reply(now.mono + self.cfg.reply_delay, &banner);
                    Rx::Idle
                }
                (_, b'c') => {
                    self.command[0] = b'c';
                    Rx::Config(1)
                }
                (_, b'p') => Rx::Request,
                _ => Rx::Idle,
            };
        }
    }

    fn transmit(&mut self, now: Now, out: &mut Vec<u8>) {
        while self.pending.front().is_some_and(|(t, ..)| *t <= now.mono) {
            let Some((_, bytes, rec)) = self.pending.pop_front() else {
                break;
            };
            if self.silent {
                continue;
            }
            out.extend_from_slice(&bytes);
            if let Some(mut rec) = rec {
                // It leaves now, which is later than planned if something went first.
                rec.at = now.mono;
                if self.log.len() == LOG_CAP {
                    self.log.pop_front();
                }
                self.log.push_back(rec);
            }
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.pending.front().map(|(t, ..)| *t)
    }
}

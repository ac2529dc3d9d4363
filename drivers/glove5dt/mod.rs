//! 5DT Data Glove 5 on a serial line (C++ `vrpn_5dt`): its `vrpn.cfg` line ([`config`]), its
//! [`Protocol`], and a device simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_5dt NAME PORT BAUD MODE TENBYTES
//! ```
//!
//! `MODE` is 1 (the driver asks for each record, C++'s advice) or 2 (the glove streams);
//! `TENBYTES` 1 for gloves that add a tenth byte to each record. As in C++, 9600 baud means a
//! receive-only wireless glove: it streams ten-byte records whatever the line says.
//!
//! # Reset
//!
//! A wired glove: the input is flushed and `A` (initialise) written; the glove answers `U`.
//! The input is flushed and `G` (information) written; the glove answers 32 bytes starting
//! `BR`: version, hand, whether pitch and roll are fitted and its name, which are announced in
//! texts. In streaming mode `D` is then written; in polled mode `C` asks for the first record.
//! Each answer has [`ANSWER_TIME`] (C++: 0.1 s of sleep, then 2 s). A wireless glove is sent
//! nothing: the reset waits for its first record.
//!
//! # What is sent
//!
//! An Analog with eight channels ([`record::channels`]): channel 0 is always 0, channels 1–5
//! the thumb to little finger (0..1), 6 and 7 pitch and roll (0..180 degrees). One
//! `vrpn_Analog Channel` message per record if a channel changed, stamped with the arrival of
//! the record's first byte. In polled mode each record is followed by the next `C`.
//!
//! # Supervision
//!
//! More than 2 s without a record sends two error texts and the glove is reset on the open
//! port. Records are found byte by byte ([`record`]); skipped bytes are reported at most once
//! a second. A port that fails is reopened every second.
//!
//! # Differences from C++ VRPN
//!
//! * Waits are deadlines: the glove answers in a few milliseconds, so start-up takes that long
//!   instead of C++'s 0.2 s of sleeps, and the server is never blocked.
//! * The watchdog works: C++ renews its time stamp on every read, so it never fires.
//! * A record that does not start with `0x80` costs one byte, not a reset.
//! * A wireless glove's first record is reported (C++ uses it only to synchronise).
//! * A reset does not zero the channels (a reset never invents data).

pub mod config;
pub mod record;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::config::Mode;
use self::record::{Framed, Framer, CHANNELS};
use crate::devices::text::TextSeverity;
use crate::driver::text::ShownBytes;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{AnalogServer, Connection, Error};

pub use self::config::Glove5dt;

/// The registry entry: `vrpn_5dt`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_5dt"],
    parse: config::parse,
    hints: &[],
};

/// Initialise command, and its answer.
pub const INIT: u8 = b'A';
/// The answer to [`INIT`].
pub const INIT_ANSWER: u8 = 85;
/// Information request.
pub const INFO: u8 = b'G';
/// Length of the information answer.
pub const INFO_LEN: usize = 32;
/// Start streaming.
pub const STREAM: u8 = b'D';
/// Ask for one record.
pub const REQUEST: u8 = b'C';
/// Time an answer (or a wireless glove's first record) has (C++: 0.1 s + 2 s).
pub const ANSWER_TIME: Duration = Duration::from_millis(2100);
/// Pause before another attempt after a wrong answer.
pub const RETRY_DELAY: Duration = Duration::from_secs(1);

/// Where the reset is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Idle,
    /// `A` written, waiting for `U`.
    Init,
    /// `G` written, collecting the information.
    Info,
    /// Waiting for a wireless glove's first record.
    Wireless,
}

/// The glove's protocol. See the module documentation.
pub struct Glove5dtProtocol {
    baud: u32,
    mode: Mode,
    wireless: bool,
    analog: AnalogServer,
    framer: Framer,
    step: Step,
    deadline: Option<Instant>,
    info: [u8; INFO_LEN],
    info_len: usize,
    announced: bool,
}

impl Glove5dtProtocol {
    /// The protocol of a `vrpn_5dt` entry, with its Analog on `conn`.
    pub fn new(cfg: &Glove5dt, conn: &Connection) -> Result<Glove5dtProtocol, Error> {
        let wireless = cfg.wireless();
        Ok(Glove5dtProtocol {
            baud: cfg.baud,
            mode: if wireless { Mode::Streaming } else { cfg.mode },
            wireless,
            analog: AnalogServer::new(&cfg.name, conn, CHANNELS)?,
            framer: Framer::new(cfg.record_len(), wireless),
            step: Step::Idle,
            deadline: None,
            info: [0; INFO_LEN],
            info_len: 0,
            announced: false,
        })
    }

    /// Bytes skipped looking for records, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    fn report(&mut self, r: &Framed, cx: &mut Cx<'_>) {
        cx.record(r.first_byte);
        self.analog
            .channels_mut()
            .copy_from_slice(&record::channels(r.bytes()));
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.analog.report_changes(Some(r.first_byte.wall));
        if self.mode == Mode::Polled {
            cx.write(&[REQUEST]);
        }
    }

    fn frame(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> usize {
        let mut n = 0;
        for &b in bytes {
            if let Some(r) = self.framer.push(b, cx.now) {
                let skipped = self.framer.take_skipped();
                cx.skipped(skipped, "5DT glove", format_args!(""));
                self.report(&r, cx);
                n += 1;
            }
        }
        n
    }

    /// The information answer is complete: announce it, then start the records.
    fn got_info(&mut self, cx: &mut Cx<'_>) -> Reset {
        let i = self.info;
        if &i[..2] != b"BR" {
            cx.say(
                TextSeverity::Error,
                format_args!(
                    "vrpn_5dt: Cannot get good header on info command (got {})",
                    ShownBytes(&i[..2])
                ),
            );
            return Reset::Failed(Retry::After(RETRY_DELAY));
        }
        let name = &i[16..];
        let name = &name[..name.iter().position(|&b| b == 0).unwrap_or(name.len())];
        cx.say(
            TextSeverity::Normal,
            format_args!(
                "vrpn_5dt: glove \"{}\" version {}.{}",
                ShownBytes(name),
                i[2],
                i[3]
            ),
        );
        let hand = if i[4] & 1 != 0 { "right" } else { "left" };
        cx.say(
            TextSeverity::Normal,
            format_args!("A {hand} glove is ready"),
        );
        let fitted = if i[5] & 16 != 0 { "are" } else { "are not" };
        cx.say(
            TextSeverity::Normal,
            format_args!("Pitch and Roll {fitted} available"),
        );
        self.step = Step::Idle;
        self.deadline = None;
        cx.write(&[match self.mode {
            Mode::Streaming => STREAM,
            Mode::Polled => REQUEST,
        }]);
        Reset::Done
    }
}

impl Protocol for Glove5dtProtocol {
    const KIND: &'static str = "5DT glove";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision {
            on_silence: Recovery::Reset,
            ..Supervision::TRACKER
        }
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        // What waited in the port's buffer was sent before now: it cannot be stamped.
        cx.flush_input();
        self.framer.clear();
        self.deadline = Some(cx.now.mono + ANSWER_TIME);
        if self.wireless {
            if !self.announced {
                self.announced = true;
                cx.say(
                    TextSeverity::Normal,
                    format_args!(
                        "Will connect to a receive-only 'wireless-type' glove - there may be \
                         a few warnings before we succeed."
                    ),
                );
            }
            self.step = Step::Wireless;
            return Reset::Working;
        }
        cx.write(&[INIT]);
        self.step = Step::Init;
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        match self.step {
            Step::Idle => Reset::Working,
            Step::Wireless => {
                if self.frame(bytes, cx) == 0 {
                    return Reset::Working;
                }
                self.step = Step::Idle;
                self.deadline = None;
                cx.say(
                    TextSeverity::Normal,
                    format_args!("A 'wireless-type' glove is ready and reporting"),
                );
                Reset::Done
            }
            Step::Init => {
                if bytes.contains(&INIT_ANSWER) {
                    cx.flush_input();
                    cx.write(&[INFO]);
                    self.info_len = 0;
                    self.step = Step::Info;
                    self.deadline = Some(cx.now.mono + ANSWER_TIME);
                }
                Reset::Working
            }
            Step::Info => {
                let n = bytes.len().min(INFO_LEN - self.info_len);
                self.info[self.info_len..self.info_len + n].copy_from_slice(&bytes[..n]);
                self.info_len += n;
                if self.info_len < INFO_LEN {
                    return Reset::Working;
                }
                self.got_info(cx)
            }
        }
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        let step = self.step;
        self.step = Step::Idle;
        self.deadline = None;
        match step {
            Step::Info => cx.say(
                TextSeverity::Error,
                format_args!(
                    "vrpn_5dt: Cannot get info. from the glove ({} of {INFO_LEN} bytes)",
                    self.info_len
                ),
            ),
            _ => cx.say(
                TextSeverity::Error,
                format_args!("vrpn_5dt: Unable to read from the glove"),
            ),
        }
        Reset::Failed(Retry::Now)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.deadline
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.frame(bytes, cx);
    }

    fn stopped(&mut self) {
        self.framer.clear();
        self.step = Step::Idle;
        self.deadline = None;
    }
}

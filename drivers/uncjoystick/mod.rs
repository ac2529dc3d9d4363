//! The UNC joystick box (a slider, two three-axis sticks, two buttons, on a single-board
//! computer behind a serial line): its `vrpn.cfg` line ([`config`]), its records
//! ([`record`]), its [`Protocol`] run by the shared [`Lifecycle`](crate::driver::Lifecycle),
//! and a device simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Joystick NAME PORT BAUD MIN_UPDATE_RATE
//! ```
//!
//! The line is 8N1 at `BAUD` (19200 in C++'s sample). `MIN_UPDATE_RATE` (reports a second,
//! 0 for none) is how often the state is sent again while the box is quiet.
//!
//! # Reset
//!
//! `r` asks for one record per channel (16 bytes): they give the sticks' rest positions (the
//! slider's is 512, it does not centre itself) and the buttons. Then `j` asks for a record
//! whenever a channel changes. C++ sleeps 1 s between the two; here `j` goes out as soon as
//! the eighth record is in, and 1 s without them is a failed attempt (`got only N of 16
//! bytes`, a warning) and `r` is sent again.
//!
//! # What is sent
//!
//! `NAME` is an Analog with 7 channels and a Button with 2 buttons. Channel *c* is (rest −
//! value) / scale (scales 1019, 200, 200, 350, 200, 200, 350), clamped to ±0.5, the slider's
//! sign flipped; the buttons are pressed when their bit is clear. After the reset's records
//! and after each record: one `vrpn_Button Change` per changed button, then a `vrpn_Analog
//! Channel` message with all seven channels (whether or not one changed, as C++), stamped
//! with the arrival of the record's first byte. When nothing was sent for 1 /
//! `MIN_UPDATE_RATE` s, the analog message is sent again, stamped with that moment.
//!
//! # Supervision
//!
//! The box sends only when something changes, so silence is normal and there is no watchdog
//! (asking it with `r` would change its rest positions). A port that fails is reopened by the
//! serial layer, then the box reset.
//!
//! # Differences from C++ VRPN
//!
//! * No 1 s sleep: the reset ends when the rest positions are in (about 10 ms at 19200 baud).
//! * All eight reset records are read (C++ reads seven positions and takes the channel
//!   numbers from them, so the buttons' record is skipped if it comes last).
//! * Reports carry the arrival of the record's first byte (C++: the time it is decoded).
//! * Problems are VRPN text messages, not lines on the server's standard error.

pub mod config;
pub mod record;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::record::{channel_value, Framer, Pair, BUTTONS, BUTTON_CHANNEL, CHANNELS, SLIDER_REST};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::TimeVal;
use crate::{AnalogServer, ButtonServer, Connection, Error};

pub use self::config::UncJoystick;

/// The registry entry: `vrpn_Joystick`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Joystick"],
    parse: config::parse,
    hints: &[],
};

/// The request for every channel's record (the rest positions).
pub const REQUEST_ALL: &[u8] = b"r";
/// The request for records on change only.
pub const REQUEST_CHANGES: &[u8] = b"j";
/// Records in the answer to [`REQUEST_ALL`].
pub const ANSWER_RECORDS: usize = 8;
/// Time the box has to answer (C++ sleeps this long, then reads).
pub const ANSWER_LIMIT: Duration = Duration::from_secs(1);

/// The UNC joystick box's protocol. See the module documentation.
pub struct UncJoystickProtocol {
    baud: u32,
    repeat_every: Option<Duration>,
    analog: AnalogServer,
    buttons: ButtonServer,
    framer: Framer,
    rest: [u16; CHANNELS],
    answer_by: Option<Instant>,
    answer_records: usize,
    answer_first: Option<TimeVal>,
    last_report: Option<Instant>,
    repeats: u64,
}

impl UncJoystickProtocol {
    /// The protocol of a `vrpn_Joystick` entry, with its servers on `conn`.
    pub fn new(cfg: &UncJoystick, conn: &Connection) -> Result<UncJoystickProtocol, Error> {
        let rate = f64::from(cfg.min_update_rate);
        Ok(UncJoystickProtocol {
            baud: cfg.baud,
            repeat_every: (rate > 0.0 && rate.is_finite())
                .then(|| Duration::from_secs_f64(1.0 / rate)),
            analog: AnalogServer::new(&cfg.name, conn, CHANNELS)?,
            buttons: ButtonServer::new(&cfg.name, conn, BUTTONS)?,
            framer: Framer::new(),
            rest: [SLIDER_REST; CHANNELS],
            answer_by: None,
            answer_records: 0,
            answer_first: None,
            last_report: None,
            repeats: 0,
        })
    }

    /// The analog server.
    pub fn analog(&self) -> &AnalogServer {
        &self.analog
    }

    /// The button server.
    pub fn buttons(&self) -> &ButtonServer {
        &self.buttons
    }

    /// The rest positions learned at the last reset.
    pub fn rest(&self) -> [u16; CHANNELS] {
        self.rest
    }

    /// Bytes skipped while looking for records, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    /// Reports sent again for the minimum update rate, since construction.
    pub fn repeats(&self) -> u64 {
        self.repeats
    }

    /// Sets the state from one record (a rest position too while resetting).
    fn apply(&mut self, p: Pair, resetting: bool) {
        if p.channel == BUTTON_CHANNEL {
            for (i, pressed) in p.buttons().into_iter().enumerate() {
                self.buttons.set_button(i, pressed);
            }
            return;
        }
        let c = usize::from(p.channel);
        if resetting && c != 0 {
            self.rest[c] = p.value;
        }
        self.analog
            .set_channel(c, channel_value(c, self.rest[c], p.value));
    }

    fn report(&mut self, time: TimeVal, mono: Instant) {
        // A failed send is the connection's business (it reports and drops the peer).
        self.buttons.set_timestamp(time);
        let _ = self.buttons.report_changes_unfiltered();
        let _ = self.analog.report(Some(time));
        self.last_report = Some(mono);
    }
}

impl Protocol for UncJoystickProtocol {
    const KIND: &'static str = "vrpn_Joystick";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision::QUIET
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        cx.flush_input();
        cx.write(REQUEST_ALL);
        self.answer_by = Some(cx.now.mono + ANSWER_LIMIT);
        self.answer_records = 0;
        self.answer_first = None;
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        for (i, &b) in bytes.iter().enumerate() {
            let Some(f) = self.framer.push(b, cx.now) else {
                continue;
            };
            self.apply(f.pair, true);
            self.answer_first.get_or_insert(f.first_byte.wall);
            self.answer_records += 1;
            if self.answer_records == ANSWER_RECORDS {
                cx.write(REQUEST_CHANGES);
                self.answer_by = None;
                cx.record(f.first_byte);
                let first = self.answer_first.unwrap_or(f.first_byte.wall);
                self.report(first, f.first_byte.mono);
                self.received(&bytes[i + 1..], cx);
                return Reset::Done;
            }
        }
        Reset::Working
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        cx.say(
            TextSeverity::Warning,
            format_args!(
                "vrpn_Joystick reset: got only {} of 16 bytes from the joystick, trying again",
                self.answer_records * 2
            ),
        );
        Reset::Failed(Retry::Now)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.answer_by
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            if let Some(f) = self.framer.push(b, cx.now) {
                cx.skipped(u64::from(f.skipped), "vrpn_Joystick", format_args!(""));
                cx.record(f.first_byte);
                self.apply(f.pair, false);
                self.report(f.first_byte.wall, f.first_byte.mono);
            }
        }
    }

    fn deadline(&self) -> Option<Instant> {
        self.last_report.zip(self.repeat_every).map(|(t, d)| t + d)
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        if self.deadline().is_some_and(|d| cx.now.mono >= d) {
            self.repeats += 1;
            self.report(cx.now.wall, cx.now.mono);
        }
    }

    fn stopped(&mut self) {
        self.framer.clear();
        self.answer_by = None;
        self.last_report = None;
    }
}

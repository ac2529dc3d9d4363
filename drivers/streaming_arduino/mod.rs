//! An Arduino running VRPN's `vrpn_streaming_arduino` sketch (C++ `vrpn_Streaming_Arduino`):
//! its `vrpn.cfg` line ([`config`]), its [`Protocol`], and a device simulator (`sim`, with the
//! `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Streaming_Arduino NAME PORT ANALOGS [BAUD]
//! ```
//!
//! `ANALOGS` inputs are read (at most 8, as C++ clamps), at `BAUD` (115200 when not given,
//! the sketch's speed), 8N1.
//!
//! # Reset
//!
//! Opening the port restarts an Arduino (DTR), whose boot loader runs for a while before the
//! sketch starts; the sketch then waits for the number of analogs, as a decimal line. C++
//! sleeps 2.1 s, writes the line once and gives up unless a byte comes within 10 ms. Here the
//! input is flushed and the line written at once and again every [`ASK_EVERY`] until the
//! first byte comes (a sketch already running takes the repeats as event markers, which the
//! reader ignores), at most [`BOOT_TIME`]; the first line after a reset is dropped, since it
//! may have lost its start. Start-up takes the boot loader's time plus one line.
//!
//! # What is sent
//!
//! An Analog with `ANALOGS` channels, the numbers of each line (0..1023 from the sketch), and a
//! Button without buttons (C++ declares one and never uses it). One `vrpn_Analog Channel`
//! message per line if a value changed, stamped with the arrival of the line's first byte
//! (C++ estimates it from the read's end, 87 µs a buffered byte).
//!
//! # Supervision
//!
//! More than 2 s without a line sends two error texts, and the port is reopened (which
//! restarts the Arduino) and the sketch set up again. Lines are read byte by byte
//! ([`line`](mod@line)); a line without `ANALOGS` numbers is skipped and reported, at most once a
//! second, instead of resetting the device as C++ does.
//!
//! # Differences from C++ VRPN
//!
//! * No 2.1 s sleep: the count is repeated until the sketch answers, so start-up is the boot
//!   loader's time and the server is never blocked.
//! * A bad line is skipped instead of resetting; garbage without digits costs nothing.
//! * Stamps are the first byte's arrival, not an estimate.
//! * The watchdog reopens the port (restarting the Arduino) instead of writing the count to a
//!   sketch that may have hung.
//! * A reset does not zero the channels (a reset never invents data).

pub mod config;
pub mod line;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::io::Write as _;
use std::time::{Duration, Instant};

use self::line::{Ended, LineReader};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{AnalogServer, ButtonServer, Connection, Error};

pub use self::config::StreamingArduino;

/// The registry entry: `vrpn_Streaming_Arduino`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Streaming_Arduino"],
    parse: config::parse,
    hints: &[],
};

/// The count is written again this often until the sketch answers.
pub const ASK_EVERY: Duration = Duration::from_millis(250);
/// Longest wait for the sketch's first byte (a boot loader takes up to 2 s, C++ sleeps 2.1).
pub const BOOT_TIME: Duration = Duration::from_secs(3);

/// The sketch's protocol. See the module documentation.
pub struct ArduinoProtocol {
    baud: u32,
    analogs: usize,
    requested: u32,
    /// The count line, `"N\n"`.
    ask: [u8; 4],
    ask_len: usize,
    analog: AnalogServer,
    _buttons: ButtonServer,
    reader: LineReader,
    /// While resetting: when the count is next written, and when to give up.
    next_ask: Option<Instant>,
    give_up: Option<Instant>,
    told_clamp: bool,
}

impl ArduinoProtocol {
    /// The protocol of a `vrpn_Streaming_Arduino` entry, with its Analog and Button on `conn`.
    pub fn new(cfg: &StreamingArduino, conn: &Connection) -> Result<ArduinoProtocol, Error> {
        let analogs = cfg.analogs();
        let mut ask = [0u8; 4];
        let mut w = &mut ask[..];
        let _ = writeln!(w, "{analogs}");
        let ask_len = 4 - w.len();
        Ok(ArduinoProtocol {
            baud: cfg.baud,
            analogs,
            requested: cfg.requested,
            ask,
            ask_len,
            analog: AnalogServer::new(&cfg.name, conn, analogs)?,
            _buttons: ButtonServer::new(&cfg.name, conn, 0)?,
            reader: LineReader::new(analogs),
            next_ask: None,
            give_up: None,
            told_clamp: false,
        })
    }

    fn ask(&mut self, cx: &mut Cx<'_>) {
        cx.flush_input();
        cx.write(&self.ask[..self.ask_len]);
        self.next_ask = Some(cx.now.mono + ASK_EVERY);
    }

    fn take(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            let Some(ended) = self.reader.push(b, cx.now) else {
                continue;
            };
            let skipped = self.reader.take_skipped();
            cx.skipped(skipped, "Streaming Arduino", format_args!(""));
            match ended {
                Ended::Line(l) => {
                    cx.record(l.first_byte);
                    for (c, &v) in self
                        .analog
                        .channels_mut()
                        .iter_mut()
                        .zip(&l.values[..self.analogs])
                    {
                        *c = f64::from(v);
                    }
                    // A failed send is the connection's business (it reports and drops the
                    // peer).
                    let _ = self.analog.report_changes(Some(l.first_byte.wall));
                }
                Ended::Bad(n) => cx.skipped(
                    n as u64,
                    "Streaming Arduino",
                    format_args!(" (a line without {} numbers)", self.analogs),
                ),
            }
        }
    }
}

impl Protocol for ArduinoProtocol {
    const KIND: &'static str = "Streaming Arduino";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision::TRACKER
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        if !self.told_clamp && self.requested as usize > self.analogs {
            self.told_clamp = true;
            cx.say(
                TextSeverity::Warning,
                format_args!(
                    "vrpn_Streaming_Arduino: Can only support {} analog channels, not {}",
                    self.analogs, self.requested
                ),
            );
        }
        self.reader.clear(true);
        self.give_up = Some(cx.now.mono + BOOT_TIME);
        self.ask(cx);
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        if bytes.is_empty() {
            return Reset::Working;
        }
        self.next_ask = None;
        self.give_up = None;
        self.take(bytes, cx);
        Reset::Done
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        if self.give_up.is_some_and(|t| cx.now.mono >= t) {
            self.next_ask = None;
            self.give_up = None;
            cx.say(
                TextSeverity::Error,
                format_args!("vrpn_Streaming_Arduino: Could not reset (no answer from the sketch)"),
            );
            return Reset::Failed(Retry::Reopen);
        }
        self.ask(cx);
        Reset::Working
    }

    fn reset_deadline(&self) -> Option<Instant> {
        [self.next_ask, self.give_up].into_iter().flatten().min()
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.take(bytes, cx);
    }

    fn stopped(&mut self) {
        self.reader.clear(true);
        self.next_ask = None;
        self.give_up = None;
    }
}

//! Origin Instruments DynaSight (and the SeeReal D4D head tracker that speaks its protocol):
//! its `vrpn.cfg` line ([`config`]), its [`Protocol`] run by the shared
//! [`Lifecycle`](crate::driver::Lifecycle), and a device simulator (`sim`, with the `sim`
//! feature).
//!
//! This folder is the example a new driver copies: `config.rs` (the line, what it serves, how
//! it is built), this file (the protocol: reset answers, records, reports), `reset.rs` and
//! `framing.rs`/`record.rs` (pure state machines and decoding), `sim.rs` (the device's end of
//! the line) and `tests.rs` (the driver on a virtual line); the end-to-end test through
//! `vrpn_server` is `tests/dyna_joylin_pty.rs`.
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tracker_Dyna NAME SENSORS PORT BAUD
//! ```
//!
//! Note the sensor count before the port. The tracker `NAME` has `SENSORS` sensors, but the
//! DynaSight tracks one target and only sensor 0 is ever reported (as C++). The line is 8N1
//! at `BAUD`, without flow control.
//!
//! # What is sent
//!
//! One `vrpn_Tracker Pos_Quat` message (LOW_LATENCY) per record: sensor 0, position in
//! metres ([`record`]), orientation the identity, stamped with the time the record's first
//! byte arrived. Resets, time-outs and resynchronisations are announced as text messages
//! from `NAME`.
//!
//! # Supervision
//!
//! Opening the port starts the reset ([`reset`]), a state machine over deadlines. An attempt
//! that gets no answer starts again at once (it already waited 2 s); one that gets a wrong
//! answer starts again after [`RETRY_DELAY`]. Records are found byte by byte ([`framing`]),
//! so garbage costs no record after it. More than 2 s without a record (counted from the end
//! of the reset, then from each record's first byte: [`Supervision::TRACKER`]) sends two
//! error texts, and the port is reopened and the DynaSight reset.
//!
//! # Differences from C++ VRPN
//!
//! * The reset waits for the device instead of sleeping 1 + 2 + 1 s: about 0.1 s on a
//!   DynaSight that answers at once, and it never blocks other devices.
//! * The watchdog starts when the reset ends. (C++ sets the watchdog's start to a time
//!   of −1 s, so whether its first check fires depends on a 32-bit overflow.)
//! * A failed candidate record gives up one byte, not eight: the record after it is kept.
//! * Problems go to clients as text messages, not to the server's standard error.

pub mod config;
pub mod framing;
pub mod record;
pub mod reset;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::framing::{Framed, Framer};
use self::record::IDENTITY_XYZW;
use self::reset::{Failure, Progress, ResetSequence, STATUS_LEN};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{Connection, Error, TrackerServer};

pub use self::config::Dyna;

/// The registry entry: `vrpn_Tracker_Dyna`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_Dyna"],
    parse: config::parse,
    hints: &[],
};

/// Pause before another attempt after a wrong status answer.
pub const RETRY_DELAY: Duration = Duration::from_secs(1);

/// The DynaSight's protocol: its reset, its records, its reports. See the module
/// documentation.
pub struct DynaProtocol {
    port: String,
    baud: u32,
    tracker: TrackerServer,
    reset: ResetSequence,
    framer: Framer,
}

impl DynaProtocol {
    /// The protocol of a `vrpn_Tracker_Dyna` entry, with its tracker served on `conn`.
    pub fn new(cfg: &Dyna, conn: &Connection) -> Result<DynaProtocol, Error> {
        if cfg.sensors == 0 {
            return Err(Error::Unsupported("a DynaSight needs at least one sensor"));
        }
        Ok(DynaProtocol {
            port: cfg.port.clone(),
            baud: cfg.baud,
            tracker: TrackerServer::new(&cfg.name, conn, cfg.sensors as usize)?,
            reset: ResetSequence::new(),
            framer: Framer::new(),
        })
    }

    /// The serial port to open, as the configuration gives it.
    pub fn port(&self) -> &str {
        &self.port
    }

    /// The tracker server the poses go out through.
    pub fn tracker(&self) -> &TrackerServer {
        &self.tracker
    }

    /// Reset attempts since the last completed one.
    pub fn reset_attempts(&self) -> u32 {
        self.reset.attempts()
    }

    /// Bytes skipped while looking for records, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    fn progress(&mut self, p: Progress, cx: &mut Cx<'_>) -> Reset {
        match p {
            Progress::Working => Reset::Working,
            Progress::Done { kept_sending } => {
                if kept_sending {
                    cx.say(
                        TextSeverity::Warning,
                        format_args!(
                            "DynaSight kept sending after the stop command (check the baud rate)"
                        ),
                    );
                }
                cx.say(
                    TextSeverity::Normal,
                    format_args!("DynaSight reset: valid status, continuous output requested"),
                );
                Reset::Done
            }
            Progress::Failed(f) => {
                let attempt = self.reset.attempts();
                match f {
                    Failure::NoAnswer => {
                        cx.say(
                            TextSeverity::Warning,
                            format_args!(
                                "DynaSight reset attempt {attempt}: no data (is the tracker \
                                 turned on?); trying again"
                            ),
                        );
                        Reset::Failed(Retry::Now)
                    }
                    Failure::Incomplete(n) => {
                        cx.say(
                            TextSeverity::Error,
                            format_args!(
                                "DynaSight reset attempt {attempt}: {n} of {STATUS_LEN} bytes \
                                 of the status answer (check the baud rate); trying again"
                            ),
                        );
                        Reset::Failed(Retry::After(RETRY_DELAY))
                    }
                    Failure::BadStatus([a, b]) => {
                        cx.say(
                            TextSeverity::Error,
                            format_args!(
                                "DynaSight reset attempt {attempt}: the status answer starts \
                                 0x{a:02X} 0x{b:02X}, not a status record (check the baud \
                                 rate); trying again"
                            ),
                        );
                        Reset::Failed(Retry::After(RETRY_DELAY))
                    }
                }
            }
        }
    }

    fn report(&mut self, framed: Framed, cx: &mut Cx<'_>) {
        cx.skipped(u64::from(framed.skipped), "DynaSight", format_args!(""));
        cx.record(framed.first_byte);
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.tracker.report_pose(
            0,
            framed.first_byte.wall,
            record::position_m(&framed.bytes),
            IDENTITY_XYZW,
        );
    }
}

impl Protocol for DynaProtocol {
    const KIND: &'static str = "DynaSight";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision::TRACKER
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.reset.start(cx.now, cx.port());
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        // Bytes after a complete status answer are flushed with the rest of the input.
        let p = self.reset.received(bytes, cx.now, cx.port());
        self.progress(p, cx)
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        let p = self.reset.poll(cx.now, cx.port());
        self.progress(p, cx)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.reset.deadline()
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            if let Some(framed) = self.framer.push(b, cx.now) {
                self.report(framed, cx);
            }
        }
    }

    fn stopped(&mut self) {
        self.reset.stop();
        self.framer.clear();
    }
}

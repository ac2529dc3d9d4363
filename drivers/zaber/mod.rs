//! Zaber linear positioners (T-series binary protocol) daisy-chained on a serial line (C++
//! `vrpn_Zaber`): its `vrpn.cfg` line ([`config`]), its [`Protocol`], and a device simulator
//! (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Zaber NAME PORT
//! ```
//!
//! The line is 9600 baud 8N1 ([`config::BAUD`]), as C++ opens it.
//!
//! # Reset
//!
//! The chain is renumbered and each device asked for its position and set up, until one does
//! not answer ([`reset`]). With `N` devices found, the Analog and the Analog_Output both have
//! `N` channels, and the positions are reported.
//!
//! # What is served
//!
//! `NAME` is an Analog (channel `i`: device `i + 1`'s position in microsteps, sent RELIABLE as
//! C++ does) and an Analog_Output: a client's request to set channel `i` to `v` moves device
//! `i + 1` to the absolute position `v` (truncated to an integer); a request for channels
//! `0..n` moves each. The device answers when the move is done, and that position is
//! reported. Positions the devices announce by themselves (homing, the knob) are reported
//! too. Each report is stamped with the arrival of its reply's first byte. A client whose
//! remote pings the device gets all channels at once, as in C++.
//!
//! # Supervision
//!
//! After [`POLL_AFTER`] without a reply, device 1 is asked for its position (C++ polls the
//! same way); more than 2 s without a reply sends two error texts and the chain is reset on
//! the open port. Replies are found byte by byte ([`reply`]); skipped bytes are reported at
//! most once a second. A port that fails is reopened every second.
//!
//! # Differences from C++ VRPN
//!
//! * No sleeps: the renumbering wait ends when the answers stop instead of after 2 s, and
//!   the server is never blocked.
//! * Moves asked for during a reset are sent once it is done (C++ writes them into the
//!   reset); several requests for one channel within one pass of the server are sent as the
//!   last one.
//! * An error reply (255) is reported as a warning and does not become a position (C++
//!   stores the error code in the channel).
//! * A reply from an unknown device or with an unknown command costs one byte, not a flush
//!   of the input.
//! * The poll asks once a second while idle (C++'s poll can race its own time-out).

pub mod config;
pub mod reply;
pub mod reset;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::config::BAUD;
use self::reply::{command, Command, Framer, Reply, MOVE_ABSOLUTE, POSITION};
use self::reset::{Failure, Progress, ResetSequence, MAX_DEVICES};
use crate::devices::analog_output::{AnalogOutputServer, OutputRequests};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::wire::class;
use crate::{AnalogServer, Connection, Error};

pub use self::config::Zaber;

/// The registry entry: `vrpn_Zaber`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Zaber"],
    parse: config::parse,
    hints: &[],
};

/// Silence after which device 1 is asked for its position.
pub const POLL_AFTER: Duration = Duration::from_secs(1);
/// Pause before another attempt after a failed reset.
pub const RETRY_DELAY: Duration = Duration::from_secs(1);

/// The chain's protocol. See the module documentation.
pub struct ZaberProtocol {
    analog: AnalogServer,
    output: AnalogOutputServer,
    /// Moves asked for, not yet written (one slot per channel: the last request wins), and
    /// pings of the Analog.
    requests: OutputRequests,
    reset: ResetSequence,
    framer: Framer,
    devices: usize,
    /// The time of the last call (a deadline already passed, for pending requests).
    last_now: Option<Instant>,
    /// The first byte of the last reply (or the end of the reset), and the last poll.
    last_reply: Option<Instant>,
    polled_at: Option<Instant>,
}

impl ZaberProtocol {
    /// The protocol of a `vrpn_Zaber` entry, with its Analog and Analog_Output on `conn`.
    pub fn new(cfg: &Zaber, conn: &Connection) -> Result<ZaberProtocol, Error> {
        let mut analog = AnalogServer::new(&cfg.name, conn, 0)?;
        analog.set_class_of_service(class::RELIABLE);
        let output = AnalogOutputServer::new(&cfg.name, conn, 0)?;
        // The server half checks and stores requests; this sees each one as it came (one
        // slot per device a chain can have: the reset learns how many there are).
        let requests = output.watch_requests(MAX_DEVICES, Some(analog.sender()))?;
        Ok(ZaberProtocol {
            analog,
            output,
            requests,
            reset: ResetSequence::new(),
            framer: Framer::new(0),
            devices: 0,
            last_now: None,
            last_reply: None,
            polled_at: None,
        })
    }

    /// Devices found by the last reset.
    pub fn devices(&self) -> usize {
        self.devices
    }

    fn progress(&mut self, p: Progress, cx: &mut Cx<'_>) -> Reset {
        match p {
            Progress::Working => Reset::Working,
            Progress::Done { devices } => {
                self.devices = devices;
                self.framer.reset(devices as u8);
                self.analog.set_num_channels(devices);
                self.output.set_num_channels(devices);
                let _ = self.output.report_num_channels();
                cx.say(
                    TextSeverity::Warning,
                    format_args!("found {devices} devices"),
                );
                cx.say(
                    TextSeverity::Warning,
                    format_args!("reset complete (this is good)"),
                );
                let mut last = None;
                for (i, &(pos, at)) in self.reset.positions()[..devices].iter().enumerate() {
                    self.analog.set_channel(i, f64::from(pos));
                    last = at.or(last);
                }
                let at = last.unwrap_or(cx.now);
                self.last_reply = Some(cx.now.mono);
                // A failed send is the connection's business (it reports and drops the peer).
                let _ = self.analog.report_changes(Some(at.wall));
                Reset::Done
            }
            Progress::Failed(f) => {
                match f {
                    Failure::NoDevices => cx.say(
                        TextSeverity::Error,
                        format_args!("reset: found 0 devices (is the chain powered?)"),
                    ),
                    Failure::Short { device, got } => cx.say(
                        TextSeverity::Error,
                        format_args!(
                            "reset: Got {got} of 24 expected characters for position (device \
                             {device})"
                        ),
                    ),
                    Failure::BadAnswer { device, got } => cx.say(
                        TextSeverity::Error,
                        format_args!(
                            "reset: Bad response to device # request (device {device}: \
                             {} {})",
                            got[0], got[1]
                        ),
                    ),
                }
                Reset::Failed(Retry::After(RETRY_DELAY))
            }
        }
    }

    fn reply(&mut self, r: Reply, cx: &mut Cx<'_>) {
        cx.record(r.first_byte);
        self.last_reply = Some(r.first_byte.mono);
        match Command::of(r.command) {
            Some(Command::Position) => {
                self.analog
                    .set_channel(usize::from(r.device) - 1, f64::from(r.data));
                // A failed send is the connection's business (it reports and drops the peer).
                let _ = self.analog.report_changes(Some(r.first_byte.wall));
            }
            Some(Command::Error) => cx.say(
                TextSeverity::Warning,
                format_args!(
                    "Requested value out of range (device {}, error {})",
                    r.device, r.data
                ),
            ),
            Some(Command::SetUp) | None => {}
        }
    }

    /// When device 1 is to be asked for its position: [`POLL_AFTER`] after the last reply,
    /// once (the lifecycle's watchdog takes over if it stays unanswered).
    fn poll_due(&self) -> Option<Instant> {
        let last = self.last_reply?;
        if self.polled_at.is_some_and(|p| p >= last) {
            return None;
        }
        Some(last + POLL_AFTER)
    }

    /// Writes the moves asked for, in channel order.
    fn send_requests(&mut self, cx: &mut Cx<'_>) {
        if self.requests.take_pinged() {
            let _ = self.analog.report(Some(cx.now.wall));
        }
        while let Some((i, v)) = self.requests.take_next() {
            if i < self.devices {
                // As C++: the value truncated to an integer (saturating).
                cx.write(&command(i as u8 + 1, MOVE_ABSOLUTE, v as i32));
            }
        }
    }
}

impl Protocol for ZaberProtocol {
    const KIND: &'static str = "Zaber";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(BAUD))
    }

    fn supervision(&self) -> Supervision {
        Supervision {
            on_silence: Recovery::Reset,
            ..Supervision::TRACKER
        }
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.last_now = Some(cx.now.mono);
        self.framer.reset(self.devices as u8);
        self.reset.start(cx.now, cx.port());
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        self.last_now = Some(cx.now.mono);
        let p = self.reset.received(bytes, cx.now, cx.port());
        self.progress(p, cx)
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.last_now = Some(cx.now.mono);
        let p = self.reset.poll(cx.now, cx.port());
        self.progress(p, cx)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.reset.deadline()
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.last_now = Some(cx.now.mono);
        for &b in bytes {
            if let Some(r) = self.framer.push(b, cx.now) {
                let skipped = self.framer.take_skipped();
                cx.skipped(skipped, "Zaber", format_args!(""));
                self.reply(r, cx);
            }
        }
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        self.last_now = Some(cx.now.mono);
        self.send_requests(cx);
        if self.poll_due().is_some_and(|d| cx.now.mono >= d) {
            cx.write(&command(1, POSITION, 0));
            self.polled_at = Some(cx.now.mono);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        if self.requests.is_pending() {
            return self.last_now;
        }
        self.poll_due()
    }

    fn stopped(&mut self) {
        self.reset.stop();
        self.framer.reset(self.devices as u8);
        self.last_reply = None;
        self.polled_at = None;
    }
}

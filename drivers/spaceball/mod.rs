//! Spacetec / Labtec Spaceball 2003, 3003 and 4000 FLX on a serial line (C++
//! `vrpn_Spaceball`): its `vrpn.cfg` line ([`config`]), its [`Protocol`], and a device
//! simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Spaceball NAME PORT BAUD
//! ```
//!
//! The line is 8N1 at `BAUD` (9600 for the device), without flow control.
//!
//! # Reset
//!
//! The input is flushed and C++'s set-up string ([`INIT`]: communication mode, null region,
//! sensitivity, update rate, movement mode, zero, beep) is written one byte every
//! [`BYTE_GAP`], as C++ writes it (the device's input is slow). The reset is done when the
//! last byte is written (about 0.16 s); the device's answers to the commands are packets the
//! reader skips.
//!
//! # What is sent
//!
//! `NAME` is an Analog with six channels and a Button with twelve buttons:
//!
//! * channels 0, 1, 2 are the X, Y, Z translations and 3, 4, 5 the X, Y, Z rotations of the
//!   ball, raw / 32768 (about -1 to 1), zero within a null radius of 8 raw units, Z axes
//!   negated ([`packet::axes`]);
//! * a 2003/3003 reports nine buttons (`K` packets, C++'s mapping: [`packet::keys`]); a 4000
//!   FLX twelve (`.` packets, [`packet::keys_4000`]); once a `.` packet is seen, `K` packets
//!   (which the 4000 also sends) are ignored until the next reset.
//!
//! Each packet is reported on its own: a `vrpn_Analog Channel` message with all six channels
//! if one changed (LOW_LATENCY), or one `vrpn_Button Change` per changed button (RELIABLE),
//! stamped with the arrival of the packet's first byte.
//!
//! # Supervision
//!
//! The ball sends only when it is touched, so there is no watchdog (as in C++). A reset
//! banner (`@` packet) while streaming means the device reset itself: it is set up again. An
//! error packet (`E`) is reported in a warning text. Bytes that start no packet are skipped
//! and reported at most once a second. A port that fails is reopened every second.
//!
//! # Differences from C++ VRPN
//!
//! * Packets are stamped with their first byte's arrival, not with the time the read ended.
//! * Data and key packets must end in a plain (unescaped) carriage return, and have none
//!   before; a candidate that does not gives up one byte and the search goes on (C++ takes
//!   any 16 bytes after a `D`, and loses the packets the bad ones overlap).
//! * Each packet is reported with its own time stamp (C++ reports once per read).
//! * The reset does not zero the channels and buttons (a reset never invents data).
//! * The writes of the reset are paced by deadlines; the server is never blocked.

pub mod config;
pub mod packet;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::packet::{Framer, Kind, Packet, Unescape, AXES, BUTTONS};
use crate::devices::text::TextSeverity;
use crate::driver::text::ShownBytes;
use crate::driver::{Cx, Driver, Protocol, Reset, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{AnalogServer, ButtonServer, Connection, Error, Now};

pub use self::config::Spaceball;

/// The registry entry: `vrpn_Spaceball`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Spaceball"],
    parse: config::parse,
    hints: &[],
};

/// The set-up string C++ sends: communication mode, null region, sensitivity, update rate,
/// movement mode, zero, beep.
pub const INIT: &[u8] = b"CB\rNT\rFTp\rFRp\rP@r@r\rMSSV\rZ\rBcCcC\r";
/// Time between two bytes of [`INIT`] (C++ writes it "slowly", 5 ms a byte).
pub const BYTE_GAP: Duration = Duration::from_millis(5);

/// The Spaceball's protocol. See the module documentation.
pub struct SpaceballProtocol {
    baud: u32,
    unescape: Unescape,
    framer: Framer,
    reports: Reports,
    /// Bytes of [`INIT`] written so far in this reset, and when the next is due.
    written: usize,
    next_write: Option<Instant>,
}

/// What a packet changes: the servers and what the packets said about the device.
struct Reports {
    analog: AnalogServer,
    buttons: ButtonServer,
    /// A 4000 FLX was seen (its `.` packets replace the `K` packets).
    model_4000: bool,
    errors: u64,
}

impl SpaceballProtocol {
    /// The protocol of a `vrpn_Spaceball` entry, with its Analog and Button on `conn`.
    pub fn new(cfg: &Spaceball, conn: &Connection) -> Result<SpaceballProtocol, Error> {
        Ok(SpaceballProtocol {
            baud: cfg.baud,
            unescape: Unescape::default(),
            framer: Framer::new(),
            reports: Reports {
                analog: AnalogServer::new(&cfg.name, conn, AXES)?,
                buttons: ButtonServer::new(&cfg.name, conn, BUTTONS)?,
                model_4000: false,
                errors: 0,
            },
            written: 0,
            next_write: None,
        })
    }

    /// True once a 4000 FLX key packet was seen since the last reset.
    pub fn is_4000(&self) -> bool {
        self.reports.model_4000
    }

    /// Error packets received since construction.
    pub fn errors(&self) -> u64 {
        self.reports.errors
    }

    /// Bytes skipped looking for packets, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    /// Finds packets in `bytes` and handles each. Returns true if the device reset itself
    /// while `streaming` (the rest of the read is dropped: it is set up again).
    fn take(&mut self, bytes: &[u8], cx: &mut Cx<'_>, streaming: bool) -> bool {
        let mut banner = false;
        for &b in bytes {
            let Some((b, escaped)) = self.unescape.push(b) else {
                continue;
            };
            let reports = &mut self.reports;
            self.framer.push(b, escaped, cx.now, &mut |p| {
                if !banner {
                    banner = reports.handle(&p, cx, streaming);
                }
            });
            let skipped = self.framer.take_skipped();
            cx.skipped(skipped, "Spaceball", format_args!(""));
            if banner {
                return true;
            }
        }
        false
    }
}

impl Reports {
    /// Handles one packet; true for a reset banner while streaming.
    fn handle(&mut self, p: &Packet, cx: &mut Cx<'_>, streaming: bool) -> bool {
        let at = p.first_byte;
        let bytes = p.bytes();
        match p.kind {
            Kind::Displacement => {
                let values = packet::axes(bytes);
                self.analog.channels_mut().copy_from_slice(&values);
                // A failed send is the connection's business (it reports and drops the peer).
                let _ = self.analog.report_changes(Some(at.wall));
            }
            Kind::Keys if !self.model_4000 => {
                for (i, &down) in packet::keys(bytes).iter().enumerate() {
                    self.buttons.set_button(i, down);
                }
                self.report_buttons(at);
            }
            Kind::Keys4000 => {
                if !self.model_4000 {
                    self.model_4000 = true;
                    cx.say(
                        TextSeverity::Normal,
                        format_args!("Spaceball 4000 FLX detected (twelve buttons)"),
                    );
                }
                let (down, _lefty) = packet::keys_4000(bytes);
                for (i, &d) in down.iter().enumerate() {
                    self.buttons.set_button(i, d);
                }
                self.report_buttons(at);
            }
            Kind::Error => {
                self.errors += 1;
                cx.say(
                    TextSeverity::Warning,
                    format_args!("Spaceball error packet: {}", ShownBytes(bytes)),
                );
            }
            Kind::ResetBanner if streaming => {
                cx.say(
                    TextSeverity::Warning,
                    format_args!("Spaceball reset itself; setting it up again"),
                );
                return true;
            }
            Kind::Keys | Kind::ResetBanner | Kind::Other => {}
        }
        cx.record(at);
        false
    }

    fn report_buttons(&mut self, at: Now) {
        self.buttons.set_timestamp(at.wall);
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.buttons.report_changes_unfiltered();
    }
}

impl Protocol for SpaceballProtocol {
    const KIND: &'static str = "Spaceball";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision::QUIET
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        cx.flush_input();
        self.reports.model_4000 = false;
        self.written = 1;
        cx.write(&INIT[..1]);
        self.next_write = Some(cx.now.mono + BYTE_GAP);
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        // Answers to the set-up commands, or the ball touched meanwhile (fresh: the input
        // was flushed). A banner here is the device answering the set-up; it is ignored.
        self.take(bytes, cx, false);
        Reset::Working
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        if self.written < INIT.len() {
            cx.write(&INIT[self.written..self.written + 1]);
            self.written += 1;
        }
        if self.written < INIT.len() {
            self.next_write = Some(cx.now.mono + BYTE_GAP);
            return Reset::Working;
        }
        self.next_write = None;
        cx.say(
            TextSeverity::Normal,
            format_args!("Spaceball reset: set-up commands sent"),
        );
        Reset::Done
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.next_write
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        if self.take(bytes, cx, true) {
            cx.reset();
        }
    }

    fn stopped(&mut self) {
        self.unescape.clear();
        self.framer.clear();
        self.written = 0;
        self.next_write = None;
    }
}

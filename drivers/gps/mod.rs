//! A GPS receiver sending NMEA 0183 sentences on a serial line (`vrpn_Tracker_GPS`):
//! sentences found byte by byte and checked ([`nmea`]), each GGA fix reported as a pose; a
//! simulator in `sim` (with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tracker_GPS NAME PORT BAUD
//! ```
//!
//! 8N1 at `BAUD` (4800 for most receivers), no flow control; RTS is set (some receivers
//! take their power from it), as C++ VRPN does.
//!
//! # What is sent
//!
//! The tracker `NAME` has one sensor. Each GGA sentence with a fix (latitude, longitude and
//! altitude present) sends one `vrpn_Tracker Pos_Quat` (LOW_LATENCY): position = (latitude
//! in degrees, north positive; longitude in degrees, east positive; altitude in metres),
//! the identity quaternion — C++ VRPN's layout — stamped with the arrival of the sentence's
//! `$`. Other sentences (RMC, GSV, GSA, …) are read, checked and passed over.
//!
//! # Supervision
//!
//! The reset sets RTS and waits [`RESET_WAIT`]; there is nothing to ask a receiver. 2 s
//! without a good sentence of any kind (a receiver without a fix still talks): C++'s two
//! tracker texts, the port reopened ([`Supervision::TRACKER`]).

pub mod config;
pub mod nmea;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::nmea::{kind, parse_gga, SentenceReader};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Reset, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{Connection, Error, TrackerServer};

pub use self::config::Gps;

/// The registry entry: `vrpn_Tracker_GPS`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_GPS"],
    parse: config::parse,
    hints: &[],
};

/// Time after setting RTS before sentences are read (C++'s wait).
pub const RESET_WAIT: Duration = Duration::from_millis(100);

/// The identity quaternion (x, y, z, w): a GPS gives no orientation.
const IDENTITY: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

/// The GPS protocol: its reset, its sentences, its reports.
pub struct GpsProtocol {
    baud: u32,
    tracker: TrackerServer,
    reader: SentenceReader,
    ready_at: Option<Instant>,
    without_fix: u32,
}

impl GpsProtocol {
    /// The protocol of an entry, with its server on `conn`.
    pub fn new(cfg: &Gps, conn: &Connection) -> Result<GpsProtocol, Error> {
        Ok(GpsProtocol {
            baud: cfg.baud,
            tracker: TrackerServer::new(&cfg.name, conn, 1)?,
            reader: SentenceReader::new(),
            ready_at: None,
            without_fix: 0,
        })
    }

    /// The tracker server the fixes go out through.
    pub fn tracker(&self) -> &TrackerServer {
        &self.tracker
    }
}

impl Protocol for GpsProtocol {
    const KIND: &'static str = "GPS";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision::TRACKER
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        cx.set_rts(true);
        self.ready_at = Some(cx.now.mono + RESET_WAIT);
        Reset::Working
    }

    fn reset_received(&mut self, _bytes: &[u8], _cx: &mut Cx<'_>) -> Reset {
        Reset::Working
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        if self.ready_at.is_some_and(|t| cx.now.mono >= t) {
            self.ready_at = None;
            cx.flush_input();
            self.reader.clear();
            cx.say(
                TextSeverity::Warning,
                format_args!("Reset Completed (this is good)"),
            );
            return Reset::Done;
        }
        Reset::Working
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.ready_at
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            let Some(s) = self.reader.push(b, cx.now) else {
                continue;
            };
            let (skipped, first_byte) = (s.skipped as u64, s.first_byte);
            let fix = parse_gga(s.body);
            let is_gga = kind(s.body) == "GGA";
            match self.reader.take_rejected() {
                Some(why) => cx.skipped(skipped, "GPS", format_args!(" (last dropped: {why:?})")),
                None => cx.skipped(skipped, "GPS", format_args!("")),
            }
            cx.record(first_byte);
            if let Some(f) = fix {
                self.without_fix = 0;
                let _ =
                    self.tracker
                        .report_pose(0, first_byte.wall, [f.lat, f.lon, f.alt], IDENTITY);
            } else if is_gga {
                self.without_fix += 1;
                if self.without_fix == 1 {
                    cx.say(
                        TextSeverity::Warning,
                        format_args!(
                            "GPS cannot determine position (empty fields). Wait for \
                             satellites or reposition GPS."
                        ),
                    );
                }
            }
        }
    }

    fn stopped(&mut self) {
        self.reader.clear();
        self.ready_at = None;
    }
}

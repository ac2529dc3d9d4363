//! Polhemus Fastrak, and InterSense IS-600 / IS-900 trackers in their Fastrak-compatible
//! serial mode: the `vrpn.cfg` lines ([`config`]), the [`Protocol`] run by the shared
//! [`Lifecycle`](crate::driver::Lifecycle), and a device simulator (`sim`, with the `sim`
//! feature).
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_Tracker_Fastrak NAME PORT BAUD [IS900time | / | \]
//! ```
//!
//! followed, when the line ends in `\`, by extra reset commands (one per line, each sent with
//! a CR; `*N` pauses N seconds), and, when a line ends in `/`, by station devices:
//!
//! ```text
//! Wand NAME SENSOR C0MIN C0LOWZERO C0HIGHZERO C0MAX C1MIN C1LOWZERO C1HIGHZERO C1MAX
//! Stylus NAME SENSOR
//! FTStylus NAME SENSOR
//! ```
//!
//! The tracker `NAME` has four sensors (stations 1 to 4 are sensors 0 to 3). A `Wand` exports
//! an Analog with two channels (joystick x and y through the clip values) and a Button with
//! six buttons, both named after the wand; a `Stylus` a Button with two buttons; an
//! `FTStylus` (a genuine Fastrak stylus) a Button with one, and it switches every station's
//! buttons to the Fastrak stylus format. `IS900time` makes an IS-900 stamp its records with
//! its own clock, zeroed at reset.
//!
//! [`FastrakProtocol::from_intersense`] runs a `vrpn_Tracker_InterSense` entry (which C++ serves
//! through InterSense's SDK) over the same Fastrak-compatible protocol, on a serial port and
//! baud rate the caller supplies.
//!
//! # What is sent
//!
//! For each record: the station device's `vrpn_Button Change` messages (RELIABLE) for changed
//! buttons, its `vrpn_Analog Channel` message (LOW_LATENCY) if the joystick moved, then one
//! `vrpn_Tracker Pos_Quat` (LOW_LATENCY): sensor = station − 1, position in metres (the
//! tracker's inches × 0.0254), quaternion x, y, z, w as received. All three carry the record's
//! time: the arrival of its first byte at the port or, with IS-900 timestamps, the tracker's
//! clock zero plus the record's milliseconds. (C++ stamps the button messages with time zero
//! and the analog message with the time it is sent; a client sees the same messages, with a
//! useful time.) Resets, time-outs and resynchronisations are reported as text messages from
//! the tracker's name.
//!
//! # Supervision
//!
//! The reset sequence ([`reset`]) is a state machine over deadlines. Once streaming, a gap of
//! more than 2 s since the first byte of the last good record (or the end of the reset:
//! [`Supervision::TRACKER`]) sends two error texts, closes and reopens the port and resets
//! again; consecutive failed attempts escalate as described in [`reset`]. Garbage is skipped
//! byte by byte ([`framing`]) without losing the records after it.
//!
//! With IS-900 timestamps, a record whose device time is not a finite number of milliseconds
//! between 0 and [`MAX_DEVICE_MS`] (line noise that passed the record checks, a tracker
//! sending ±∞, NaN or ±3.4·10³⁸) is stamped with the arrival of its first byte instead, and
//! counted ([`FastrakProtocol::bad_times`]); a warning text says so at most once a second.

pub mod config;
pub mod framing;
pub mod record;
pub mod reset;
#[cfg(any(test, feature = "sim"))]
pub mod sim;
pub mod stations;

#[cfg(test)]
mod tests;

use std::fmt;
use std::time::{Duration, Instant};

use self::framing::{Framed, Framer, Reject};
use self::record::{is900_offset, ButtonFormat, StationFormat, MAX_STATIONS};
use self::reset::{Extra, Progress, ResetPlan, ResetSequence, Say};
use self::stations::StationServers;
use crate::devices::text::TextSeverity;
use crate::driver::registry::{Driver, Hint};
use crate::driver::text::Shown;
use crate::driver::{Cx, Protocol, Reset, Supervision, Texts};
use crate::serial::{PortKind, PortSettings};
use crate::time::TimeVal;
use crate::{Connection, Error, TrackerServer};

use self::config::{Fastrak, InterSense, ResetStep, StationDevice};

/// The registry entry: `vrpn_Tracker_Fastrak`, and `vrpn_Tracker_InterSense` (refused with
/// an explanation: C++ serves it through InterSense's own library).
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_Fastrak", "vrpn_Tracker_InterSense"],
    parse: |line| {
        if line.keyword() == "vrpn_Tracker_InterSense" {
            config::parse_intersense(line)
        } else {
            config::parse_fastrak(line)
        }
    },
    hints: &[Hint {
        keyword: "vrpn_Tracker_IS900",
        text: "VRPN has no such keyword; run an IS-900 with vrpn_Tracker_Fastrak NAME PORT \
               BAUD IS900time (or vrpn_Tracker_InterSense)",
    }],
};

/// The largest IS-900 device time taken for a time (2^33 ms, about 99 days after the reset
/// zeroed the tracker's clock); beyond it, or not finite, a record is stamped with its arrival.
pub const MAX_DEVICE_MS: f32 = 8_589_934_592.0;

/// At most one warning about unusable device times per this interval.
const BAD_TIME_NOTE_INTERVAL: Duration = Duration::from_secs(1);

/// Position filter command VRPN's server always sends.
const POSITION_FILTER: &[u8] = b"x0.2,0.2,0.8,0.8\r";
/// Orientation filter command VRPN's server always sends.
const ORIENTATION_FILTER: &[u8] = b"v0.2,0.2,0.8,0.8\r";
/// Selects the genuine Fastrak stylus button format.
const STYLUS_FORMAT: &[u8] = b"e1,0\r";

/// The protocol of a Fastrak (or IS-600 / IS-900 in Fastrak mode). See the module
/// documentation.
pub struct FastrakProtocol {
    port: String,
    baud: u32,
    tracker: TrackerServer,
    /// Index = station − 1.
    stations: Vec<Option<StationServers>>,
    formats: Vec<StationFormat>,
    framer: Framer,
    reset: ResetSequence,
    is900_time: bool,
    clock_zero: Option<TimeVal>,
    bad_times: u64,
    last_bad_time_note: Option<Instant>,
}

impl FastrakProtocol {
    /// The protocol of a `vrpn_Tracker_Fastrak` entry, with its tracker (four sensors) and
    /// station devices served on `conn`.
    pub fn new(cfg: &Fastrak, conn: &Connection) -> Result<FastrakProtocol, Error> {
        FastrakProtocol::build(
            Setup {
                name: &cfg.name,
                port: &cfg.port,
                baud: cfg.baud,
                is900_time: cfg.is900_timestamps,
                reset_commands: &cfg.reset_commands,
                devices: &cfg.stations,
                stations: Fastrak::STATIONS as usize,
            },
            conn,
        )
    }

    /// The protocol of a `vrpn_Tracker_InterSense` entry, run over the Fastrak-compatible
    /// serial protocol (not InterSense's SDK) on `port` at `baud`, which the entry's
    /// `COMn`/`AUTO` does not give. The tracker has eight sensors; `ResetAtStartup` changes
    /// nothing, because the port is always reset when it opens.
    pub fn from_intersense(
        cfg: &InterSense,
        port: &str,
        baud: u32,
        conn: &Connection,
    ) -> Result<FastrakProtocol, Error> {
        FastrakProtocol::build(
            Setup {
                name: &cfg.name,
                port,
                baud,
                is900_time: cfg.is900_timestamps,
                reset_commands: &cfg.reset_commands,
                devices: &cfg.stations,
                stations: InterSense::STATIONS as usize,
            },
            conn,
        )
    }

    fn build(s: Setup<'_>, conn: &Connection) -> Result<FastrakProtocol, Error> {
        debug_assert!(s.stations <= MAX_STATIONS);
        if s.devices.iter().any(|d| d.sensor() as usize >= s.stations) {
            return Err(Error::Unsupported(
                "a station device is on a sensor the tracker does not have",
            ));
        }
        let really_fastrak = s
            .devices
            .iter()
            .any(|d| matches!(d, StationDevice::FtStylus { .. }));
        let tracker = TrackerServer::new(s.name, conn, s.stations)?;
        let mut stations = Vec::with_capacity(s.stations);
        let mut formats = Vec::with_capacity(s.stations);
        for sensor in 0..s.stations {
            let device = s.devices.iter().find(|d| d.sensor() as usize == sensor);
            formats.push(StationFormat {
                timestamp: s.is900_time,
                buttons: match (device, really_fastrak) {
                    (None, _) => ButtonFormat::None,
                    (Some(_), true) => ButtonFormat::FastrakStylus,
                    (Some(_), false) => ButtonFormat::Is900,
                },
                joystick: matches!(device, Some(StationDevice::Wand { .. })),
            });
            stations.push(device.map(|d| StationServers::new(d, conn)).transpose()?);
        }
        let mut commands: Vec<Vec<u8>> = formats
            .iter()
            .zip(1u8..)
            .map(|(f, station)| f.output_list_command(station))
            .collect();
        if really_fastrak {
            commands.push(STYLUS_FORMAT.to_vec());
        }
        commands.push(POSITION_FILTER.to_vec());
        commands.push(ORIENTATION_FILTER.to_vec());
        let extra = s
            .reset_commands
            .iter()
            .map(|step| match step {
                ResetStep::Pause(secs) => Extra::Pause(Duration::from_secs(u64::from(*secs))),
                ResetStep::Command(text) => {
                    let mut bytes = text.as_bytes().to_vec();
                    bytes.push(b'\r');
                    Extra::Command(bytes)
                }
            })
            .collect();
        Ok(FastrakProtocol {
            port: s.port.to_owned(),
            baud: s.baud,
            tracker,
            stations,
            framer: Framer::new(&formats),
            formats,
            reset: ResetSequence::new(ResetPlan {
                commands,
                extra,
                is900_time: s.is900_time,
                baud: s.baud,
            }),
            is900_time: s.is900_time,
            clock_zero: None,
            bad_times: 0,
            last_bad_time_note: None,
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

    /// The layout of each station's records (index = station − 1).
    pub fn formats(&self) -> &[StationFormat] {
        &self.formats
    }

    /// The servers of the device on `sensor` (0-based), if one was configured.
    pub fn station(&self, sensor: usize) -> Option<&StationServers> {
        self.stations.get(sensor).and_then(Option::as_ref)
    }

    /// Consecutive reset attempts so far (0 after the tracker answered a status request).
    pub fn reset_attempts(&self) -> u32 {
        self.reset.attempts()
    }

    /// With IS-900 timestamps, the host time of the tracker clock's zero.
    pub fn clock_zero(&self) -> Option<TimeVal> {
        self.clock_zero
    }

    /// Records whose IS-900 device time was not a time (stamped with their arrival instead).
    pub fn bad_times(&self) -> u64 {
        self.bad_times
    }

    /// Bytes skipped while resynchronising, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    fn progress(&mut self, p: Progress, cx: &mut Cx<'_>) -> Reset {
        match p {
            Progress::Busy => Reset::Working,
            Progress::Done { clock_zero } => {
                self.clock_zero = clock_zero;
                self.framer.clear();
                cx.say(
                    TextSeverity::Warning,
                    format_args!("Reset Completed (this is good)"),
                );
                Reset::Done
            }
        }
    }

    /// The record's time: with IS-900 timestamps, the tracker's clock zero plus its device
    /// time, if that is a time; else the arrival of its first byte.
    fn record_time(&mut self, framed: &Framed, cx: &mut Cx<'_>) -> TimeVal {
        let (Some(zero), Some(ms)) = (
            self.clock_zero.filter(|_| self.is900_time),
            framed.record.time_ms,
        ) else {
            return framed.first_byte.wall;
        };
        if ms.is_finite() && (0.0..=MAX_DEVICE_MS).contains(&ms) {
            return TimeVal::from_micros(zero.as_micros() + is900_offset(ms).as_micros());
        }
        self.bad_times += 1;
        let now = framed.first_byte.mono;
        if self
            .last_bad_time_note
            .map_or(true, |t| now >= t + BAD_TIME_NOTE_INTERVAL)
        {
            self.last_bad_time_note = Some(now);
            cx.say(
                TextSeverity::Warning,
                format_args!(
                    "IS-900 timestamp {ms} ms is not a time since the reset; {} such record(s) \
                     stamped with their arrival instead",
                    self.bad_times
                ),
            );
        }
        framed.first_byte.wall
    }

    fn report(&mut self, framed: Framed, cx: &mut Cx<'_>) {
        if let Some(r) = framed.resync {
            let n = r.skipped;
            let sev = TextSeverity::Normal;
            match r.reason {
                Reject::NotRecordStart(b) => cx.say(
                    sev,
                    format_args!(
                        "While syncing (looking for '0', got {}), skipped {n} bytes",
                        Shown(b)
                    ),
                ),
                Reject::BadStation(b) => cx.say(
                    sev,
                    format_args!(
                        "Bad sensor # ({}) in record, re-synced after {n} bytes",
                        i32::from(b) - i32::from(b'1')
                    ),
                ),
                Reject::BadStatus(_) => cx.say(
                    sev,
                    format_args!("Bad 3rd char in record, re-synced after {n} bytes"),
                ),
                Reject::NoClosingSpace(_) => cx.say(
                    sev,
                    format_args!("No space character at end of report, re-synced after {n} bytes"),
                ),
            }
        }
        let time = self.record_time(&framed, cx);
        cx.record(framed.first_byte);
        let rec = framed.record;
        let index = usize::from(rec.station - 1);
        if let Some(device) = self.stations[index].as_mut() {
            device.report(&rec, self.formats[index].buttons, time);
        }
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.tracker.report_pose(
            i32::from(rec.station) - 1,
            time,
            rec.position_m(),
            rec.quat_xyzw(),
        );
    }
}

/// The parts of an entry the protocol needs.
struct Setup<'a> {
    name: &'a str,
    port: &'a str,
    baud: u32,
    is900_time: bool,
    reset_commands: &'a [ResetStep],
    devices: &'a [StationDevice],
    stations: usize,
}

impl Protocol for FastrakProtocol {
    const KIND: &'static str = "Fastrak";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision::TRACKER
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.framer.clear();
        let now = cx.now;
        let (port, texts) = cx.port_and_texts();
        let p = self.reset.start(now, port, &mut TextsSay(texts));
        self.progress(p, cx)
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        let now = cx.now;
        let (port, texts) = cx.port_and_texts();
        let p = self.reset.received(bytes, now, port, &mut TextsSay(texts));
        self.progress(p, cx)
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        let now = cx.now;
        let (port, texts) = cx.port_and_texts();
        let p = self.reset.poll(now, port, &mut TextsSay(texts));
        self.progress(p, cx)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.reset.deadline()
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            self.framer.push(b, cx.now);
            while let Some(framed) = self.framer.next_record() {
                self.report(framed, cx);
            }
        }
    }

    fn stopped(&mut self) {
        self.reset.stop();
        self.framer.clear();
    }
}

/// The reset's texts, sent from the tracker's name.
struct TextsSay<'a>(&'a Texts);

impl Say for TextsSay<'_> {
    fn say(&mut self, severity: TextSeverity, args: fmt::Arguments<'_>) {
        self.0.say(severity, args);
    }
}

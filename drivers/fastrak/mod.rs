//! Polhemus Fastrak, and InterSense IS-600 / IS-900 trackers in their Fastrak-compatible
//! serial mode: a sans-IO [`SerialDriver`] and a device simulator (`sim`, with the `sim` feature).
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
//! [`FastrakDriver::from_intersense`] runs a `vrpn_Tracker_InterSense` entry (which C++ serves
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
//! more than [`WATCHDOG`] since the first byte of the last good record (or the end of the
//! reset) sends two error texts, closes and reopens the port and resets again; consecutive
//! failed attempts escalate as described in [`reset`]. Garbage is skipped byte by byte
//! ([`framing`]) without losing the records after it.

pub mod config;
pub mod framing;
pub mod record;
pub mod reset;
#[cfg(any(test, feature = "sim"))]
pub mod sim;
pub mod stations;

#[cfg(test)]
mod tests;

use std::fmt::{self, Write as _};
use std::time::{Duration, Instant};

use self::framing::{Framed, Framer, Reject};
use self::record::{is900_offset, ButtonFormat, StationFormat, MAX_STATIONS};
use self::reset::{Extra, Progress, ResetPlan, ResetSequence, Say};
use self::stations::StationServers;
use crate::devices::text::TextSeverity;
use crate::driver::registry::{Driver, Hint};
use crate::serial::{PortKind, PortOps, PortSettings, SerialDriver};

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
use crate::time::{Now, TimeVal};
use crate::{Connection, Error, TrackerServer};

/// Longest gap between good records before the tracker is declared failed and reset (as C++).
pub const WATCHDOG: Duration = Duration::from_secs(2);

/// Position filter command VRPN's server always sends.
const POSITION_FILTER: &[u8] = b"x0.2,0.2,0.8,0.8\r";
/// Orientation filter command VRPN's server always sends.
const ORIENTATION_FILTER: &[u8] = b"v0.2,0.2,0.8,0.8\r";
/// Selects the genuine Fastrak stylus button format.
const STYLUS_FORMAT: &[u8] = b"e1,0\r";

/// Where the driver is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    /// The port is closed (or being reopened).
    Closed,
    /// The reset sequence runs.
    Resetting,
    /// Records are streaming.
    Streaming,
}

/// A Fastrak (or IS-600 / IS-900 in Fastrak mode) on one serial port.
pub struct FastrakDriver {
    name: String,
    port: String,
    baud: u32,
    tracker: TrackerServer,
    /// Index = station − 1.
    stations: Vec<Option<StationServers>>,
    formats: Vec<StationFormat>,
    framer: Framer,
    reset: ResetSequence,
    mode: Mode,
    is900_time: bool,
    clock_zero: Option<TimeVal>,
    /// First byte of the last good record, or the end of the reset: the watchdog's start.
    last_record: Option<Now>,
    records: u64,
}

impl FastrakDriver {
    /// The driver for a `vrpn_Tracker_Fastrak` entry, with its tracker (four sensors) and
    /// station devices served on `conn`.
    pub fn new(cfg: &Fastrak, conn: &Connection) -> Result<FastrakDriver, Error> {
        FastrakDriver::build(
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

    /// The driver for a `vrpn_Tracker_InterSense` entry, run over the Fastrak-compatible
    /// serial protocol (not InterSense's SDK) on `port` at `baud`, which the entry's
    /// `COMn`/`AUTO` does not give. The tracker has eight sensors; `ResetAtStartup` changes
    /// nothing, because the port is always reset when it opens.
    pub fn from_intersense(
        cfg: &InterSense,
        port: &str,
        baud: u32,
        conn: &Connection,
    ) -> Result<FastrakDriver, Error> {
        FastrakDriver::build(
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

    fn build(s: Setup<'_>, conn: &Connection) -> Result<FastrakDriver, Error> {
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
        Ok(FastrakDriver {
            name: s.name.to_owned(),
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
            mode: Mode::Closed,
            is900_time: s.is900_time,
            clock_zero: None,
            last_record: None,
            records: 0,
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

    /// True once the reset finished and records are expected.
    pub fn is_streaming(&self) -> bool {
        self.mode == Mode::Streaming
    }

    /// Consecutive reset attempts so far (0 after the tracker answered a status request).
    pub fn reset_attempts(&self) -> u32 {
        self.reset.attempts()
    }

    /// With IS-900 timestamps, the host time of the tracker clock's zero.
    pub fn clock_zero(&self) -> Option<TimeVal> {
        self.clock_zero
    }

    /// Good records reported since construction.
    pub fn records(&self) -> u64 {
        self.records
    }

    /// Bytes skipped while resynchronising, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    fn progress(&mut self, p: Progress, now: Now) {
        if let Progress::Done { clock_zero } = p {
            self.mode = Mode::Streaming;
            self.clock_zero = clock_zero;
            self.last_record = Some(now);
            self.framer.clear();
            say(
                &self.tracker,
                TextSeverity::Warning,
                format_args!("Reset Completed (this is good)"),
            );
        }
    }

    fn report(&mut self, framed: Framed) {
        if let Some(r) = framed.resync {
            let n = r.skipped;
            let sev = TextSeverity::Normal;
            let t = &self.tracker;
            match r.reason {
                Reject::NotRecordStart(b) => say(
                    t,
                    sev,
                    format_args!(
                        "While syncing (looking for '0', got {}), skipped {n} bytes",
                        Shown(b)
                    ),
                ),
                Reject::BadStation(b) => say(
                    t,
                    sev,
                    format_args!(
                        "Bad sensor # ({}) in record, re-synced after {n} bytes",
                        i32::from(b) - i32::from(b'1')
                    ),
                ),
                Reject::BadStatus(_) => say(
                    t,
                    sev,
                    format_args!("Bad 3rd char in record, re-synced after {n} bytes"),
                ),
                Reject::NoClosingSpace(_) => say(
                    t,
                    sev,
                    format_args!("No space character at end of report, re-synced after {n} bytes"),
                ),
            }
        }
        let rec = framed.record;
        let time = match (self.is900_time, self.clock_zero, rec.time_ms) {
            (true, Some(zero), Some(ms)) => {
                TimeVal::from_micros(zero.as_micros() + is900_offset(ms).as_micros())
            }
            _ => framed.first_byte.wall,
        };
        self.last_record = Some(framed.first_byte);
        self.records += 1;
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

    fn watchdog(&mut self, now: Now, port: &mut PortOps) {
        let Some(last) = self.last_record else {
            return;
        };
        if now.mono < last.mono + WATCHDOG {
            return;
        }
        let (cur, ts) = (now.wall, last.wall);
        say(
            &self.tracker,
            TextSeverity::Error,
            format_args!(
                "Tracker failed to read... current_time={}:{}, timestamp={}:{}",
                cur.sec, cur.usec, ts.sec, ts.usec
            ),
        );
        say(
            &self.tracker,
            TextSeverity::Error,
            format_args!(
                "Tracker failed, trying to reset (Try power cycle if more than 4 attempts made)"
            ),
        );
        self.mode = Mode::Closed;
        self.last_record = None;
        self.framer.clear();
        port.reopen();
    }
}

/// The parts of an entry the driver needs.
struct Setup<'a> {
    name: &'a str,
    port: &'a str,
    baud: u32,
    is900_time: bool,
    reset_commands: &'a [ResetStep],
    devices: &'a [StationDevice],
    stations: usize,
}

impl SerialDriver for FastrakDriver {
    fn name(&self) -> &str {
        &self.name
    }

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn opened(&mut self, now: Now, port: &mut PortOps) {
        self.framer.clear();
        self.last_record = None;
        self.mode = Mode::Resetting;
        let p = self.reset.start(now, port, &mut TrackerSay(&self.tracker));
        self.progress(p, now);
    }

    fn received(&mut self, bytes: &[u8], arrived: Now, port: &mut PortOps) {
        match self.mode {
            Mode::Closed => {}
            Mode::Resetting => {
                let p = self
                    .reset
                    .received(bytes, arrived, port, &mut TrackerSay(&self.tracker));
                self.progress(p, arrived);
            }
            Mode::Streaming => {
                for &b in bytes {
                    self.framer.push(b, arrived);
                    while let Some(framed) = self.framer.next_record() {
                        self.report(framed);
                    }
                }
            }
        }
    }

    fn poll(&mut self, now: Now, port: &mut PortOps) {
        match self.mode {
            Mode::Closed => {}
            Mode::Resetting => {
                let p = self.reset.poll(now, port, &mut TrackerSay(&self.tracker));
                self.progress(p, now);
            }
            Mode::Streaming => self.watchdog(now, port),
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        match self.mode {
            Mode::Closed => None,
            Mode::Resetting => self.reset.deadline(),
            Mode::Streaming => self.last_record.map(|t| t.mono + WATCHDOG),
        }
    }

    fn closed(&mut self, _now: Now) {
        self.mode = Mode::Closed;
        self.reset.stop();
        self.framer.clear();
        self.last_record = None;
    }
}

/// Sends texts from the tracker's sender.
struct TrackerSay<'a>(&'a TrackerServer);

impl Say for TrackerSay<'_> {
    fn say(&mut self, severity: TextSeverity, args: fmt::Arguments<'_>) {
        say(self.0, severity, args);
    }
}

/// Formats a text message on the stack (no allocation) and sends it from `tracker`.
fn say(tracker: &TrackerServer, severity: TextSeverity, args: fmt::Arguments<'_>) {
    let mut text = TextBuf::default();
    let _ = text.write_fmt(args);
    // A failed send is the connection's business (it reports and drops the peer).
    let _ = tracker.send_text(severity, 0, text.as_str());
}

/// A byte as C++ prints it in messages: the character if printable, else its hex value.
struct Shown(u8);

impl fmt::Display for Shown {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_ascii_graphic() || self.0 == b' ' {
            write!(f, "'{}'", self.0 as char)
        } else {
            write!(f, "0x{:02X}", self.0)
        }
    }
}

/// A fixed buffer for one text message; longer text is cut at a character boundary.
struct TextBuf {
    buf: [u8; 256],
    len: usize,
}

impl Default for TextBuf {
    fn default() -> TextBuf {
        TextBuf {
            buf: [0; 256],
            len: 0,
        }
    }
}

impl TextBuf {
    fn as_str(&self) -> &str {
        // Only whole characters are ever copied in.
        std::str::from_utf8(&self.buf[..self.len]).unwrap_or("")
    }
}

impl fmt::Write for TextBuf {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let room = self.buf.len() - self.len;
        let mut n = s.len().min(room);
        while !s.is_char_boundary(n) {
            n -= 1;
        }
        self.buf[self.len..self.len + n].copy_from_slice(&s.as_bytes()[..n]);
        self.len += n;
        Ok(())
    }
}

//! `vrpn_Tracker_JsonNet`: a Tracker, Button, Analog and text sender fed JSON messages over UDP
//! (C++ VRPN's protocol of its Android widgets; any program that sends such datagrams).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tracker_JsonNet NAME UDP_PORT
//! ```
//!
//! `UDP_PORT` is bound on every IPv4 interface (0: any free port, beyond C++). See
//! docs/DRIVERS.md.
//!
//! # What is received and sent
//!
//! Each datagram (under 2000 bytes, as C++) holds one JSON object, read as C++ VRPN reads it
//! ([`message::parse`]): `{"type":1,"id":S,"quat":[x,y,z,w],"pos":[x,y,z]}` sends a
//! `vrpn_Tracker Pos_Quat` for sensor `S` (a `quat` or `pos` left out keeps the previous one);
//! `{"type":2,"button":B,"state":true}` sets button `B` of 256; `{"type":3,"num":C,"data":V}`
//! sets channel `C` of 128; `{"type":4,"data":"text"}` sends a text (`vrpn_TEXT_NORMAL`).
//! After each accepted message the buttons that changed and (if any channel changed) all 128
//! channels are reported, stamped with the datagram's arrival. Anything else is counted
//! ([`JsonNetStats`]) and skipped; a warning text says why, at most once a second.

pub mod message;
#[cfg(test)]
mod tests;

use std::fmt::Write as _;
use std::time::{Duration, Instant};

use crate::config::{ConfigError, ConfigLine};
use crate::devices::analog::AnalogServer;
use crate::devices::button::ButtonServer;
use crate::devices::text::TextSeverity;
use crate::devices::tracker::TrackerServer;
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::driver::udp::{Datagram, UdpSource};
use crate::error::Error;
use crate::time::Now;
use crate::Connection;

pub use message::{parse, Message, Rejected};

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_JsonNet"],
    parse: parse_line,
    hints: &[],
};

/// C++'s receive buffer: a datagram of this many bytes or more is dropped.
pub const DATAGRAM_MAX: usize = 2000;
/// Buttons (C++'s `vrpn_BUTTON_MAX_BUTTONS`).
pub const BUTTONS: usize = 256;
/// Analog channels (C++'s `vrpn_CHANNEL_MAX`), all sent in every analog report.
pub const CHANNELS: usize = 128;
/// Tracker sensors served (C++ sends any 32-bit sensor number; ours are 0 to 511).
pub const SENSORS: usize = 512;
/// The longest text VRPN sends (C++'s `vrpn_MAX_TEXT_LEN` less its terminating NUL).
pub const TEXT_MAX: usize = 1023;

/// The `vrpn_Tracker_JsonNet` line.
#[derive(Clone, Debug, PartialEq)]
pub struct JsonNet {
    /// Device name of the tracker, button, analog and text sender.
    pub name: String,
    /// UDP port listened on (0: any free port).
    pub port: u16,
}

fn parse_line(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(2, "name, UDP port")?;
    let name = line.name(0)?;
    let port = line.uint(1, "UDP port", 0, u32::from(u16::MAX))? as u16;
    Ok(Box::new(JsonNet { name, port }))
}

impl DeviceSpec for JsonNet {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(
            &self.name,
            &[Interface::Tracker, Interface::Button, Interface::Analog],
        )
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(JsonNetDevice::new(self, cx.conn())?)])
    }
}

/// What the device received so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct JsonNetStats {
    /// Datagrams read.
    pub datagrams: u64,
    /// Messages accepted (C++ would have acted on them).
    pub accepted: u64,
    /// Datagrams that are not JSON (or not UTF-8).
    pub malformed: u64,
    /// JSON that is not a message C++ accepts (no object, no or unknown type, a required
    /// field missing or unusable).
    pub rejected: u64,
    /// Datagrams of [`DATAGRAM_MAX`] bytes or more.
    pub too_long: u64,
    /// Accepted messages naming a sensor, button or channel out of range, or a text too long
    /// for VRPN (nothing sent for them, as C++ except for sensors).
    pub out_of_range: u64,
}

/// The servers and the state messages build on.
struct Stream {
    name: String,
    tracker: TrackerServer,
    button: ButtonServer,
    analog: AnalogServer,
    pos: [f64; 3],
    quat: [f64; 4],
    /// A text message's characters (room for a datagram: never grows).
    text: String,
    /// A warning's words (likewise).
    warning: String,
    stats: JsonNetStats,
    unreported: u64,
    last_warning: Option<Instant>,
}

/// The running device: the UDP socket in the server's reactor and the servers it feeds.
pub struct JsonNetDevice {
    source: UdpSource,
    buf: Box<[u8]>,
    stream: Stream,
}

impl JsonNetDevice {
    /// Binds the configured port on `conn`'s reactor and serves `NAME` on `conn`.
    pub fn new(cfg: &JsonNet, conn: &Connection) -> Result<JsonNetDevice, Error> {
        let reactor = conn.reactor();
        let source = UdpSource::bind(cfg.port, None, reactor.as_ref())
            .map_err(|e| Error::io(format!("JsonNet {}: UDP port {}", cfg.name, cfg.port), e))?;
        Ok(JsonNetDevice {
            source,
            buf: vec![0u8; DATAGRAM_MAX + 1].into_boxed_slice(),
            stream: Stream {
                name: cfg.name.clone(),
                tracker: TrackerServer::new(&cfg.name, conn, SENSORS)?,
                button: ButtonServer::new(&cfg.name, conn, BUTTONS)?,
                analog: AnalogServer::new(&cfg.name, conn, CHANNELS)?,
                pos: [0.0; 3],
                quat: [0.0, 0.0, 0.0, 1.0],
                text: String::with_capacity(DATAGRAM_MAX * 2),
                warning: String::with_capacity(256),
                stats: JsonNetStats::default(),
                unreported: 0,
                last_warning: None,
            },
        })
    }

    /// The local UDP port (the configured one, or the one chosen for port 0).
    pub fn local_port(&self) -> u16 {
        self.source.local_port()
    }

    /// What was received so far.
    pub fn stats(&self) -> JsonNetStats {
        self.stream.stats
    }
}

impl Stream {
    fn datagram(&mut self, d: Datagram<'_>) {
        self.stats.datagrams += 1;
        if d.too_long || d.bytes.len() >= DATAGRAM_MAX {
            self.stats.too_long += 1;
            self.skipped(d.arrived.mono, "a datagram of 2000 bytes or more");
            return;
        }
        let message = match message::parse(d.bytes, &mut self.text) {
            Ok(m) => m,
            Err(why) => {
                if why == Rejected::Syntax {
                    self.stats.malformed += 1;
                } else {
                    self.stats.rejected += 1;
                }
                self.skipped(d.arrived.mono, why);
                return;
            }
        };
        self.stats.accepted += 1;
        let time = d.arrived.wall;
        match message {
            Message::Tracker { sensor, quat, pos } => {
                if let Some(q) = quat {
                    self.quat = q;
                }
                if let Some(p) = pos {
                    self.pos = p;
                }
                match usize::try_from(sensor).ok().filter(|&s| s < SENSORS) {
                    Some(s) => {
                        let _ = self.tracker.report_pose(s, time, self.pos, self.quat);
                    }
                    None => self.stats.out_of_range += 1,
                }
            }
            Message::Button { button, pressed } => {
                match usize::try_from(button).ok().filter(|&b| b < BUTTONS) {
                    Some(b) => self.button.set_button(b, pressed),
                    None => self.stats.out_of_range += 1,
                }
            }
            Message::Analog { channel, value } => {
                match usize::try_from(channel).ok().filter(|&c| c < CHANNELS) {
                    Some(c) => self.analog.set_channel(c, value),
                    None => self.stats.out_of_range += 1,
                }
            }
            Message::Text => {
                // C++ sends the text as a C string: up to a NUL, if any.
                let text = self.text.split('\0').next().unwrap_or("");
                if text.len() > TEXT_MAX {
                    self.stats.out_of_range += 1;
                } else {
                    let _ = self.tracker.send_text(TextSeverity::Normal, 0, text);
                }
            }
        }
        // As C++: the button changes (unfiltered), then the channels if any changed.
        self.button.set_timestamp(time);
        let _ = self.button.report_changes_unfiltered();
        let _ = self.analog.report_changes(Some(time));
    }

    /// Counts a skipped datagram; a warning text at most once a second says why.
    fn skipped(&mut self, now: Instant, why: impl std::fmt::Display) {
        self.unreported += 1;
        if self
            .last_warning
            .is_some_and(|t| now.saturating_duration_since(t) < Duration::from_secs(1))
        {
            return;
        }
        self.last_warning = Some(now);
        self.warning.clear();
        let _ = write!(
            self.warning,
            "{}: datagram skipped: {why} ({} skipped since the last warning)",
            self.name, self.unreported
        );
        self.unreported = 0;
        let _ = self
            .tracker
            .send_text(TextSeverity::Warning, 0, &self.warning);
    }
}

impl ServerDevice for JsonNetDevice {
    fn name(&self) -> &str {
        &self.stream.name
    }

    fn mainloop(&mut self, now: Now) {
        let stream = &mut self.stream;
        let _ = self
            .source
            .drain(&mut self.buf, now, |d| stream.datagram(d));
    }

    /// Datagrams wake the reactor; nothing is due otherwise.
    fn next_deadline(&self) -> Option<Instant> {
        None
    }
}

//! `vrpn_Tracker_Fastrak` and `vrpn_Tracker_InterSense`: the trackers whose entries continue
//! over `\\` (reset command) and `/` (station device) lines, with their wands and styluses;
//! what they serve and how they are built.

use super::FastrakProtocol;
use crate::config::fields::{baud, block_need, device_name, f64_field, need, uint_in};
use crate::config::lines::{c_tokens, is_c_space};
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, Ctx};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// Longest combined reset-command string, in bytes.
pub const MAX_RESET_COMMANDS: usize = 2048;

/// One step of the extra reset sequence of a Fastrak / InterSense entry (`\` lines).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ResetStep {
    /// `*N`: wait N seconds.
    Pause(u32),
    /// A command sent to the tracker, followed by a carriage return (not stored here).
    Command(String),
}

/// Clip values of one IS-900 wand joystick channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WandClip {
    /// Raw value mapped to -1.
    pub min: f64,
    /// Low end of the dead zone.
    pub low_zero: f64,
    /// High end of the dead zone.
    pub high_zero: f64,
    /// Raw value mapped to +1.
    pub max: f64,
}

/// A device attached to one station of a Fastrak / InterSense (`/` lines).
#[derive(Clone, Debug, PartialEq)]
pub enum StationDevice {
    /// `Wand NAME SENSOR C0MIN C0LO C0HI C0MAX C1MIN C1LO C1HI C1MAX`: IS-900 wand, an
    /// Analog (2 channels) and a Button (6) named `name`.
    Wand {
        /// Name of the wand's Analog and Button servers.
        name: String,
        /// Station (0-based).
        sensor: u32,
        /// Clip values of the joystick x and y channels.
        clip: [WandClip; 2],
    },
    /// `Stylus NAME SENSOR`: IS-900 stylus, a Button (2) named `name`.
    Stylus {
        /// Name of the stylus Button server.
        name: String,
        /// Station (0-based).
        sensor: u32,
    },
    /// `FTStylus NAME SENSOR`: genuine Fastrak stylus, a Button (1) named `name`; switches the
    /// driver into Fastrak button format.
    FtStylus {
        /// Name of the stylus Button server.
        name: String,
        /// Station (0-based).
        sensor: u32,
    },
}

impl StationDevice {
    /// The name of the servers this station device creates.
    pub fn name(&self) -> &str {
        match self {
            StationDevice::Wand { name, .. }
            | StationDevice::Stylus { name, .. }
            | StationDevice::FtStylus { name, .. } => name,
        }
    }

    /// The station it is attached to.
    pub fn sensor(&self) -> u32 {
        match self {
            StationDevice::Wand { sensor, .. }
            | StationDevice::Stylus { sensor, .. }
            | StationDevice::FtStylus { sensor, .. } => *sensor,
        }
    }
}

/// `vrpn_Tracker_Fastrak NAME PORT BAUD [IS900time|/|\]` plus optional `\` reset-command lines
/// and `/` station-device lines. Polhemus Fastrak, or an InterSense IS-600 /
/// IS-900 in Fastrak-compatible mode.
#[derive(Clone, Debug, PartialEq)]
pub struct Fastrak {
    /// Device name.
    pub name: String,
    /// Serial port, passed to the OS unchanged.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`](crate::config::BAUD_RATES).
    pub baud: u32,
    /// IS-900 hardware timestamps (an option token starting with `IS900time`).
    pub is900_timestamps: bool,
    /// Extra reset commands, in order.
    pub reset_commands: Vec<ResetStep>,
    /// Station devices (wands, styluses), in order.
    pub stations: Vec<StationDevice>,
}

impl Fastrak {
    /// Stations vrpn_server configures (hard-wired in C++); station indexes are below this.
    pub const STATIONS: u32 = 4;

    /// Whether an `FTStylus` line switched the driver into genuine-Fastrak button format.
    pub fn really_fastrak(&self) -> bool {
        self.stations
            .iter()
            .any(|s| matches!(s, StationDevice::FtStylus { .. }))
    }
}

/// Port of a [`InterSense`] tracker.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum InterSensePort {
    /// `COM1` .. `COM4`.
    Com(u8),
    /// `AUTO`: let the SDK search.
    Auto,
}

/// `vrpn_Tracker_InterSense NAME COM1..COM4|AUTO [IS900time] [ResetAtStartup] [/|\]` plus the
/// same continuation lines as [`Fastrak`] (needs InterSense's SDK). This is the
/// only IS-900-specific keyword: there is no `vrpn_Tracker_IS900` in VRPN 07.35.
#[derive(Clone, Debug, PartialEq)]
pub struct InterSense {
    /// Device name.
    pub name: String,
    /// Port.
    pub port: InterSensePort,
    /// IS-900 hardware timestamps (`IS900time`).
    pub is900_timestamps: bool,
    /// Reset the tracker when the server starts (`ResetAtStartup`).
    pub reset_at_startup: bool,
    /// Extra reset commands, in order.
    pub reset_commands: Vec<ResetStep>,
    /// Station devices (wands, styluses), in order.
    pub stations: Vec<StationDevice>,
}

impl InterSense {
    /// Stations we accept (the SDK's `ISD_MAX_STATIONS`); station indexes are below this.
    pub const STATIONS: u32 = 8;
}

// ---------------------------------------------------------------------------------------------
// Parsers
// ---------------------------------------------------------------------------------------------

/// Splits a trailing continuation character (`\` or `/`, the very last character before the
/// newline) off a line's content.
fn split_continuation(content: &str) -> (&str, Option<char>) {
    match content.chars().last() {
        Some(c @ ('\\' | '/')) => (&content[..content.len() - 1], Some(c)),
        _ => (content, None),
    }
}

/// Continuation lines after a Fastrak / InterSense first line ending in `cont`.
struct Continuations {
    reset_commands: Vec<ResetStep>,
    stations: Vec<StationDevice>,
}

fn read_continuations(
    line: &mut ConfigLine<'_, '_>,
    mut cont: Option<char>,
    stations_max: u32,
) -> Result<Continuations, ConfigError> {
    let ctx = &line.ctx().clone();
    let mut out = Continuations {
        reset_commands: Vec::new(),
        stations: Vec::new(),
    };
    let mut reset_len = 0usize;
    while cont == Some('\\') {
        let next_line = line.block_line("the reset command promised by the trailing '\\'")?;
        let (body, next) = split_continuation(next_line.content());
        reset_len += body.len() + 1;
        if reset_len > MAX_RESET_COMMANDS {
            return Err(ctx.at(next_line.number).err(
                ConfigErrorKind::BadBlockLine,
                format!("reset commands exceed {MAX_RESET_COMMANDS} characters in total"),
            ));
        }
        out.reset_commands
            .push(reset_step(&ctx.at(next_line.number), body)?);
        cont = next;
    }
    while cont == Some('/') {
        let next_line = line.block_line("the station device line promised by the trailing '/'")?;
        let (body, next) = split_continuation(next_line.content());
        let here = ctx.at(next_line.number);
        let station = station_device(&here, &c_tokens(body), stations_max)?;
        if let Some(other) = out.stations.iter().find(|s| s.sensor() == station.sensor()) {
            return Err(here.err(
                ConfigErrorKind::BadBlockLine,
                format!(
                    "station {} already has device '{}'",
                    station.sensor(),
                    other.name()
                ),
            ));
        }
        out.stations.push(station);
        cont = next;
    }
    Ok(out)
}

fn reset_step(ctx: &Ctx<'_>, body: &str) -> Result<ResetStep, ConfigError> {
    let Some(secs) = body.strip_prefix('*') else {
        return Ok(ResetStep::Command(body.to_owned()));
    };
    let secs = secs.trim_matches(is_c_space);
    uint_in(ctx, "reset pause (*N, in seconds)", secs, 0, 3600).map(ResetStep::Pause)
}

fn station_device(ctx: &Ctx<'_>, t: &[&str], stations: u32) -> Result<StationDevice, ConfigError> {
    let Some(&first) = t.first() else {
        return Err(ctx.err(
            ConfigErrorKind::BadBlockLine,
            "empty station device line; expected Wand, Stylus or FTStylus",
        ));
    };
    let max = stations - 1;
    match first {
        "Wand" => {
            block_need(
                ctx,
                first,
                t,
                11,
                "name, sensor, c0min, c0lo, c0hi, c0max, c1min, c1lo, c1hi, c1max",
            )?;
            let name = device_name(ctx, "Wand name", t[1])?;
            let sensor = uint_in(ctx, "Wand sensor", t[2], 0, max)?;
            let clip0 = wand_clip(ctx, 0, &t[3..7])?;
            let clip1 = wand_clip(ctx, 1, &t[7..11])?;
            Ok(StationDevice::Wand {
                name,
                sensor,
                clip: [clip0, clip1],
            })
        }
        "Stylus" | "FTStylus" => {
            block_need(ctx, first, t, 3, "name, sensor")?;
            let name = device_name(ctx, &format!("{first} name"), t[1])?;
            let sensor = uint_in(ctx, &format!("{first} sensor"), t[2], 0, max)?;
            Ok(if first == "Stylus" {
                StationDevice::Stylus { name, sensor }
            } else {
                StationDevice::FtStylus { name, sensor }
            })
        }
        other => Err(ctx.err(
            ConfigErrorKind::BadBlockLine,
            format!("unknown station device '{other}'; expected Wand, Stylus or FTStylus"),
        )),
    }
}

fn wand_clip(ctx: &Ctx<'_>, channel: usize, t: &[&str]) -> Result<WandClip, ConfigError> {
    let f = |i: usize, what: &str| f64_field(ctx, &format!("Wand channel {channel} {what}"), t[i]);
    let clip = WandClip {
        min: f(0, "min")?,
        low_zero: f(1, "lowzero")?,
        high_zero: f(2, "highzero")?,
        max: f(3, "max")?,
    };
    if clip.min <= clip.low_zero && clip.low_zero <= clip.high_zero && clip.high_zero <= clip.max {
        Ok(clip)
    } else {
        Err(ctx.err(
            ConfigErrorKind::OutOfRange,
            format!(
                "Wand channel {channel} clip values must satisfy min <= lowzero <= highzero <= \
                 max, found {} {} {} {}",
                t[0], t[1], t[2], t[3]
            ),
        ))
    }
}

pub(super) fn parse_fastrak(
    line: &mut ConfigLine<'_, '_>,
) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    let ctx = &line.ctx().clone();
    let rest = line.rest();
    let (head, cont) = split_continuation(rest.strip_suffix('\n').unwrap_or(rest));
    let a = c_tokens(head);
    need(ctx, &a, 3, "name, port, baud, [IS900time | / | \\]")?;
    let name = device_name(ctx, "name", a[0])?;
    let port = a[1].to_owned();
    let baud = baud(ctx, a[2])?;
    let is900_timestamps = match a.get(3) {
        None => false,
        Some(t) if t.starts_with("IS900time") => true,
        Some(&("/" | "\\")) => false,
        Some(t) => {
            return Err(ctx.err(
                ConfigErrorKind::BadValue,
                format!("the optional 4th argument must be IS900time, '/' or '\\', found '{t}'"),
            ))
        }
    };
    let more = read_continuations(line, cont, Fastrak::STATIONS)?;
    Ok(Box::new(Fastrak {
        name,
        port,
        baud,
        is900_timestamps,
        reset_commands: more.reset_commands,
        stations: more.stations,
    }))
}

pub(super) fn parse_intersense(
    line: &mut ConfigLine<'_, '_>,
) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    let ctx = &line.ctx().clone();
    let rest = line.rest();
    let (head, cont) = split_continuation(rest.strip_suffix('\n').unwrap_or(rest));
    let a = c_tokens(head);
    need(
        ctx,
        &a,
        2,
        "name, COM1..COM4 or AUTO, [IS900time] [ResetAtStartup]",
    )?;
    let name = device_name(ctx, "name", a[0])?;
    let port = match a[1] {
        "AUTO" => InterSensePort::Auto,
        "COM1" => InterSensePort::Com(1),
        "COM2" => InterSensePort::Com(2),
        "COM3" => InterSensePort::Com(3),
        "COM4" => InterSensePort::Com(4),
        other => {
            return Err(ctx.err(
                ConfigErrorKind::BadValue,
                format!("port must be COM1, COM2, COM3, COM4 or AUTO, found '{other}'"),
            ))
        }
    };
    let (mut is900_timestamps, mut reset_at_startup) = (false, false);
    for opt in a.iter().skip(2).take(3) {
        match *opt {
            "IS900time" => is900_timestamps = true,
            "ResetAtStartup" => reset_at_startup = true,
            "/" | "\\" => {}
            other => {
                return Err(ctx.err(
                    ConfigErrorKind::BadValue,
                    format!(
                        "options must be IS900time, ResetAtStartup, '/' or '\\', found '{other}'"
                    ),
                ))
            }
        }
    }
    let more = read_continuations(line, cont, InterSense::STATIONS)?;
    Ok(Box::new(InterSense {
        name,
        port,
        is900_timestamps,
        reset_at_startup,
        reset_commands: more.reset_commands,
        stations: more.stations,
    }))
}

/// Every (name, interface) pair of a tracker and its station devices.
fn served_with_stations<'a>(name: &'a str, stations: &'a [StationDevice]) -> Vec<Served<'a>> {
    let mut served = Served::all(name, &[Interface::Tracker]);
    for station in stations {
        let interfaces: &[Interface] = match station {
            StationDevice::Wand { .. } => &[Interface::Button, Interface::Analog],
            StationDevice::Stylus { .. } | StationDevice::FtStylus { .. } => &[Interface::Button],
        };
        served.extend(Served::all(station.name(), interfaces));
    }
    served
}

impl Fastrak {
    /// The driver for this entry, with its tracker and station devices served on `conn`,
    /// ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<FastrakProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            FastrakProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Fastrak {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        served_with_stations(&self.name, &self.stations)
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = FastrakProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

impl DeviceSpec for InterSense {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        served_with_stations(&self.name, &self.stations)
    }

    /// Refused: C++ serves this keyword through InterSense's own library.
    fn build(&self, _cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Err(Error::Unsupported(
            "vrpn_Tracker_InterSense needs InterSense's own library, which this server does \
             not use; an IS-600 or IS-900 in Fastrak mode is served by a vrpn_Tracker_Fastrak \
             line (with IS900time for its clock, Wand and Stylus lines for its buttons and \
             analogs)",
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ctx() -> Ctx<'static> {
        Ctx::new("t.cfg", 7, "kw")
    }

    #[test]
    fn continuation_split() {
        assert_eq!(split_continuation("a b \\"), ("a b ", Some('\\')));
        assert_eq!(split_continuation("a b/"), ("a b", Some('/')));
        assert_eq!(split_continuation("a b /\r"), ("a b /\r", None));
        assert_eq!(split_continuation(""), ("", None));
    }

    #[test]
    fn reset_steps() {
        let c = ctx();
        assert_eq!(reset_step(&c, "*5"), Ok(ResetStep::Pause(5)));
        assert_eq!(reset_step(&c, "MCe"), Ok(ResetStep::Command("MCe".into())));
        assert!(reset_step(&c, "*x").is_err());
    }
}

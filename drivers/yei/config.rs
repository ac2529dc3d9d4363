//! The `vrpn_YEI_3Space_Sensor` and `vrpn_YEI_3Space_Sensor_Wireless` entries: their fields,
//! their continuation lines, what they serve and how they are built.

use super::wired::WiredProtocol;
use super::wireless::WirelessProtocol;
use crate::config::continuation::{head, split_continuation};
use crate::config::fields::{baud, device_name, f32_field, f64_field, need, uint_in};
use crate::config::lines::c_tokens;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, Ctx};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// The wireless keyword (also the first word of each further unit's line).
pub const WIRELESS_KEYWORD: &str = "vrpn_YEI_3Space_Sensor_Wireless";

/// Highest logical id a dongle has.
pub const MAX_LOGICAL_ID: u32 = 14;

/// What is said about one unit (wired, or one wireless unit on a dongle).
#[derive(Clone, Debug, PartialEq)]
pub struct Unit {
    /// Device name: a Tracker (2 sensors), an Analog (11 channels) and a Button (8).
    pub name: String,
    /// Logical id on the dongle (wireless units only).
    pub logical_id: u8,
    /// Calibrate the gyroscopes at start-up (the unit must be still).
    pub calibrate_gyros: bool,
    /// Tare at start-up (the unit must face the right way).
    pub tare: bool,
    /// Records per second asked for (0 or less: as fast as the unit can).
    pub frames_per_second: f64,
    /// LED colour, red, green, blue, each 0–1.
    pub led_color: [f32; 3],
    /// LED mode: 0 standard, 1 static.
    pub led_mode: u8,
    /// ASCII commands sent at every reset (the `\` lines), without their `:`.
    pub reset_commands: Vec<String>,
}

/// `vrpn_YEI_3Space_Sensor NAME PORT BAUD CALIBRATE TARE FPS RED GREEN BLUE LED_MODE [\]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Yei {
    /// The unit.
    pub unit: Unit,
    /// Serial port.
    pub port: String,
    /// Baud rate.
    pub baud: u32,
}

/// `vrpn_YEI_3Space_Sensor_Wireless NAME ID PORT BAUD CALIBRATE TARE FPS RED GREEN BLUE
/// LED_MODE [\ | /]` and, after a `/`, a further unit on the same dongle per line.
#[derive(Clone, Debug, PartialEq)]
pub struct YeiWireless {
    /// The dongle's serial port.
    pub port: String,
    /// Baud rate.
    pub baud: u32,
    /// The units, in the order of their lines.
    pub units: Vec<Unit>,
}

const FIRST_USAGE: &str = "name, logical_id, port, baud, calibrate_gyros, tare, \
                           frames_per_second, red, green, blue, LED_mode";
const MORE_USAGE: &str = "name, logical_id, calibrate_gyros, tare, frames_per_second, red, \
                          green, blue, LED_mode";

const WIRED_USAGE: &str = "name, port, baud, calibrate_gyros, tare, frames_per_second, red, \
                           green, blue, LED_mode";
/// The six unit fields after the port (or the logical id): calibrate, tare, rate, colour,
/// mode.
fn unit_fields(ctx: &Ctx<'_>, name: String, id: u8, t: &[&str]) -> Result<Unit, ConfigError> {
    let flag = |field: &str, tok: &str| uint_in(ctx, field, tok, 0, 1).map(|v| v == 1);
    let color = |field: &str, tok: &str| -> Result<f32, ConfigError> {
        let v = f32_field(ctx, field, tok)?;
        if (0.0..=1.0).contains(&v) {
            Ok(v)
        } else {
            Err(ctx.err(
                ConfigErrorKind::OutOfRange,
                format!("{field} must be between 0 and 1, found {tok}"),
            ))
        }
    };
    Ok(Unit {
        name,
        logical_id: id,
        calibrate_gyros: flag("calibrate_gyros_on_startup (0 or 1)", t[0])?,
        tare: flag("tare_on_startup (0 or 1)", t[1])?,
        frames_per_second: f64_field(ctx, "frames_per_second", t[2])?,
        led_color: [
            color("red_LED_color", t[3])?,
            color("green_LED_color", t[4])?,
            color("blue_LED_color", t[5])?,
        ],
        led_mode: uint_in(ctx, "LED_mode (0 standard, 1 static)", t[6], 0, 1)? as u8,
        reset_commands: Vec::new(),
    })
}

fn no_extra(ctx: &Ctx<'_>, t: &[&str], n: usize, slash: bool) -> Result<(), ConfigError> {
    match t.get(n) {
        None => Ok(()),
        Some(extra) => Err(ctx.err(
            ConfigErrorKind::BadValue,
            format!(
                "unexpected argument '{extra}' after LED_mode; only a trailing '\\' (reset \
                 commands follow){} may end the line",
                if slash {
                    " or '/' (another unit on the dongle follows)"
                } else {
                    ""
                }
            ),
        )),
    }
}

/// Reads the reset command lines promised by a trailing `\`: the first word of each line (a
/// command without its `:`, no spaces, e.g. `238,1,1,0`). Returns them and the continuation
/// character the last line ends in.
fn reset_commands(
    line: &mut ConfigLine<'_, '_>,
    mut cont: Option<char>,
) -> Result<(Vec<String>, Option<char>), ConfigError> {
    let ctx = line.ctx().clone();
    let mut out = Vec::new();
    while cont == Some('\\') {
        let next = line.block_line("the reset command promised by the trailing '\\'")?;
        let (body, c) = split_continuation(next.content());
        let here = ctx.at(next.number);
        match c_tokens(body)[..] {
            [] => {
                return Err(here.err(
                    ConfigErrorKind::BadBlockLine,
                    "empty line where a reset command (like 238,1,1,0) was promised",
                ))
            }
            [cmd] if cmd.len() <= 200 && cmd.bytes().all(|b| b.is_ascii_graphic()) => {
                out.push(cmd.to_owned());
            }
            [cmd] => {
                return Err(here.err(
                    ConfigErrorKind::BadBlockLine,
                    format!(
                        "reset command '{cmd}' must be printable ASCII of at most 200 characters"
                    ),
                ))
            }
            [_, extra, ..] => {
                return Err(here.err(
                    ConfigErrorKind::BadBlockLine,
                    format!(
                        "a reset command line holds one command without spaces; found \
                         '{extra}' after it"
                    ),
                ))
            }
        }
        cont = c;
    }
    Ok((out, cont))
}

/// Parses a `vrpn_YEI_3Space_Sensor` entry.
fn parse_wired(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    let ctx = line.ctx().clone();
    let (a, cont) = head(line);
    need(&ctx, &a, 10, WIRED_USAGE)?;
    no_extra(&ctx, &a, 10, false)?;
    let name = device_name(&ctx, "name", a[0])?;
    let port = a[1].to_owned();
    let baud = baud(&ctx, a[2])?;
    let mut unit = unit_fields(&ctx, name, 0, &a[3..])?;
    let (commands, cont) = reset_commands(line, cont)?;
    unit.reset_commands = commands;
    if cont == Some('/') {
        return Err(ctx.err(
            ConfigErrorKind::BadValue,
            format!("a trailing '/' (another unit on the dongle) is for {WIRELESS_KEYWORD}"),
        ));
    }
    Ok(Box::new(Yei { unit, port, baud }))
}

/// Parses a `vrpn_YEI_3Space_Sensor_Wireless` entry and the further units after a `/`.
fn parse_wireless(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    let ctx = line.ctx().clone();
    let (a, cont) = head(line);
    need(&ctx, &a, 11, FIRST_USAGE)?;
    no_extra(&ctx, &a, 11, true)?;
    let name = device_name(&ctx, "name", a[0])?;
    let id = uint_in(
        &ctx,
        "logical_id_on_wireless (0-14)",
        a[1],
        0,
        MAX_LOGICAL_ID,
    )? as u8;
    let port = a[2].to_owned();
    let baud = baud(&ctx, a[3])?;
    let mut first = unit_fields(&ctx, name, id, &a[4..])?;
    let (commands, mut cont) = reset_commands(line, cont)?;
    first.reset_commands = commands;
    let mut units = vec![first];
    while cont == Some('/') {
        let next = line.block_line("the further wireless unit promised by the trailing '/'")?;
        let here = ctx.at(next.number);
        let (body, c) = split_continuation(next.content());
        let t = c_tokens(body);
        if t.first() != Some(&WIRELESS_KEYWORD) {
            return Err(here.err(
                ConfigErrorKind::BadBlockLine,
                format!(
                    "after a trailing '/', a line '{WIRELESS_KEYWORD} {MORE_USAGE}' (no port: \
                     the dongle's) was promised; found '{}'",
                    t.first().unwrap_or(&"")
                ),
            ));
        }
        let t = &t[1..];
        need(&here, t, 9, MORE_USAGE)?;
        no_extra(&here, t, 9, true)?;
        let name = device_name(&here, "name", t[0])?;
        let id = uint_in(
            &here,
            "logical_id_on_wireless (0-14)",
            t[1],
            0,
            MAX_LOGICAL_ID,
        )? as u8;
        let mut unit = unit_fields(&here, name, id, &t[2..])?;
        if let Some(o) = units
            .iter()
            .find(|o| o.logical_id == id || o.name == unit.name)
        {
            return Err(here.err(
                ConfigErrorKind::BadBlockLine,
                format!(
                    "unit '{}' (logical id {id}) clashes with unit '{}' (logical id {}) on \
                     the same dongle: names and logical ids must differ",
                    unit.name, o.name, o.logical_id
                ),
            ));
        }
        let (commands, after) = reset_commands(line, c)?;
        unit.reset_commands = commands;
        units.push(unit);
        cont = after;
    }
    Ok(Box::new(YeiWireless { port, baud, units }))
}

/// Parses either keyword's entry.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    if line.keyword() == WIRELESS_KEYWORD {
        parse_wireless(line)
    } else {
        parse_wired(line)
    }
}

const SERVED: [Interface; 3] = [Interface::Tracker, Interface::Analog, Interface::Button];

impl Yei {
    /// The driver for this entry, with its servers on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<WiredProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.unit.name,
            WiredProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Yei {
    fn name(&self) -> &str {
        &self.unit.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.unit.name, &SERVED)
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = WiredProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.unit.name, &self.port, protocol, cx)])
    }
}

impl YeiWireless {
    /// The driver for this entry (every unit on the dongle), with its servers on `conn`.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<WirelessProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.units[0].name,
            WirelessProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for YeiWireless {
    fn name(&self) -> &str {
        &self.units[0].name
    }

    fn served(&self) -> Vec<Served<'_>> {
        self.units
            .iter()
            .flat_map(|u| Served::all(&u.name, &SERVED))
            .collect()
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = WirelessProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.units[0].name, &self.port, protocol, cx)])
    }
}

//! Devices configured on one line: the test and example devices and the serial trackers and
//! input devices, their typed configurations and their parsers.

use super::entry::DeviceConfig;
use super::error::{ConfigError, ConfigErrorKind, Ctx};
use super::fields::{any_int, baud, device_name, f32_field, need, period, rate, uint_in};
use super::lines::from_token;
use super::{MAX_BUTTONS, MAX_CHANNELS, MAX_DIALS, MAX_FLOCK_SENSORS, MAX_TRACKER_SENSORS};

/// `vrpn_Tracker_NULL NAME SENSORS RATE`: identity poses at a fixed rate.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackerNull {
    /// Device name.
    pub name: String,
    /// Number of sensors, 1..=[`MAX_TRACKER_SENSORS`].
    pub sensors: u32,
    /// Reports per second, > 0.
    pub rate: f32,
}

/// `vrpn_Tracker_Spin NAME SENSORS RATE AXIS_X AXIS_Y AXIS_Z SPIN_HZ`: a tracker spinning
/// about an axis.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackerSpin {
    /// Device name.
    pub name: String,
    /// Number of sensors, 1..=[`MAX_TRACKER_SENSORS`].
    pub sensors: u32,
    /// Reports per second, > 0.
    pub rate: f32,
    /// Rotation axis (need not be normalised; all zero gives the identity).
    pub axis: [f32; 3],
    /// Revolutions per second (negative spins the other way).
    pub spin_hz: f32,
}

/// `vrpn_Button_Example NAME BUTTONS RATE`: buttons that all flip together.
#[derive(Clone, Debug, PartialEq)]
pub struct ButtonExample {
    /// Device name.
    pub name: String,
    /// Number of buttons, 1..=[`MAX_BUTTONS`] (C++ clamps larger values; we reject them).
    pub buttons: u32,
    /// Transitions per second, > 0.
    pub rate: f32,
}

/// `vrpn_Dial_Example NAME DIALS SPIN_RATE UPDATE_RATE`: dials turning at a constant rate.
#[derive(Clone, Debug, PartialEq)]
pub struct DialExample {
    /// Device name.
    pub name: String,
    /// Number of dials, 1..=[`MAX_DIALS`].
    pub dials: u32,
    /// Revolutions per second of every dial (any sign).
    pub spin_rate: f32,
    /// Reports per second, > 0.
    pub update_rate: f32,
}

/// **Our extension** (not in C++ VRPN): `vrpn_Analog_Example NAME CHANNELS RATE`, an analog
/// server whose channels change over time, reporting `RATE` times per second.
#[derive(Clone, Debug, PartialEq)]
pub struct AnalogExample {
    /// Device name.
    pub name: String,
    /// Number of channels, 1..=[`MAX_CHANNELS`].
    pub channels: u32,
    /// Reports per second, > 0.
    pub rate: f32,
}

/// **Our extension** (not in C++ VRPN): `vrpn_Text_Example NAME PERIOD_SECONDS MESSAGE...`,
/// a text sender that sends `MESSAGE` every `PERIOD_SECONDS`.
#[derive(Clone, Debug, PartialEq)]
pub struct TextExample {
    /// Device name.
    pub name: String,
    /// Seconds between messages, > 0.
    pub period: f32,
    /// The text: everything after the period, with surrounding blanks removed and inner
    /// spacing kept.
    pub message: String,
}

/// `vrpn_Joylin NAME DEVICE`: a Linux joystick (`/dev/input/jsN`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Joylin {
    /// Device name (Analog and Button under it).
    pub name: String,
    /// Joystick device path.
    pub device: String,
}

/// Hemisphere a Flock of Birds works in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Hemisphere {
    /// `+x`.
    PosX,
    /// `-x`.
    NegX,
    /// `+y`.
    PosY,
    /// `-y`.
    NegY,
    /// `+z` (the default).
    PosZ,
    /// `-z`.
    NegZ,
}

impl Hemisphere {
    /// Parses `+x -x +y -y +z -z` (axis letter in either case).
    pub fn parse(tok: &str) -> Option<Hemisphere> {
        match tok.to_ascii_lowercase().as_str() {
            "+x" => Some(Hemisphere::PosX),
            "-x" => Some(Hemisphere::NegX),
            "+y" => Some(Hemisphere::PosY),
            "-y" => Some(Hemisphere::NegY),
            "+z" => Some(Hemisphere::PosZ),
            "-z" => Some(Hemisphere::NegZ),
            _ => None,
        }
    }
}

/// `vrpn_Tracker_Flock NAME SENSORS PORT BAUD INVERT [USE_ERT] [HEMISPHERE]`: Ascension Flock
/// of Birds on one serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Flock {
    /// Device name.
    pub name: String,
    /// Number of receivers, 1..=[`MAX_FLOCK_SENSORS`].
    pub sensors: u32,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`](super::BAUD_RATES).
    pub baud: u32,
    /// Report the inverse quaternion (non-zero INVERT).
    pub invert_quaternion: bool,
    /// Extended-range transmitter present (default yes; a token starting with `n`/`N` = no).
    pub use_ert: bool,
    /// Hemisphere (default `+z`).
    pub hemisphere: Hemisphere,
}

/// `vrpn_Tracker_Flock_Parallel NAME SENSORS MASTER_PORT BAUD INVERT PORT_1 .. PORT_N`: one
/// serial line per receiver.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FlockParallel {
    /// Device name.
    pub name: String,
    /// Number of receivers N, 1..=[`MAX_FLOCK_SENSORS`] (C++ 07.35 does not check; later
    /// versions reject more than 13, as we do).
    pub sensors: u32,
    /// Master's serial port.
    pub master_port: String,
    /// Baud rate of all ports, one of [`BAUD_RATES`](super::BAUD_RATES).
    pub baud: u32,
    /// The INVERT flag; C++ applies it only to the master, so it changes nothing reported.
    pub invert_quaternion: bool,
    /// One serial port per receiver (N of them).
    pub slave_ports: Vec<String>,
}

/// `vrpn_Magellan NAME PORT BAUD [altreset]`: Magellan / SpaceMouse on a serial port.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Magellan {
    /// Device name (Analog with 6 channels, Button with 9).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`](super::BAUD_RATES) (the device documents 9600).
    pub baud: u32,
    /// Use the alternate reset string of older units (`altreset`).
    pub alt_reset: bool,
}

/// `vrpn_CerealBox NAME PORT BAUD BUTTONS ANALOGS ENCODERS`: BG Systems CerealBox.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CerealBox {
    /// Device name (Button, Analog and Dial under it).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`](super::BAUD_RATES) (the device documents 19200).
    pub baud: u32,
    /// Buttons, 0..=24 (C++ clamps larger values; we reject them).
    pub buttons: u32,
    /// Analog channels, 0..=8.
    pub analogs: u32,
    /// Encoders (dials), 0..=8.
    pub encoders: u32,
}

impl CerealBox {
    /// Most buttons.
    pub const MAX_BUTTONS: u32 = 24;
    /// Most analogs.
    pub const MAX_ANALOGS: u32 = 8;
    /// Most encoders.
    pub const MAX_ENCODERS: u32 = 8;
}

/// `vrpn_Tracker_Dyna NAME SENSORS PORT BAUD`: Origin Instruments DynaSight (note: sensor
/// count before the port).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Dyna {
    /// Device name.
    pub name: String,
    /// Sensor count, 1..=[`MAX_FLOCK_SENSORS`] (only sensor 0 is ever reported).
    pub sensors: u32,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`](super::BAUD_RATES).
    pub baud: u32,
}

// ---------------------------------------------------------------------------------------------
// Parsers
// ---------------------------------------------------------------------------------------------

pub(super) fn parse_tracker_null(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 3, "name, sensors, rate")?;
    Ok(DeviceConfig::TrackerNull(TrackerNull {
        name: device_name(ctx, "name", a[0])?,
        sensors: uint_in(ctx, "sensors", a[1], 1, MAX_TRACKER_SENSORS)?,
        rate: rate(ctx, "rate", a[2])?,
    }))
}

pub(super) fn parse_tracker_spin(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(
        ctx,
        a,
        7,
        "name, sensors, rate, axis_x, axis_y, axis_z, spin_hz",
    )?;
    Ok(DeviceConfig::TrackerSpin(TrackerSpin {
        name: device_name(ctx, "name", a[0])?,
        sensors: uint_in(ctx, "sensors", a[1], 1, MAX_TRACKER_SENSORS)?,
        rate: rate(ctx, "rate", a[2])?,
        axis: [
            f32_field(ctx, "axis_x", a[3])?,
            f32_field(ctx, "axis_y", a[4])?,
            f32_field(ctx, "axis_z", a[5])?,
        ],
        spin_hz: f32_field(ctx, "spin_hz", a[6])?,
    }))
}

pub(super) fn parse_button_example(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 3, "name, buttons, rate")?;
    Ok(DeviceConfig::ButtonExample(ButtonExample {
        name: device_name(ctx, "name", a[0])?,
        buttons: uint_in(ctx, "buttons", a[1], 1, MAX_BUTTONS)?,
        rate: rate(ctx, "rate", a[2])?,
    }))
}

pub(super) fn parse_dial_example(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 4, "name, dials, spin_rate, update_rate")?;
    Ok(DeviceConfig::DialExample(DialExample {
        name: device_name(ctx, "name", a[0])?,
        dials: uint_in(ctx, "dials", a[1], 1, MAX_DIALS)?,
        spin_rate: f32_field(ctx, "spin_rate", a[2])?,
        update_rate: rate(ctx, "update_rate", a[3])?,
    }))
}

pub(super) fn parse_analog_example(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 3, "name, channels, rate")?;
    Ok(DeviceConfig::AnalogExample(AnalogExample {
        name: device_name(ctx, "name", a[0])?,
        channels: uint_in(ctx, "channels", a[1], 1, MAX_CHANNELS)?,
        rate: rate(ctx, "rate", a[2])?,
    }))
}

pub(super) fn parse_text_example(
    ctx: &Ctx<'_>,
    a: &[&str],
    rest: &str,
) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 3, "name, period_seconds, message")?;
    Ok(DeviceConfig::TextExample(TextExample {
        name: device_name(ctx, "name", a[0])?,
        period: period(ctx, "period_seconds", a[1])?,
        message: from_token(rest, 2).to_owned(),
    }))
}

pub(super) fn parse_joylin(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 2, "name, device")?;
    Ok(DeviceConfig::Joylin(Joylin {
        name: device_name(ctx, "name", a[0])?,
        device: a[1].to_owned(),
    }))
}

pub(super) fn parse_flock(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(
        ctx,
        a,
        5,
        "name, sensors, port, baud, invert_quaternion, [useERT], [hemisphere]",
    )?;
    let use_ert = a.get(5).map_or(true, |t| !t.starts_with(['n', 'N']));
    let hemisphere = match a.get(6) {
        None => Hemisphere::PosZ,
        Some(t) => Hemisphere::parse(t).ok_or_else(|| {
            ctx.err(
                ConfigErrorKind::BadValue,
                format!("hemisphere must be one of +x -x +y -y +z -z, found '{t}'"),
            )
        })?,
    };
    Ok(DeviceConfig::Flock(Flock {
        name: device_name(ctx, "name", a[0])?,
        sensors: uint_in(ctx, "sensors", a[1], 1, MAX_FLOCK_SENSORS)?,
        port: a[2].to_owned(),
        baud: baud(ctx, a[3])?,
        invert_quaternion: any_int(ctx, "invert_quaternion", a[4])? != 0,
        use_ert,
        hemisphere,
    }))
}

pub(super) fn parse_flock_parallel(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    const USAGE: &str = "name, sensors, master_port, baud, invert_quaternion, then one port \
                         per sensor";
    need(ctx, a, 5, USAGE)?;
    let sensors = uint_in(ctx, "sensors", a[1], 1, MAX_FLOCK_SENSORS)?;
    let ports = &a[5..];
    let wanted = sensors as usize;
    if ports.len() < wanted {
        return Err(ctx.err(
            ConfigErrorKind::MissingArguments,
            format!(
                "expected {wanted} slave port name(s) after invert_quaternion (one per \
                 sensor), found {}",
                ports.len()
            ),
        ));
    }
    Ok(DeviceConfig::FlockParallel(FlockParallel {
        name: device_name(ctx, "name", a[0])?,
        sensors,
        master_port: a[2].to_owned(),
        baud: baud(ctx, a[3])?,
        invert_quaternion: any_int(ctx, "invert_quaternion", a[4])? != 0,
        slave_ports: ports[..wanted].iter().map(|p| (*p).to_owned()).collect(),
    }))
}

pub(super) fn parse_magellan(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 3, "name, port, baud, [altreset]")?;
    let alt_reset = match a.get(3) {
        None => false,
        Some(&"altreset") => true,
        Some(t) => {
            return Err(ctx.err(
                ConfigErrorKind::BadValue,
                format!("the optional 4th argument must be 'altreset', found '{t}'"),
            ))
        }
    };
    Ok(DeviceConfig::Magellan(Magellan {
        name: device_name(ctx, "name", a[0])?,
        port: a[1].to_owned(),
        baud: baud(ctx, a[2])?,
        alt_reset,
    }))
}

pub(super) fn parse_cerealbox(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 6, "name, port, baud, buttons, analogs, encoders")?;
    Ok(DeviceConfig::CerealBox(CerealBox {
        name: device_name(ctx, "name", a[0])?,
        port: a[1].to_owned(),
        baud: baud(ctx, a[2])?,
        buttons: uint_in(ctx, "buttons", a[3], 0, CerealBox::MAX_BUTTONS)?,
        analogs: uint_in(ctx, "analogs", a[4], 0, CerealBox::MAX_ANALOGS)?,
        encoders: uint_in(ctx, "encoders", a[5], 0, CerealBox::MAX_ENCODERS)?,
    }))
}

pub(super) fn parse_dyna(ctx: &Ctx<'_>, a: &[&str]) -> Result<DeviceConfig, ConfigError> {
    need(ctx, a, 4, "name, sensors, port, baud")?;
    Ok(DeviceConfig::Dyna(Dyna {
        name: device_name(ctx, "name", a[0])?,
        sensors: uint_in(ctx, "sensors", a[1], 1, MAX_FLOCK_SENSORS)?,
        port: a[2].to_owned(),
        baud: baud(ctx, a[3])?,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hemispheres() {
        assert_eq!(Hemisphere::parse("-X"), Some(Hemisphere::NegX));
        assert_eq!(Hemisphere::parse("z"), None);
    }
}

//! The `vrpn_Tracker_3Space` and `vrpn_Tracker_Isotrak` lines: their fields, their parsers,
//! what they serve and how they are built.

use super::record::Model;
use super::ThreeSpaceProtocol;
use crate::config::continuation::{device_lines, head, reset_steps, ResetStep};
use crate::config::fields::{baud, block_need, device_name, need, uint_in};
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, Ctx};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// A stylus switch on one ISOTRAK station (`Stylus NAME SENSOR`): a Button with one button.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stylus {
    /// Name of the Button server.
    pub name: String,
    /// Station, 0-based (VRPN sensor).
    pub sensor: u32,
}

/// `vrpn_Tracker_3Space NAME PORT BAUD`, or `vrpn_Tracker_Isotrak NAME PORT BAUD` with its
/// optional `\` reset-command lines and `/` stylus lines.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ThreeSpace {
    /// Which tracker.
    pub model: Model,
    /// Device name.
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`](crate::config::BAUD_RATES).
    pub baud: u32,
    /// Extra reset commands (ISOTRAK only), in order.
    pub reset_commands: Vec<ResetStep>,
    /// Stylus switches (ISOTRAK only).
    pub styluses: Vec<Stylus>,
}

/// Parses a `vrpn_Tracker_3Space` line.
pub(super) fn parse_3space(
    line: &mut ConfigLine<'_, '_>,
) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, port, baud")?;
    Ok(Box::new(ThreeSpace {
        model: Model::ThreeSpace,
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
        reset_commands: Vec::new(),
        styluses: Vec::new(),
    }))
}

/// Parses a `vrpn_Tracker_Isotrak` entry and its continuation lines.
pub(super) fn parse_isotrak(
    line: &mut ConfigLine<'_, '_>,
) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    let ctx = line.ctx().clone();
    let (a, cont) = head(line);
    need(&ctx, &a, 3, "name, port, baud, [\\ | /]")?;
    if let Some(extra) = a.get(3) {
        return Err(ctx.err(
            ConfigErrorKind::BadValue,
            format!(
                "unexpected argument '{extra}' after the baud rate; only a trailing '\\' \
                 (reset commands follow) or '/' (Stylus lines follow) may end the line"
            ),
        ));
    }
    let name = device_name(&ctx, "name", a[0])?;
    let port = a[1].to_owned();
    let baud = baud(&ctx, a[2])?;
    let (reset_commands, cont) = reset_steps(line, cont)?;
    let mut styluses: Vec<Stylus> = Vec::new();
    for s in device_lines(line, cont, "Stylus", stylus)? {
        if styluses.iter().any(|o| o.sensor == s.sensor) {
            return Err(ctx.err(
                ConfigErrorKind::BadBlockLine,
                format!("sensor {} has two Stylus lines", s.sensor),
            ));
        }
        styluses.push(s);
    }
    Ok(Box::new(ThreeSpace {
        model: Model::Isotrak,
        name,
        port,
        baud,
        reset_commands,
        styluses,
    }))
}

fn stylus(ctx: &Ctx<'_>, t: &[&str]) -> Result<Stylus, ConfigError> {
    match t.first() {
        Some(&"Stylus") => {}
        Some(other) => {
            return Err(ctx.err(
                ConfigErrorKind::BadBlockLine,
                format!("unknown device '{other}' on an Isotrak; expected Stylus NAME SENSOR"),
            ))
        }
        None => {
            return Err(ctx.err(
                ConfigErrorKind::BadBlockLine,
                "empty line where a Stylus NAME SENSOR line was promised",
            ))
        }
    }
    block_need(ctx, "Stylus", t, 3, "name, sensor")?;
    let max = Model::Isotrak.stations() as u32 - 1;
    Ok(Stylus {
        name: device_name(ctx, "Stylus name", t[1])?,
        sensor: uint_in(ctx, "Stylus sensor", t[2], 0, max)?,
    })
}

impl ThreeSpace {
    /// The driver for this entry, with its servers on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<ThreeSpaceProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            ThreeSpaceProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for ThreeSpace {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        let mut s = Served::all(&self.name, &[Interface::Tracker]);
        for st in &self.styluses {
            s.push(Served {
                name: &st.name,
                interface: Interface::Button,
            });
        }
        s
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = ThreeSpaceProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

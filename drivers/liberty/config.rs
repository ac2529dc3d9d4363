//! The `vrpn_Tracker_Liberty` line: its fields, its parser, what it serves, how it is built.

use super::record::STATIONS;
use super::reset::{DEFAULT_WHOAMI_LEN, MAX_WHOAMI_LEN};
use super::LibertyProtocol;
use crate::config::continuation::{device_lines, head, reset_steps, ResetStep};
use crate::config::fields::{baud, block_need, device_name, need, uint_in};
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, Ctx};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// A stylus on one station (`Stylus NAME SENSOR`): a Button with two buttons, the first the
/// stylus switch (as C++ VRPN makes it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stylus {
    /// Name of the Button server.
    pub name: String,
    /// Station, 0-based (VRPN sensor).
    pub sensor: u32,
}

/// `vrpn_Tracker_Liberty NAME PORT BAUD [WHOAMI_LEN]` with its optional `\` reset-command
/// lines and `/` stylus lines: a Polhemus Liberty or Patriot on a serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Liberty {
    /// Device name.
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate.
    pub baud: u32,
    /// Bytes of the tracker's WhoAmI answer (195 unless given).
    pub whoami_len: usize,
    /// Extra reset commands, in order.
    pub reset_commands: Vec<ResetStep>,
    /// Styluses.
    pub styluses: Vec<Stylus>,
}

/// Parses a `vrpn_Tracker_Liberty` entry and its continuation lines.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    let ctx = line.ctx().clone();
    let (a, cont) = head(line);
    need(&ctx, &a, 3, "name, port, baud, [whoami_length], [\\ | /]")?;
    let name = device_name(&ctx, "name", a[0])?;
    let port = a[1].to_owned();
    let baud = baud(&ctx, a[2])?;
    let whoami_len = match a.get(3) {
        None => DEFAULT_WHOAMI_LEN,
        Some(t) => uint_in(&ctx, "whoami length", t, 1, MAX_WHOAMI_LEN as u32)? as usize,
    };
    if let Some(extra) = a.get(4) {
        return Err(ctx.err(
            ConfigErrorKind::BadValue,
            format!(
                "unexpected argument '{extra}'; only a trailing '\\' (reset commands follow) or \
                 '/' (Stylus lines follow) may end the line"
            ),
        ));
    }
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
    Ok(Box::new(Liberty {
        name,
        port,
        baud,
        whoami_len,
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
                format!("unknown device '{other}' on a Liberty; expected Stylus NAME SENSOR"),
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
    Ok(Stylus {
        name: device_name(ctx, "Stylus name", t[1])?,
        sensor: uint_in(ctx, "Stylus sensor", t[2], 0, STATIONS as u32 - 1)?,
    })
}

impl Liberty {
    /// The driver for this entry, with its servers on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<LibertyProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            LibertyProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Liberty {
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
        let protocol = LibertyProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

//! The `vrpn_GlobalHapticsOrb` line: its fields, its parser, what it serves, how it is built.

use super::OrbProtocol;
use crate::config::fields::{baud, device_name, need};
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_GlobalHapticsOrb NAME PORT BAUD`: a Global Haptics Orb on a serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Orb {
    /// Device name (a Button, an Analog and a Dial).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate (19200).
    pub baud: u32,
}

/// Parses a `vrpn_GlobalHapticsOrb` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    let ctx = line.ctx().clone();
    let a = line.args().to_vec();
    need(&ctx, &a, 3, "name, port, baud")?;
    if let Some(extra) = a.get(3) {
        return Err(ctx.err(
            ConfigErrorKind::BadValue,
            format!("unexpected argument '{extra}' after the baud rate"),
        ));
    }
    Ok(Box::new(Orb {
        name: device_name(&ctx, "name", a[0])?,
        port: a[1].to_owned(),
        baud: baud(&ctx, a[2])?,
    }))
}

impl Orb {
    /// The driver for this entry, with its servers on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<OrbProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            OrbProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Orb {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(
            &self.name,
            &[Interface::Button, Interface::Analog, Interface::Dial],
        )
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = OrbProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

//! The `vrpn_Tracker_Crossbow` line: its fields, its parser, what it serves, how it is built.

use super::CrossbowProtocol;
use crate::config::fields::{baud, device_name, need, positive};
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_Tracker_Crossbow NAME PORT BAUD [G_RANGE [ANGULAR_RANGE]]`: a Crossbow RGA300CA
/// (or a DMU of the same protocol) on a serial line.
#[derive(Clone, Debug, PartialEq)]
pub struct Crossbow {
    /// Device name.
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate.
    pub baud: u32,
    /// Linear acceleration sensitivity, g (2.0 unless given).
    pub g_range: f32,
    /// Angular rate sensitivity, degrees per second (100 unless given).
    pub ar_range: f32,
}

/// Parses a `vrpn_Tracker_Crossbow` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    let ctx = line.ctx().clone();
    let a = line.args().to_vec();
    need(
        &ctx,
        &a,
        3,
        "name, port, baud, [linear_acceleration_sensitivity], [angular_rate_sensitivity]",
    )?;
    if let Some(extra) = a.get(5) {
        return Err(ctx.err(
            ConfigErrorKind::BadValue,
            format!("unexpected argument '{extra}' after the angular rate sensitivity"),
        ));
    }
    Ok(Box::new(Crossbow {
        name: device_name(&ctx, "name", a[0])?,
        port: a[1].to_owned(),
        baud: baud(&ctx, a[2])?,
        g_range: match a.get(3) {
            Some(t) => positive(&ctx, "linear acceleration sensitivity", t)?,
            None => 2.0,
        },
        ar_range: match a.get(4) {
            Some(t) => positive(&ctx, "angular rate sensitivity", t)?,
            None => 100.0,
        },
    }))
}

impl Crossbow {
    /// The driver for this entry, with its server on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<CrossbowProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            CrossbowProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Crossbow {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = CrossbowProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

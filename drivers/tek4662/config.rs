//! The `vrpn_Tek4662` line: its fields, its parser, what it serves and how it is built.

use super::Tek4662Protocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_Tek4662 NAME PORT BAUD`: a Tektronix 4662 plotter on a serial line (8N1).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Tek4662 {
    /// Device name (a Poser and a Tracker).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate (the plotter's usual 1200).
    pub baud: u32,
}

/// Parses a `vrpn_Tek4662` line (words after the baud rate are ignored, as C++ ignores
/// them).
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, port, baud")?;
    Ok(Box::new(Tek4662 {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
    }))
}

impl Tek4662 {
    /// The driver for this entry, with its Poser and Tracker served on `conn`.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<Tek4662Protocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            Tek4662Protocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Tek4662 {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Poser, Interface::Tracker])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = Tek4662Protocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

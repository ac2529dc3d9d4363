//! The `vrpn_Tng3` line: its fields, its parser, what it serves and how it is built.

use super::Tng3Protocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// Most buttons and analogs a TNG-3 has.
pub const MAX_INPUTS: u32 = 8;

/// `vrpn_Tng3 NAME PORT BUTTONS ANALOGS`: a TNG-3 at 19200 baud.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Tng3 {
    /// Device name (Analog and Button).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Digital inputs read as buttons (0-8).
    pub buttons: u32,
    /// Analog inputs read (0-8).
    pub analogs: u32,
}

/// Parses a `vrpn_Tng3` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(4, "name, port, buttons, analogs")?;
    Ok(Box::new(Tng3 {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        buttons: line.uint(2, "buttons", 0, MAX_INPUTS)?,
        analogs: line.uint(3, "analogs", 0, MAX_INPUTS)?,
    }))
}

impl Tng3 {
    /// The driver for this entry, with its servers on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<Tng3Protocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            Tng3Protocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Tng3 {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = Tng3Protocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

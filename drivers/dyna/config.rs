//! The `vrpn_Tracker_Dyna` line: its fields, its parser, what it serves and how it is built.

use super::DynaProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// Most sensors a DynaSight entry may declare (C++ bounds its trackers' counts the same way).
pub const MAX_SENSORS: u32 = 13;

/// `vrpn_Tracker_Dyna NAME SENSORS PORT BAUD`: Origin Instruments DynaSight (note: sensor
/// count before the port).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Dyna {
    /// Device name.
    pub name: String,
    /// Sensor count, 1..=[`MAX_SENSORS`] (only sensor 0 is ever reported).
    pub sensors: u32,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`](crate::config::BAUD_RATES).
    pub baud: u32,
}

/// Parses a `vrpn_Tracker_Dyna` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(4, "name, sensors, port, baud")?;
    Ok(Box::new(Dyna {
        name: line.name(0)?,
        sensors: line.uint(1, "sensors", 1, MAX_SENSORS)?,
        port: line.word(2)?.to_owned(),
        baud: line.baud(3)?,
    }))
}

impl Dyna {
    /// The driver for this entry, with its tracker served on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<DynaProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            DynaProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Dyna {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = DynaProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

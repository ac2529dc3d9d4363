//! The `vrpn_Spaceball` line: its fields, its parser, what it serves and how it is built.

use super::SpaceballProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_Spaceball NAME PORT BAUD`: a Spaceball 2003, 3003 or 4000 FLX on a serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Spaceball {
    /// Device name (an Analog and a Button).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`](crate::config::BAUD_RATES) (9600 for the device).
    pub baud: u32,
}

/// Parses a `vrpn_Spaceball` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, port, baud")?;
    Ok(Box::new(Spaceball {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
    }))
}

impl Spaceball {
    /// The driver for this entry, with its Analog and Button served on `conn`.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<SpaceballProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            SpaceballProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Spaceball {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = SpaceballProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

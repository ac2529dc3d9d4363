//! The `vrpn_Radamec_SPI` line: its fields, its parser, what it serves and how it is built.

use super::RadamecProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_Radamec_SPI NAME PORT BAUD`: a Radamec Serial Position Interface.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Radamec {
    /// Device name (Analog).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate (38400 in normal operation).
    pub baud: u32,
}

/// Parses a `vrpn_Radamec_SPI` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, port, baud")?;
    Ok(Box::new(Radamec {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
    }))
}

impl Radamec {
    /// The driver for this entry, with its Analog on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<RadamecProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            RadamecProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Radamec {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = RadamecProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

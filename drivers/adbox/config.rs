//! The `vrpn_ADBox` line: its fields, its parser, what it serves and how it is built.

use super::AdBoxProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_ADBox NAME PORT BAUD`: a Fraunhofer IMK AD-Box (or Fakespace Cubic Mouse) on a
/// serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdBox {
    /// Device name (an Analog and a Button).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate.
    pub baud: u32,
}

/// Parses a `vrpn_ADBox` line (words after the baud rate are ignored, as C++ does).
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, port, baud")?;
    Ok(Box::new(AdBox {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
    }))
}

impl AdBox {
    /// The driver for this entry, with its Analog and Button served on `conn`.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<AdBoxProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            AdBoxProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for AdBox {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = AdBoxProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

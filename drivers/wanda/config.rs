//! The `vrpn_Wanda` line: its fields, its parser, what it serves and how it is built.

use super::WandaProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_Wanda NAME PORT BAUD MIN_UPDATE_RATE`: a Wanda on a serial port.
#[derive(Clone, Debug, PartialEq)]
pub struct Wanda {
    /// Device name (Analog with 2 channels, Button with 3).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate (the Wanda runs at 1200).
    pub baud: u32,
    /// The minimum update rate. C++ parses it and never uses it; so does this driver.
    pub min_update_rate: f32,
}

/// Parses a `vrpn_Wanda` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(4, "name, port, baud, minimum update rate")?;
    Ok(Box::new(Wanda {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
        min_update_rate: line.f32(3, "minimum update rate")?,
    }))
}

impl Wanda {
    /// The driver for this entry, with its servers on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<WandaProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            WandaProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Wanda {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = WandaProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

//! The `vrpn_Zaber` line: its fields, its parser, what it serves and how it is built.

use super::ZaberProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// The line speed of Zaber's binary protocol (C++ opens the port at its default, 9600).
pub const BAUD: u32 = 9600;

/// `vrpn_Zaber NAME PORT`: a chain of Zaber linear positioners on a serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Zaber {
    /// Device name (an Analog and an Analog_Output).
    pub name: String,
    /// Serial port.
    pub port: String,
}

/// Parses a `vrpn_Zaber` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(2, "name, port")?;
    Ok(Box::new(Zaber {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
    }))
}

impl Zaber {
    /// The driver for this entry, with its Analog and Analog_Output served on `conn`.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<ZaberProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            ZaberProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Zaber {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::AnalogOutput])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = ZaberProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

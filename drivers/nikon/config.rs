//! The `vrpn_nikon_controls` line: its fields, its parser, what it serves and how it is built.

use super::NikonProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// The line speed (C++ opens the port at its serial analog's default, 9600 8N1).
pub const BAUD: u32 = 9600;

/// `vrpn_nikon_controls NAME PORT`: a Nikon microscope's focus on a serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Nikon {
    /// Device name (an Analog and an Analog_Output).
    pub name: String,
    /// Serial port.
    pub port: String,
}

/// Parses a `vrpn_nikon_controls` line (words after the port are ignored, as C++ does).
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(2, "name, port")?;
    Ok(Box::new(Nikon {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
    }))
}

impl Nikon {
    /// The driver for this entry, with its Analog and Analog_Output served on `conn`.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<NikonProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            NikonProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Nikon {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::AnalogOutput])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = NikonProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

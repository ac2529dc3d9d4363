//! The `vrpn_BiosciencesTools` line: its fields, its parser, what it serves and how it is
//! built.

use super::BioProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// The controller's line speed (8N1, RTS/CTS), as C++ opens it.
pub const BAUD: u32 = 115_200;

/// `vrpn_BiosciencesTools NAME PORT TEMP1 TEMP2 CONTROL`: a Biosciences Tools temperature
/// controller.
#[derive(Clone, Debug, PartialEq)]
pub struct Biosciences {
    /// Device name (an Analog, an Analog_Output and a Button).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Reference temperature of channel 1, °C.
    pub temp1: f32,
    /// Reference temperature of channel 2, °C.
    pub temp2: f32,
    /// Temperature control on at start.
    pub control: bool,
}

/// Parses a `vrpn_BiosciencesTools` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(
        5,
        "name, port, temperature 1, temperature 2, control (0 or 1)",
    )?;
    Ok(Box::new(Biosciences {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        temp1: line.f32(2, "temperature 1")?,
        temp2: line.f32(3, "temperature 2")?,
        control: line.int(4, "control")? != 0,
    }))
}

impl Biosciences {
    /// The driver for this entry, with its devices served on `conn`.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<BioProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            BioProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Biosciences {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(
            &self.name,
            &[
                Interface::Analog,
                Interface::AnalogOutput,
                Interface::Button,
            ],
        )
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = BioProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

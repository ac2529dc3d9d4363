//! The `vrpn_Button_PinchGlove` line: its fields, its parser, what it serves and how it is
//! built.

use super::PinchGloveProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_Button_PinchGlove NAME PORT BAUD`: a Fakespace Pinch Glove system on a serial port.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PinchGlove {
    /// Device name (Button with 10 buttons).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate (9600 is usual).
    pub baud: u32,
}

/// Parses a `vrpn_Button_PinchGlove` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, port, baud")?;
    Ok(Box::new(PinchGlove {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
    }))
}

impl PinchGlove {
    /// The driver for this entry, with its buttons on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<PinchGloveProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            PinchGloveProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for PinchGlove {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = PinchGloveProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

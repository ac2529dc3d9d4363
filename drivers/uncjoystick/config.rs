//! The `vrpn_Joystick` line: its fields, its parser, what it serves and how it is built.

use super::UncJoystickProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_Joystick NAME PORT BAUD MIN_UPDATE_RATE`: the UNC joystick box on a serial port.
#[derive(Clone, Debug, PartialEq)]
pub struct UncJoystick {
    /// Device name (Analog with 7 channels, Button with 2).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate.
    pub baud: u32,
    /// Reports a second while the box is quiet (0: none).
    pub min_update_rate: f32,
}

/// Parses a `vrpn_Joystick` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(4, "name, port, baud, minimum update rate")?;
    Ok(Box::new(UncJoystick {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
        min_update_rate: line.non_negative(3, "minimum update rate")?,
    }))
}

impl UncJoystick {
    /// The driver for this entry, with its servers on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<UncJoystickProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            UncJoystickProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for UncJoystick {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = UncJoystickProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

//! The `vrpn_VPJoystick` line: its fields, its parser, what it serves and how it is built.

use super::VpJoystickProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_VPJoystick NAME PORT BAUD`: the buttons of a Virtual Presence joystick.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VpJoystick {
    /// Device name (a Button with 8 buttons).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate (9600).
    pub baud: u32,
}

/// Parses a `vrpn_VPJoystick` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, port, baud")?;
    Ok(Box::new(VpJoystick {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
    }))
}

impl VpJoystick {
    /// The driver for this entry, with its server on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<VpJoystickProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            VpJoystickProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for VpJoystick {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = VpJoystickProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

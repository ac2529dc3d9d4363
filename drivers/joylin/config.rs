//! The `vrpn_Joylin` line: its fields, its parser, what it serves and how it is built.

use super::JoylinProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_Joylin NAME DEVICE`: a Linux joystick (`/dev/input/jsN`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Joylin {
    /// Device name (Analog and Button under it).
    pub name: String,
    /// Joystick device path.
    pub device: String,
}

/// Parses a `vrpn_Joylin` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(2, "name, device")?;
    Ok(Box::new(Joylin {
        name: line.name(0)?,
        device: line.word(1)?.to_owned(),
    }))
}

impl Joylin {
    /// The driver for this entry, with its Analog and Button served on `conn`, ready for a
    /// device file.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<JoylinProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            JoylinProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Joylin {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = JoylinProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.device, protocol, cx)])
    }
}

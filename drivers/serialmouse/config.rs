//! The `vrpn_Button_SerialMouse` line: its fields, its parser, what it serves and how it is
//! built.

use super::packet::MouseType;
use super::SerialMouseProtocol;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_Button_SerialMouse NAME PORT TYPE`: the buttons of a serial mouse (or of a box
/// wired in parallel with them), `TYPE` `mousesystems` or `3button`. The line runs at 1200
/// baud 8N1, as C++ opens it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SerialMouse {
    /// Device name (a Button with 3 buttons).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// The mouse's protocol.
    pub kind: MouseType,
}

/// Parses a `vrpn_Button_SerialMouse` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, port, mouse type (mousesystems or 3button)")?;
    let kind = match line.word(2)? {
        "mousesystems" => MouseType::MouseSystems,
        "3button" => MouseType::ThreeButton,
        other => {
            return Err(line.err(
                ConfigErrorKind::BadValue,
                format!("bad mouse type '{other}' (expected mousesystems or 3button)"),
            ))
        }
    };
    Ok(Box::new(SerialMouse {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        kind,
    }))
}

impl SerialMouse {
    /// The driver for this entry, with its server on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<SerialMouseProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            SerialMouseProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for SerialMouse {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = SerialMouseProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

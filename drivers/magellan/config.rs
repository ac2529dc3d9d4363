//! The `vrpn_Magellan` line: its fields, its parser, what it serves and how it is built.

use super::MagellanProtocol;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_Magellan NAME PORT BAUD [altreset]`: Magellan / SpaceMouse on a serial port.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Magellan {
    /// Device name (Analog with 6 channels, Button with 9).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`](crate::config::BAUD_RATES) (the device documents
    /// 9600).
    pub baud: u32,
    /// Use the alternate reset string of older units (`altreset`).
    pub alt_reset: bool,
}

/// Parses a `vrpn_Magellan` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, port, baud, [altreset]")?;
    let alt_reset = match line.arg(3) {
        None => false,
        Some("altreset") => true,
        Some(t) => {
            return Err(line.err(
                ConfigErrorKind::BadValue,
                format!("the optional 4th argument must be 'altreset', found '{t}'"),
            ))
        }
    };
    Ok(Box::new(Magellan {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
        alt_reset,
    }))
}

impl Magellan {
    /// The driver for this entry, with its Analog and Button served on `conn`, ready for a
    /// port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<MagellanProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            MagellanProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Magellan {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = MagellanProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

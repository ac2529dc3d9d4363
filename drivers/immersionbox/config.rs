//! The `vrpn_ImmersionBox` line: its fields, its parser, what it serves and how it is built.

use super::record::{MAX_ANALOGS, MAX_BUTTONS, MAX_ENCODERS};
use super::ImmersionBoxProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_ImmersionBox NAME PORT BAUD BUTTONS ANALOGS ENCODERS`: an Immersion Interface Box.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImmersionBox {
    /// Device name (Button, Analog and Dial).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate.
    pub baud: u32,
    /// Buttons read (0-7).
    pub buttons: u32,
    /// Analog inputs asked for (0-8).
    pub analogs: u32,
    /// Encoders asked for (0-6).
    pub encoders: u32,
}

/// Parses a `vrpn_ImmersionBox` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(6, "name, port, baud, buttons, analogs, encoders")?;
    Ok(Box::new(ImmersionBox {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
        buttons: line.uint(3, "buttons", 0, MAX_BUTTONS)?,
        analogs: line.uint(4, "analogs", 0, MAX_ANALOGS)?,
        encoders: line.uint(5, "encoders", 0, MAX_ENCODERS)?,
    }))
}

impl ImmersionBox {
    /// The driver for this entry, with its servers on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<ImmersionBoxProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            ImmersionBoxProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for ImmersionBox {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(
            &self.name,
            &[Interface::Button, Interface::Analog, Interface::Dial],
        )
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = ImmersionBoxProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

//! The `vrpn_raw_SGIBox` line: its fields, its parser, what it serves and how it is built.

use super::record::BUTTONS;
use super::SgiBoxProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_raw_SGIBox NAME PORT [BUTTON ...]`: the SGI dial and button boxes on a serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SgiBox {
    /// Device name (Button with 32 buttons, Analog with 8 channels, Dial with 8 dials).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Buttons that toggle (initially off), in the order listed.
    pub toggles: Vec<u32>,
}

/// Parses a `vrpn_raw_SGIBox` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(2, "name, port, [buttons to toggle]")?;
    let toggles = (2..line.args().len())
        .map(|i| line.uint(i, "button to toggle", 0, BUTTONS as u32 - 1))
        .collect::<Result<Vec<u32>, ConfigError>>()?;
    Ok(Box::new(SgiBox {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        toggles,
    }))
}

impl SgiBox {
    /// The driver for this entry, with its servers on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<SgiBoxProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            SgiBoxProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for SgiBox {
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
        let protocol = SgiBoxProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

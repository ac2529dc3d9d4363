//! The `vrpn_Tracker_3DMouse` line: its fields, its parser, what it serves and how it is
//! built.

use super::ThreeDMouseProtocol;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_Tracker_3DMouse NAME PORT BAUD [FILTER_COUNT]`: a Logitech 3D mouse or head tracker
/// on a serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ThreeDMouse {
    /// Device name (a Tracker with one sensor and a Button with 5 buttons).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate (19200).
    pub baud: u32,
    /// The control unit's filter count, 1–5 (1, the device's own, unless given; only a count
    /// above 1 is sent).
    pub filter_count: u8,
}

/// Parses a `vrpn_Tracker_3DMouse` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, port, baud, [filter count 1-5]")?;
    let filter_count = match line.arg(3) {
        None => 1,
        Some(_) => line.uint(3, "filter count", 1, 5)? as u8,
    };
    if let Some(extra) = line.arg(4) {
        return Err(line.err(
            ConfigErrorKind::BadValue,
            format!("unexpected argument '{extra}' after the filter count"),
        ));
    }
    Ok(Box::new(ThreeDMouse {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
        filter_count,
    }))
}

impl ThreeDMouse {
    /// The driver for this entry, with its servers on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<ThreeDMouseProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            ThreeDMouseProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for ThreeDMouse {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker, Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = ThreeDMouseProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

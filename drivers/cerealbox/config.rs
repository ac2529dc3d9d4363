//! The `vrpn_CerealBox` line: its fields, its parser, what it serves and how it is built.

use super::CerealBoxProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_CerealBox NAME PORT BAUD BUTTONS ANALOGS ENCODERS`: BG Systems CerealBox.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CerealBox {
    /// Device name (Button, Analog and Dial under it).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`](crate::config::BAUD_RATES) (the device documents
    /// 19200).
    pub baud: u32,
    /// Buttons, 0..=24 (C++ clamps larger values; we reject them).
    pub buttons: u32,
    /// Analog channels, 0..=8.
    pub analogs: u32,
    /// Encoders (dials), 0..=8.
    pub encoders: u32,
}

impl CerealBox {
    /// Most buttons.
    pub const MAX_BUTTONS: u32 = 24;
    /// Most analogs.
    pub const MAX_ANALOGS: u32 = 8;
    /// Most encoders.
    pub const MAX_ENCODERS: u32 = 8;
}

/// Parses a `vrpn_CerealBox` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(6, "name, port, baud, buttons, analogs, encoders")?;
    Ok(Box::new(CerealBox {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
        buttons: line.uint(3, "buttons", 0, CerealBox::MAX_BUTTONS)?,
        analogs: line.uint(4, "analogs", 0, CerealBox::MAX_ANALOGS)?,
        encoders: line.uint(5, "encoders", 0, CerealBox::MAX_ENCODERS)?,
    }))
}

impl CerealBox {
    /// The driver for this entry, with its Analog, Button and Dial served on `conn`, ready
    /// for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<CerealBoxProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            CerealBoxProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for CerealBox {
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
        let protocol = CerealBoxProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

//! The `vrpn_Streaming_Arduino` line: its fields, its parser, what it serves and how it is
//! built.

use super::ArduinoProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// Most analog inputs the sketch reads (C++ clamps larger counts to this).
pub const MAX_ANALOGS: u32 = 8;
/// The baud rate when the line gives none (the sketch's).
pub const DEFAULT_BAUD: u32 = 115_200;

/// `vrpn_Streaming_Arduino NAME PORT ANALOGS [BAUD]`: an Arduino running VRPN's
/// `vrpn_streaming_arduino` sketch.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StreamingArduino {
    /// Device name (an Analog and a Button without buttons, as C++).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Analog inputs to read, as the line gives it (1 or more).
    pub requested: u32,
    /// Baud rate ([`DEFAULT_BAUD`] unless given).
    pub baud: u32,
}

impl StreamingArduino {
    /// Analog inputs read: the line's count, at most [`MAX_ANALOGS`] (as C++).
    pub fn analogs(&self) -> usize {
        self.requested.min(MAX_ANALOGS) as usize
    }

    /// The driver for this entry, with its Analog and Button served on `conn`.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<ArduinoProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            ArduinoProtocol::new(self, conn)?,
            conn,
        ))
    }
}

/// Parses a `vrpn_Streaming_Arduino` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, port, number of analogs [, baud]")?;
    let baud = match line.arg(3) {
        Some(_) => line.baud(3)?,
        None => DEFAULT_BAUD,
    };
    Ok(Box::new(StreamingArduino {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        requested: line.uint(2, "number of analogs", 1, u32::MAX)?,
        baud,
    }))
}

impl DeviceSpec for StreamingArduino {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::Button])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = ArduinoProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

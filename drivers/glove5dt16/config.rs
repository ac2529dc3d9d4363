//! The `vrpn_5dt16` line: its fields, its parser, what it serves and how it is built.

use super::Glove16Protocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// `vrpn_5dt16 NAME PORT BAUD`: a 5DT Data Glove 16 on a serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Glove5dt16 {
    /// Device name (an Analog).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate (19200 for the glove).
    pub baud: u32,
}

/// Parses a `vrpn_5dt16` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, port, baud")?;
    Ok(Box::new(Glove5dt16 {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
    }))
}

impl Glove5dt16 {
    /// The driver for this entry, with its Analog served on `conn`.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<Glove16Protocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            Glove16Protocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Glove5dt16 {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = Glove16Protocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

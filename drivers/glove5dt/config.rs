//! The `vrpn_5dt` line: its fields, its parser, what it serves and how it is built.

use super::Glove5dtProtocol;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// How the glove's records are asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// `1`: one record per request (`C`), C++'s advice.
    Polled,
    /// `2`: the glove streams (`D`).
    Streaming,
}

/// `vrpn_5dt NAME PORT BAUD MODE TENBYTES`: a 5DT Data Glove 5 on a serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Glove5dt {
    /// Device name (an Analog).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Baud rate; 9600 means a receive-only wireless glove (as C++ decides).
    pub baud: u32,
    /// Polled (1) or streaming (2); a wireless glove always streams.
    pub mode: Mode,
    /// Records are ten bytes instead of nine (always for a wireless glove).
    pub ten_bytes: bool,
}

impl Glove5dt {
    /// A receive-only wireless glove: C++ takes 9600 baud to mean one.
    pub fn wireless(&self) -> bool {
        self.baud == 9600
    }

    /// Bytes per record.
    pub fn record_len(&self) -> usize {
        if self.ten_bytes || self.wireless() {
            10
        } else {
            9
        }
    }

    /// The driver for this entry, with its Analog served on `conn`.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<Glove5dtProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            Glove5dtProtocol::new(self, conn)?,
            conn,
        ))
    }
}

/// Parses a `vrpn_5dt` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(
        5,
        "name, port, baud, mode (1 polled, 2 streaming), ten_bytes (0 or 1)",
    )?;
    let mode = match line.uint(3, "mode (1 polled, 2 streaming)", 1, 2)? {
        1 => Mode::Polled,
        _ => Mode::Streaming,
    };
    Ok(Box::new(Glove5dt {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        baud: line.baud(2)?,
        mode,
        ten_bytes: line.int(4, "ten_bytes")? != 0,
    }))
}

impl DeviceSpec for Glove5dt {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = Glove5dtProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

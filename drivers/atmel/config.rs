//! The `vrpn_Atmel` entry: its lines, its parser, what it serves and how it is built.
//!
//! C++ reads the entry over several lines, each starting with the keyword:
//!
//! ```text
//! vrpn_Atmel NAME PORT BAUD CHANNELS
//! vrpn_Atmel CHANNEL MODE          (as many as wanted; MODE is RW, RO, WO or NA)
//! vrpn_Atmel -1 END                (ends the entry; C++ needs a word after -1)
//! ```
//!
//! A channel without a line is `NA`. Comment and blank lines may stand between the lines.

use super::command::Mode;
use super::AtmelProtocol;
use crate::config::lines::{c_tokens, classify_line, LineClass};
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// The most channels (C++'s `vrpn_CHANNEL_MAX`).
pub const MAX_CHANNELS: usize = 128;

/// A `vrpn_Atmel` entry: an Atmel ATmega32 board (Albotronic) on a serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Atmel {
    /// Device name (an Analog and an Analog_Output).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// The baud rate as written.
    pub baud: u32,
    /// Each channel's mode (channel `i` is register `i`).
    pub modes: Vec<Mode>,
}

impl Atmel {
    /// The speed the port is opened at: 38400 when asked for, else 9600 (as C++).
    pub fn line_speed(&self) -> u32 {
        if self.baud == 38400 {
            38400
        } else {
            9600
        }
    }

    /// The driver for this entry, with its Analog and Analog_Output served on `conn`.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<AtmelProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            AtmelProtocol::new(self, conn)?,
            conn,
        ))
    }
}

const CHANNEL_LINE: &str = "'vrpn_Atmel CHANNEL MODE' (MODE RW, RO, WO or NA)";

/// Parses a `vrpn_Atmel` entry: its first line and the channel lines up to `vrpn_Atmel -1`.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(4, "name, port, baud, channels")?;
    let name = line.name(0)?;
    let port = line.word(1)?.to_owned();
    let baud = line.uint(2, "baud", 1, u32::MAX)?;
    let count = line.uint(3, "channels", 1, MAX_CHANNELS as u32)? as usize;
    let mut modes = vec![Mode::Unused; count];
    let keyword = line.keyword();
    loop {
        let next = line.block_line(&format!("the line 'vrpn_Atmel -1 END' ending {name}"))?;
        let ctx = line.ctx().at(next.number);
        if !matches!(classify_line(next.text), LineClass::Entry(_)) {
            continue;
        }
        let t = c_tokens(next.text);
        if t.first() != Some(&keyword) {
            return Err(ctx.err(
                ConfigErrorKind::BadBlockLine,
                format!(
                    "expected a channel line of vrpn_Atmel {name}, {CHANNEL_LINE}, or \
                     'vrpn_Atmel -1 END' to end it; found '{}'",
                    next.content().trim()
                ),
            ));
        }
        let Some(channel) = t.get(1) else {
            return Err(ctx.err(
                ConfigErrorKind::MissingArguments,
                format!("a channel line needs a channel and a mode: {CHANNEL_LINE}"),
            ));
        };
        let channel: i64 = channel.parse().map_err(|_| {
            ctx.err(
                ConfigErrorKind::BadNumber,
                format!("the channel must be a whole number, found '{channel}'"),
            )
        })?;
        if channel == -1 {
            return Ok(Box::new(Atmel {
                name,
                port,
                baud,
                modes,
            }));
        }
        if channel < 0 || channel >= count as i64 {
            return Err(ctx.err(
                ConfigErrorKind::OutOfRange,
                format!(
                    "channel {channel} is out of range: {name} has {count} channels \
                     (0..={}); -1 ends the entry",
                    count - 1
                ),
            ));
        }
        let Some(word) = t.get(2) else {
            return Err(ctx.err(
                ConfigErrorKind::MissingArguments,
                format!("channel {channel} needs a mode: {CHANNEL_LINE}"),
            ));
        };
        modes[channel as usize] = Mode::from_word(word).ok_or_else(|| {
            ctx.err(
                ConfigErrorKind::BadValue,
                format!("unknown io-mode '{word}' for channel {channel}: RW, RO, WO or NA"),
            )
        })?;
    }
}

impl DeviceSpec for Atmel {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog, Interface::AnalogOutput])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = AtmelProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

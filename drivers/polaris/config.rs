//! The `vrpn_Tracker_NDI_Polaris` line: its fields, its parser, what it serves, how it is
//! built.

use super::reply::MAX_HANDLES;
use super::reset::{padded, MAX_ROM};
use super::PolarisProtocol;
use crate::config::fields::{device_name, need, uint_in};
use crate::config::lines::c_tokens;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// A tool (rigid body): its `.rom` file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Tool {
    /// The file, as the line names it (relative to the server's working directory).
    pub file: String,
    /// The configuration line that names it.
    pub line: usize,
}

impl Tool {
    /// Reads the file: its contents padded with zeros to whole 64-byte chunks, or an error
    /// naming the file, its line and the problem.
    pub fn read(&self) -> Result<Vec<u8>, Error> {
        let bad = |why: String| {
            Error::InvalidArgument(format!(
                "the .rom file '{}' (configuration line {}) {why}",
                self.file, self.line
            ))
        };
        let rom = std::fs::read(&self.file).map_err(|e| bad(format!("cannot be read: {e}")))?;
        if rom.is_empty() || rom.len() > MAX_ROM {
            return Err(bad(format!(
                "has {} bytes; a tool definition has 1 to {MAX_ROM}",
                rom.len()
            )));
        }
        Ok(padded(rom))
    }
}

/// `vrpn_Tracker_NDI_Polaris NAME PORT N` followed by `N` lines, each naming a tool's `.rom`
/// file: an NDI Polaris (Spectra, Vectra) on a serial line or its USB adapter.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Polaris {
    /// Device name.
    pub name: String,
    /// Serial port.
    pub port: String,
    /// The tools, sensor 0 first.
    pub tools: Vec<Tool>,
}

/// Parses a `vrpn_Tracker_NDI_Polaris` entry and its `.rom` lines (the files are read when
/// the device is built).
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    let ctx = line.ctx().clone();
    let a = line.args().to_vec();
    need(&ctx, &a, 3, "name, port, number_of_rigid_bodies")?;
    let name = device_name(&ctx, "name", a[0])?;
    let port = a[1].to_owned();
    let n = uint_in(&ctx, "number of rigid bodies", a[2], 1, MAX_HANDLES as u32)?;
    if let Some(extra) = a.get(3) {
        return Err(ctx.err(
            ConfigErrorKind::BadValue,
            format!("unexpected argument '{extra}' (the .rom files go on the lines after)"),
        ));
    }
    let mut tools = Vec::new();
    for i in 0..n {
        let next = line.block_line(&format!("the .rom file of rigid body {i}"))?;
        let here = ctx.at(next.number);
        let tokens = c_tokens(next.content());
        let Some(&file) = tokens.first() else {
            return Err(here.err(
                ConfigErrorKind::BadBlockLine,
                format!("an empty line where the .rom file of rigid body {i} was expected"),
            ));
        };
        tools.push(Tool {
            file: file.to_owned(),
            line: next.number,
        });
    }
    Ok(Box::new(Polaris { name, port, tools }))
}

impl Polaris {
    /// The driver for this entry, with its server on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<PolarisProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            PolarisProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Polaris {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = PolarisProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

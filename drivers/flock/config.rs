//! The `vrpn_Tracker_Flock` and `vrpn_Tracker_Flock_Parallel` lines: their fields, their
//! parsers, what they serve and how they are built.

use super::{FlockParallelPort, FlockProtocol};
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, serve_port, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// Most receivers on an Ascension Flock of Birds.
pub const MAX_FLOCK_SENSORS: u32 = 13;

/// Hemisphere a Flock of Birds works in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Hemisphere {
    /// `+x`.
    PosX,
    /// `-x`.
    NegX,
    /// `+y`.
    PosY,
    /// `-y`.
    NegY,
    /// `+z` (the default).
    PosZ,
    /// `-z`.
    NegZ,
}

impl Hemisphere {
    /// Parses `+x -x +y -y +z -z` (axis letter in either case).
    pub fn parse(tok: &str) -> Option<Hemisphere> {
        match tok.to_ascii_lowercase().as_str() {
            "+x" => Some(Hemisphere::PosX),
            "-x" => Some(Hemisphere::NegX),
            "+y" => Some(Hemisphere::PosY),
            "-y" => Some(Hemisphere::NegY),
            "+z" => Some(Hemisphere::PosZ),
            "-z" => Some(Hemisphere::NegZ),
            _ => None,
        }
    }
}

/// `vrpn_Tracker_Flock NAME SENSORS PORT BAUD INVERT [USE_ERT] [HEMISPHERE]`: Ascension Flock
/// of Birds on one serial line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Flock {
    /// Device name.
    pub name: String,
    /// Number of receivers, 1..=[`MAX_FLOCK_SENSORS`].
    pub sensors: u32,
    /// Serial port.
    pub port: String,
    /// Baud rate, one of [`BAUD_RATES`](crate::config::BAUD_RATES).
    pub baud: u32,
    /// Report the inverse quaternion (non-zero INVERT).
    pub invert_quaternion: bool,
    /// Extended-range transmitter present (default yes; a token starting with `n`/`N` = no).
    pub use_ert: bool,
    /// Hemisphere (default `+z`).
    pub hemisphere: Hemisphere,
}

/// `vrpn_Tracker_Flock_Parallel NAME SENSORS MASTER_PORT BAUD INVERT PORT_1 .. PORT_N`: one
/// serial line per receiver.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FlockParallel {
    /// Device name.
    pub name: String,
    /// Number of receivers N, 1..=[`MAX_FLOCK_SENSORS`] (C++ 07.35 does not check; later
    /// versions reject more than 13, as we do).
    pub sensors: u32,
    /// Master's serial port.
    pub master_port: String,
    /// Baud rate of all ports, one of [`BAUD_RATES`](crate::config::BAUD_RATES).
    pub baud: u32,
    /// The INVERT flag; C++ applies it only to the master, so it changes nothing reported.
    pub invert_quaternion: bool,
    /// One serial port per receiver (N of them).
    pub slave_ports: Vec<String>,
}

/// Parses a `vrpn_Tracker_Flock` line.
pub(super) fn parse_flock(
    line: &mut ConfigLine<'_, '_>,
) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(
        5,
        "name, sensors, port, baud, invert_quaternion, [useERT], [hemisphere]",
    )?;
    let use_ert = line.arg(5).map_or(true, |t| !t.starts_with(['n', 'N']));
    let hemisphere = match line.arg(6) {
        None => Hemisphere::PosZ,
        Some(t) => Hemisphere::parse(t).ok_or_else(|| {
            line.err(
                ConfigErrorKind::BadValue,
                format!("hemisphere must be one of +x -x +y -y +z -z, found '{t}'"),
            )
        })?,
    };
    Ok(Box::new(Flock {
        name: line.name(0)?,
        sensors: line.uint(1, "sensors", 1, MAX_FLOCK_SENSORS)?,
        port: line.word(2)?.to_owned(),
        baud: line.baud(3)?,
        invert_quaternion: line.int(4, "invert_quaternion")? != 0,
        use_ert,
        hemisphere,
    }))
}

/// Parses a `vrpn_Tracker_Flock_Parallel` line.
pub(super) fn parse_parallel(
    line: &mut ConfigLine<'_, '_>,
) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    const USAGE: &str = "name, sensors, master_port, baud, invert_quaternion, then one port \
                         per sensor";
    line.need(5, USAGE)?;
    let sensors = line.uint(1, "sensors", 1, MAX_FLOCK_SENSORS)?;
    let ports = &line.args()[5..];
    let wanted = sensors as usize;
    if ports.len() < wanted {
        return Err(line.err(
            ConfigErrorKind::MissingArguments,
            format!(
                "expected {wanted} slave port name(s) after invert_quaternion (one per \
                 sensor), found {}",
                ports.len()
            ),
        ));
    }
    Ok(Box::new(FlockParallel {
        name: line.name(0)?,
        sensors,
        master_port: line.word(2)?.to_owned(),
        baud: line.baud(3)?,
        invert_quaternion: line.int(4, "invert_quaternion")? != 0,
        slave_ports: ports[..wanted].iter().map(|p| (*p).to_owned()).collect(),
    }))
}

impl Flock {
    /// The driver for this entry, with its tracker served on `conn`, ready for a port.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<FlockProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            FlockProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Flock {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = FlockProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}

impl DeviceSpec for FlockParallel {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }

    /// One device per line, master first, sharing the Flock's state.
    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let ports = FlockParallelPort::new_group(self, cx.conn())?;
        Ok(ports
            .into_iter()
            .map(|d| {
                let path = d.port().to_owned();
                serve_port(&path, d, cx)
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hemispheres() {
        assert_eq!(Hemisphere::parse("-X"), Some(Hemisphere::NegX));
        assert_eq!(Hemisphere::parse("z"), None);
    }
}

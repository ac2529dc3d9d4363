//! From `vrpn.cfg` entries to running devices: the table from keyword to constructor.

use super::config::{DeviceConfig, DeviceEntry};
use crate::connection::Connection;
use crate::devices::analog::AnalogExample;
use crate::devices::button::ButtonExample;
use crate::devices::dial::DialExample;
use crate::devices::text_device::TextExample;
use crate::devices::tracker::{TrackerNull, TrackerSpin};
use crate::devices::ServerDevice;
use crate::drivers::cerealbox::CerealBoxDriver;
use crate::drivers::dyna::DynaDriver;
use crate::drivers::fastrak::FastrakDriver;
use crate::drivers::flock::{FlockDriver, FlockParallelPort};
use crate::drivers::joylin::JoylinDriver;
use crate::drivers::magellan::MagellanDriver;
use crate::layered::{TrackerAnalogFly, TrackerButtonFly};
use crate::serial::SerialDevice;

/// What [`build_devices`] has to say about an entry, for the program to print.
#[derive(Debug)]
pub enum BuildNote<'a> {
    /// A device was created (`vrpn_server -v` prints these).
    Opened {
        /// The entry it came from.
        entry: &'a DeviceEntry,
        /// The device's name.
        name: &'a str,
    },
    /// With `warn_only`, an entry that could not be built and was left out (C++ `-warn`
    /// prints the problem and goes on).
    Skipped {
        /// The entry.
        entry: &'a DeviceEntry,
        /// Why, naming the file and line.
        error: String,
    },
}

/// Builds the devices `entries` describe on `conn`, in file order, telling `note` about each.
///
/// An entry that cannot be served (unknown keyword, a device not implemented yet, a constructor
/// failure) is an error naming the file and line; with `warn_only` (`vrpn_server -warn`) it is
/// reported as [`BuildNote::Skipped`] and left out instead, as C++ does. Entries sharing a
/// name are all built (see [`super::config::name_clashes`] for the ones worth a warning).
pub fn build_devices(
    entries: &[DeviceEntry],
    conn: &Connection,
    warn_only: bool,
    mut note: impl FnMut(BuildNote<'_>),
) -> Result<Vec<Box<dyn ServerDevice>>, String> {
    let mut devices: Vec<Box<dyn ServerDevice>> = Vec::new();
    for entry in entries {
        match build_one(entry, conn) {
            Ok(built) => {
                if let Some(first) = built.first() {
                    note(BuildNote::Opened {
                        entry,
                        name: first.name(),
                    });
                }
                devices.extend(built);
            }
            Err(error) if warn_only => note(BuildNote::Skipped { entry, error }),
            Err(e) => return Err(e),
        }
    }
    Ok(devices)
}

/// The devices of one entry: usually one; a device on several serial lines (Flock_Parallel)
/// runs one per line.
fn build_one(entry: &DeviceEntry, conn: &Connection) -> Result<Vec<Box<dyn ServerDevice>>, String> {
    let at = |e: crate::Error| format!("{}: {}: {e}", entry.location, entry.keyword);
    match &entry.config {
        DeviceConfig::Fastrak(c) => {
            let driver = FastrakDriver::new(c, conn).map_err(at)?;
            Ok(vec![Box::new(SerialDevice::new(&c.port, driver, conn))])
        }
        DeviceConfig::Flock(c) => {
            let driver = FlockDriver::new(c, conn).map_err(at)?;
            Ok(vec![Box::new(SerialDevice::new(&c.port, driver, conn))])
        }
        DeviceConfig::Dyna(c) => {
            let driver = DynaDriver::new(c, conn).map_err(at)?;
            Ok(vec![Box::new(SerialDevice::new(&c.port, driver, conn))])
        }
        DeviceConfig::Joylin(c) => {
            let driver = JoylinDriver::new(c, conn).map_err(at)?;
            Ok(vec![Box::new(SerialDevice::new(&c.device, driver, conn))])
        }
        DeviceConfig::CerealBox(c) => {
            let driver = CerealBoxDriver::new(c, conn).map_err(at)?;
            Ok(vec![Box::new(SerialDevice::new(&c.port, driver, conn))])
        }
        DeviceConfig::Magellan(c) => {
            let driver = MagellanDriver::new(c, conn).map_err(at)?;
            Ok(vec![Box::new(SerialDevice::new(&c.port, driver, conn))])
        }
        DeviceConfig::FlockParallel(c) => {
            let ports = FlockParallelPort::new_group(c, conn).map_err(at)?;
            Ok(ports
                .into_iter()
                .map(|d| {
                    let path = d.port().to_string();
                    Box::new(SerialDevice::new(&path, d, conn)) as Box<dyn ServerDevice>
                })
                .collect())
        }
        other => build_simple(entry, other, conn).map(|d| vec![d]),
    }
}

fn build_simple(
    entry: &DeviceEntry,
    config: &DeviceConfig,
    conn: &Connection,
) -> Result<Box<dyn ServerDevice>, String> {
    let at = |e: crate::Error| format!("{}: {}: {e}", entry.location, entry.keyword);
    match config {
        DeviceConfig::TrackerNull(c) => Ok(Box::new(
            TrackerNull::new(&c.name, conn, c.sensors as usize, c.rate as f64).map_err(at)?,
        )),
        DeviceConfig::TrackerSpin(c) => Ok(Box::new(
            TrackerSpin::new(
                &c.name,
                conn,
                c.sensors as usize,
                c.rate as f64,
                c.axis.map(f64::from),
                c.spin_hz as f64,
            )
            .map_err(at)?,
        )),
        DeviceConfig::ButtonExample(c) => Ok(Box::new(
            ButtonExample::new(&c.name, conn, c.buttons as usize, c.rate as f64).map_err(at)?,
        )),
        DeviceConfig::DialExample(c) => Ok(Box::new(
            DialExample::new(
                &c.name,
                conn,
                c.dials as usize,
                c.spin_rate as f64,
                c.update_rate as f64,
            )
            .map_err(at)?,
        )),
        DeviceConfig::AnalogExample(c) => Ok(Box::new(
            AnalogExample::new(&c.name, conn, c.channels as usize, c.rate as f64).map_err(at)?,
        )),
        DeviceConfig::TextExample(c) => Ok(Box::new(
            TextExample::new(&c.name, conn, c.period as f64, &c.message).map_err(at)?,
        )),
        DeviceConfig::AnalogFly(c) => Ok(Box::new(TrackerAnalogFly::new(c, conn).map_err(at)?)),
        DeviceConfig::ButtonFly(c) => Ok(Box::new(TrackerButtonFly::new(c, conn).map_err(at)?)),
        DeviceConfig::Unknown { .. } => Err(entry
            .unknown_error()
            .map(|e| e.to_string())
            .unwrap_or_else(|| format!("{}: unknown device", entry.location))),
        DeviceConfig::InterSense(_) => Err(format!(
            "{}: vrpn_Tracker_InterSense needs InterSense's own library, which this server \
             does not use; an IS-600 or IS-900 in Fastrak mode is served by a \
             vrpn_Tracker_Fastrak line (with IS900time for its clock, Wand and Stylus lines \
             for its buttons and analogs)",
            entry.location
        )),
        other => Err(format!(
            "{}: {} is recognised but this vrpn_server cannot serve it yet",
            entry.location,
            other.keyword()
        )),
    }
}

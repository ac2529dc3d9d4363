//! From `vrpn.cfg` entries to running devices: each entry's configuration builds itself.

use std::fmt;

use super::config::{ConfigError, DeviceEntry, SourceLocation};
use crate::connection::Connection;
use crate::devices::ServerDevice;
use crate::driver::registry::BuildContext;
use crate::driver::StatusSink;

/// Why an entry could not be built.
#[derive(Debug)]
pub enum BuildError {
    /// Its keyword is not one a driver serves (the error says which, with a hint).
    Unknown(ConfigError),
    /// Its driver could not make it (a name that cannot be registered, a combination the
    /// device does not support).
    Device {
        /// The entry's location.
        location: SourceLocation,
        /// The entry's keyword.
        keyword: String,
        /// What went wrong.
        error: crate::Error,
    },
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BuildError::Unknown(e) => e.fmt(f),
            BuildError::Device {
                location,
                keyword,
                error,
            } => write!(f, "{location}: {keyword}: {error}"),
        }
    }
}

impl std::error::Error for BuildError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            BuildError::Unknown(e) => Some(e),
            BuildError::Device { error, .. } => Some(error),
        }
    }
}

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
        error: BuildError,
    },
}

/// Builds the devices `entries` describe on `conn`, in file order, telling `note` about each.
/// Devices on ports tell `status` (if given) when their port cannot be opened, opens, or is
/// lost (see [`crate::driver::DeviceStatus`]).
///
/// An entry that cannot be served (unknown keyword, a constructor failure) is an error naming
/// the file and line; with `warn_only` (`vrpn_server -warn`) it is reported as
/// [`BuildNote::Skipped`] and left out instead, as C++ does. Entries sharing a name are all
/// built (see [`super::config::name_clashes`] for the ones worth a warning).
pub fn build_devices(
    entries: &[DeviceEntry],
    conn: &Connection,
    warn_only: bool,
    status: Option<StatusSink>,
    note: impl FnMut(BuildNote<'_>),
) -> Result<Vec<Box<dyn ServerDevice>>, BuildError> {
    let cx = match status {
        Some(sink) => BuildContext::with_status(conn, sink),
        None => BuildContext::new(conn),
    };
    build_devices_in(entries, &cx, warn_only, note)
}

/// [`build_devices`] with a prepared context (a device tree other than the system's, for
/// `vrpn_server -devroot`).
pub fn build_devices_in(
    entries: &[DeviceEntry],
    cx: &BuildContext<'_>,
    warn_only: bool,
    mut note: impl FnMut(BuildNote<'_>),
) -> Result<Vec<Box<dyn ServerDevice>>, BuildError> {
    let mut devices: Vec<Box<dyn ServerDevice>> = Vec::new();
    for entry in entries {
        match build_one(entry, cx) {
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

/// The devices of one entry: usually one; a device on several ports runs one per port.
fn build_one(
    entry: &DeviceEntry,
    cx: &BuildContext<'_>,
) -> Result<Vec<Box<dyn ServerDevice>>, BuildError> {
    if let Some(e) = entry.unknown_error() {
        return Err(BuildError::Unknown(e));
    }
    entry.config.build(cx).map_err(|error| BuildError::Device {
        location: entry.location.clone(),
        keyword: entry.keyword.clone(),
        error,
    })
}

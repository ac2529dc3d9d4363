//! What a device tells the program running it about its port: it cannot be opened (and why),
//! it opened, it was lost. The library never prints; `vrpn_server` prints these on its
//! standard error, once per change (a port that stays missing is reported once, not at every
//! retry).

use std::fmt;
use std::io;
use std::rc::Rc;

/// Why a port could not be opened, in the terms an operator acts on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum OpenFailure {
    /// No such file: the device is not plugged in, or the path is wrong.
    NotFound,
    /// The file exists but this user may not open it.
    PermissionDenied,
    /// Another reason, as the system gave it.
    Other(String),
}

impl OpenFailure {
    /// Classifies an open error.
    pub fn from_io(e: &io::Error) -> OpenFailure {
        match e.kind() {
            io::ErrorKind::NotFound => OpenFailure::NotFound,
            io::ErrorKind::PermissionDenied => OpenFailure::PermissionDenied,
            _ => OpenFailure::Other(e.to_string()),
        }
    }
}

impl fmt::Display for OpenFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OpenFailure::NotFound => f.write_str(
                "no such file (is the device plugged in, and is the path in vrpn.cfg right?)",
            ),
            OpenFailure::PermissionDenied => f.write_str(
                "permission denied (serial ports belong to the 'dialout' group: add the user \
                 running the server with 'sudo usermod -aG dialout USER', then log in again)",
            ),
            OpenFailure::Other(why) => f.write_str(why),
        }
    }
}

/// A change in a device's access to its port.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceStatus {
    /// The port cannot be opened; the device tries again every second and says nothing more
    /// until the reason changes or the port opens.
    CannotOpen {
        /// The port, as configured.
        port: String,
        /// Why.
        reason: OpenFailure,
    },
    /// The port opened after it could not be opened or was lost.
    Opened {
        /// The port, as configured.
        port: String,
    },
    /// A USB or input device the configuration names is not plugged in; it is opened as
    /// soon as it appears (hot-plug, no polling).
    Waiting {
        /// What is waited for (`046d:c626`, `"USB Optical Mouse"`).
        device: String,
    },
    /// The open port failed or vanished (unplugged); it is reopened when it comes back.
    Lost {
        /// The port, as configured.
        port: String,
        /// What the system said.
        reason: String,
    },
}

impl fmt::Display for DeviceStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DeviceStatus::CannotOpen { port, reason } => {
                write!(f, "cannot open {port}: {reason}; trying again every second")
            }
            DeviceStatus::Opened { port } => write!(f, "{port} is open"),
            DeviceStatus::Waiting { device } => {
                write!(f, "waiting for {device} to be plugged in")
            }
            DeviceStatus::Lost { port, reason } => {
                write!(
                    f,
                    "{port} failed ({reason}); reopening it when it comes back"
                )
            }
        }
    }
}

/// Receives `(device name, status)` on every change. Set with
/// [`BuildContext::with_status`](super::BuildContext::with_status).
pub type StatusSink = Rc<dyn Fn(&str, &DeviceStatus)>;

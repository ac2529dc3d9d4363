//! Device names: `Tracker0@host`, `Tracker0@host:3884`, `Tracker0@tcp://host:3884`,
//! `Tracker0@x-vrpn://host`, `Tracker0@loopback:`, `Tracker0@file:///abs/log.vrpn` …
//! parsed with the rules of C++ `vrpn_get_connection_by_name`.

use crate::wire::DEFAULT_PORT;

/// Where a device's connection goes.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Location {
    /// A network server: UDP connection request and TCP call-back, or TCP only.
    Net {
        /// Host name or dotted-quad address.
        host: String,
        /// Server port (3883 when none is given).
        port: u16,
        /// Client connects over TCP only (`tcp://` or `tcp:` anywhere in the location).
        tcp_only: bool,
    },
    /// The in-process connection of this process (`loopback:`).
    Loopback,
    /// Replay of a log file (`file:`).
    File {
        /// Path of the log.
        path: String,
    },
}

/// A parsed device name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceName {
    /// Sender name of the device: text before the first `@`.
    pub device: String,
    /// Connection location text exactly as given (connections are shared by this text).
    pub location_text: String,
    /// Parsed location.
    pub location: Location,
}

/// Why a name could not be used.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NameError {
    /// The name as given.
    pub name: String,
    /// What is wrong with it.
    pub problem: NameProblem,
}

/// What is wrong with a device name.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum NameProblem {
    /// No `@` in the name of a remote device.
    NoAt,
    /// Nothing before the `@`.
    EmptyDevice,
    /// Nothing after the `@`.
    EmptyLocation,
    /// The device name is longer than a VRPN name may be.
    DeviceTooLong,
    /// The location after the `@` cannot be used.
    Location(LocationError),
}

impl std::fmt::Display for NameError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "bad VRPN device name {:?}: {}", self.name, self.problem)?;
        if self.problem == NameProblem::NoAt {
            write!(
                f,
                ": a remote device is named DEVICE@HOST, for example \"{}@localhost\"",
                self.name
            )?;
        }
        f.write_str(
            " (expected DEVICE@HOST, DEVICE@HOST:PORT, DEVICE@tcp://HOST:PORT, \
             DEVICE@loopback: or DEVICE@file:PATH)",
        )
    }
}

impl std::fmt::Display for NameProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NameProblem::NoAt => f.write_str("it has no '@'"),
            NameProblem::EmptyDevice => f.write_str("the device name before '@' is empty"),
            NameProblem::EmptyLocation => f.write_str("the location after '@' is empty"),
            NameProblem::DeviceTooLong => f.write_str("the device name is longer than 95 bytes"),
            NameProblem::Location(e) => e.fmt(f),
        }
    }
}

/// Why the location after a name's `@` cannot be used.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum LocationError {
    /// `file:` with no path.
    NoFile,
    /// `x-vrsh:`: remote start over rsh/ssh.
    RemoteStart,
    /// `mpi:`.
    Mpi,
    /// No host name.
    NoHost,
    /// A port that is not a number from 1 to 65535 (the text as given).
    BadPort(String),
}

impl std::fmt::Display for LocationError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LocationError::NoFile => f.write_str("the file: location names no file"),
            LocationError::RemoteStart => {
                f.write_str("x-vrsh: (remote start over rsh/ssh) is not supported")
            }
            LocationError::Mpi => f.write_str("mpi: connections are not supported"),
            LocationError::NoHost => f.write_str("no host name"),
            LocationError::BadPort(p) => write!(f, "port {p:?} is not a number from 1 to 65535"),
        }
    }
}

impl std::error::Error for LocationError {}

impl std::error::Error for NameError {}

const SCHEMES: [&str; 8] = [
    "x-vrpn://",
    "x-vrsh://",
    "x-vrpn:",
    "x-vrsh:",
    "tcp://",
    "tcp:",
    "mpi://",
    "mpi:",
];

impl DeviceName {
    /// Parses `DEVICE@LOCATION`. Device names may contain spaces (`Rigid Body 1@host`).
    pub fn parse(name: &str) -> Result<DeviceName, NameError> {
        let err = |problem: NameProblem| NameError {
            name: name.to_string(),
            problem,
        };
        let (device, location_text) = match (name.find('@'), name.rfind('@')) {
            (Some(first), Some(last)) => (&name[..first], &name[last + 1..]),
            // A bare location (`host:port`) names a connection, as in C++.
            _ => (name, name),
        };
        if device.is_empty() {
            return Err(err(NameProblem::EmptyDevice));
        }
        if location_text.is_empty() {
            return Err(err(NameProblem::EmptyLocation));
        }
        if device.len() > crate::wire::MAX_NAME_LEN {
            return Err(err(NameProblem::DeviceTooLong));
        }
        let location =
            Self::parse_location(location_text).map_err(|e| err(NameProblem::Location(e)))?;
        Ok(DeviceName {
            device: device.to_string(),
            location_text: location_text.to_string(),
            location,
        })
    }

    /// Parses the name of a device to open a remote of: like [`parse`](Self::parse), and the
    /// `@LOCATION` part must be there. (C++ takes a name without `@` for a host name, so
    /// `Tracker0` would fail as "cannot resolve host", hiding what is missing.)
    pub fn parse_remote(name: &str) -> Result<DeviceName, NameError> {
        if !name.contains('@') && !name.is_empty() {
            return Err(NameError {
                name: name.to_string(),
                problem: NameProblem::NoAt,
            });
        }
        Self::parse(name)
    }

    /// Parses the part after `@`.
    pub fn parse_location(loc: &str) -> Result<Location, LocationError> {
        if loc == "loopback:" || loc == "loopback" || loc.starts_with("loopback:") {
            return Ok(Location::Loopback);
        }
        if let Some(rest) = loc.strip_prefix("file:") {
            let path = rest.strip_prefix("//").unwrap_or(rest);
            if path.is_empty() {
                return Err(LocationError::NoFile);
            }
            return Ok(Location::File {
                path: path.to_string(),
            });
        }
        if loc.contains("x-vrsh:") {
            return Err(LocationError::RemoteStart);
        }
        if loc.starts_with("mpi:") {
            return Err(LocationError::Mpi);
        }
        let tcp_only = loc.contains("tcp:");
        let after_scheme = SCHEMES
            .iter()
            .find_map(|s| loc.strip_prefix(s))
            .unwrap_or(loc);
        let host_end = after_scheme.find([':', '/']).unwrap_or(after_scheme.len());
        let host = &after_scheme[..host_end];
        if host.is_empty() {
            return Err(LocationError::NoHost);
        }
        let port = match after_scheme.rfind(':') {
            None => DEFAULT_PORT,
            Some(i) => {
                let digits: String = after_scheme[i + 1..]
                    .chars()
                    .take_while(|c| c.is_ascii_digit())
                    .collect();
                match digits.parse::<u32>() {
                    Ok(p) if (1..=65535).contains(&p) => p as u16,
                    _ => return Err(LocationError::BadPort(after_scheme[i + 1..].to_owned())),
                }
            }
        };
        Ok(Location::Net {
            host: host.to_string(),
            port,
            tcp_only,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn net(name: &str) -> (String, String, u16, bool) {
        let d = DeviceName::parse(name).unwrap();
        match d.location {
            Location::Net {
                host,
                port,
                tcp_only,
            } => (d.device, host, port, tcp_only),
            other => panic!("not net: {other:?}"),
        }
    }

    #[test]
    fn forms_cpp_accepts() {
        assert_eq!(
            net("Tracker0@host"),
            ("Tracker0".into(), "host".into(), 3883, false)
        );
        assert_eq!(net("Tracker0@host:3884").2, 3884);
        assert_eq!(
            net("Tracker0@x-vrpn://host:3884"),
            ("Tracker0".into(), "host".into(), 3884, false)
        );
        assert_eq!(net("Tracker0@x-vrpn:host").2, 3883);
        assert_eq!(
            net("Tracker0@tcp://host:3884"),
            ("Tracker0".into(), "host".into(), 3884, true)
        );
        assert!(net("Tracker0@tcp:host:3884").3);
        assert_eq!(net("Rigid Body 1@127.0.0.1").0, "Rigid Body 1");
        assert_eq!(net("a@b@host").1, "host");
        assert_eq!(
            DeviceName::parse("T@loopback:").unwrap().location,
            Location::Loopback
        );
        assert_eq!(
            DeviceName::parse("T@file:///abs/x.vrpn").unwrap().location,
            Location::File {
                path: "/abs/x.vrpn".into()
            }
        );
        assert_eq!(
            DeviceName::parse("T@file:rel.vrpn").unwrap().location,
            Location::File {
                path: "rel.vrpn".into()
            }
        );
    }

    #[test]
    fn clear_errors() {
        let e = DeviceName::parse("Tracker0@host:abc").unwrap_err();
        assert!(e.to_string().contains("port"), "{e}");
        assert!(DeviceName::parse("@host").is_err());
        assert!(DeviceName::parse("T@").is_err());
        assert!(DeviceName::parse("T@tcp://:3883").is_err());
        // A device name without `@HOST` says so (C++ would try to resolve "Tracker0" as a
        // host); a bare location still names a connection.
        let e = DeviceName::parse_remote("Tracker0")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no '@'") && e.contains("Tracker0@localhost"),
            "{e}"
        );
        assert!(!e.contains("resolve"), "{e}");
        assert_eq!(net("127.0.0.1:3884").2, 3884);
    }
}

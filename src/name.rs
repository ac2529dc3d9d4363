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
    pub problem: String,
}

impl std::fmt::Display for NameError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "bad VRPN device name {:?}: {} (expected DEVICE@HOST, DEVICE@HOST:PORT, \
             DEVICE@tcp://HOST:PORT, DEVICE@loopback: or DEVICE@file:PATH)",
            self.name, self.problem
        )
    }
}

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
        let err = |problem: &str| NameError {
            name: name.to_string(),
            problem: problem.to_string(),
        };
        let (device, location_text) = match (name.find('@'), name.rfind('@')) {
            (Some(first), Some(last)) => (&name[..first], &name[last + 1..]),
            // A bare location (`host:port`) names a connection, as in C++.
            _ => (name, name),
        };
        if device.is_empty() {
            return Err(err("the device name before '@' is empty"));
        }
        if location_text.is_empty() {
            return Err(err("the location after '@' is empty"));
        }
        if device.len() > crate::wire::MAX_NAME_LEN {
            return Err(err("the device name is longer than 95 bytes"));
        }
        let location = Self::parse_location(location_text).map_err(|p| err(&p))?;
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
                problem: format!(
                    "it has no '@': a remote device is named DEVICE@HOST, for example \
                     \"{name}@localhost\""
                ),
            });
        }
        Self::parse(name)
    }

    /// Parses the part after `@`.
    pub fn parse_location(loc: &str) -> Result<Location, String> {
        if loc == "loopback:" || loc == "loopback" || loc.starts_with("loopback:") {
            return Ok(Location::Loopback);
        }
        if let Some(rest) = loc.strip_prefix("file:") {
            let path = rest.strip_prefix("//").unwrap_or(rest);
            if path.is_empty() {
                return Err("the file: location names no file".into());
            }
            return Ok(Location::File {
                path: path.to_string(),
            });
        }
        if loc.contains("x-vrsh:") {
            return Err("x-vrsh: (remote start over rsh/ssh) is not supported".into());
        }
        if loc.starts_with("mpi:") {
            return Err("mpi: connections are not supported".into());
        }
        let tcp_only = loc.contains("tcp:");
        let after_scheme = SCHEMES
            .iter()
            .find_map(|s| loc.strip_prefix(s))
            .unwrap_or(loc);
        let host_end = after_scheme.find([':', '/']).unwrap_or(after_scheme.len());
        let host = &after_scheme[..host_end];
        if host.is_empty() {
            return Err("no host name".into());
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
                    _ => {
                        return Err(format!(
                            "port {:?} is not a number from 1 to 65535",
                            &after_scheme[i + 1..]
                        ))
                    }
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

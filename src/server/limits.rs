//! What a program may publish on a server connection through the bindings (the C ABI and the
//! Python module): the device counts `vrpn.cfg` accepts, names a client can open, and one
//! device of each interface per name.
//!
//! The configuration file is checked by [`super::config`]; a program that makes device servers
//! by hand (`vrpn_tracker_server_new`, `vrpn.TrackerServer(...)`) is checked here against the
//! same bounds, so that no entry point lets a typo allocate gigabytes or publish a device no
//! client can name.

use std::cell::RefCell;
use std::rc::{Rc, Weak};

use super::config::{MAX_BUTTONS, MAX_CHANNELS, MAX_DIALS, MAX_TRACKER_SENSORS};
use crate::wire::MAX_NAME_LEN;

/// A device-server interface, with the count its constructor takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interface {
    /// A tracker: 1 to [`MAX_TRACKER_SENSORS`] sensors.
    Tracker,
    /// A button device: 1 to [`MAX_BUTTONS`] buttons.
    Button,
    /// An analog device: 1 to [`MAX_CHANNELS`] channels.
    Analog,
    /// A dial device: 1 to [`MAX_DIALS`] dials.
    Dial,
    /// A text sender (no count).
    Text,
}

impl Interface {
    /// The interface in words ("tracker", "button device", …).
    pub fn noun(self) -> &'static str {
        match self {
            Interface::Tracker => "tracker",
            Interface::Button => "button device",
            Interface::Analog => "analog device",
            Interface::Dial => "dial device",
            Interface::Text => "text sender",
        }
    }

    /// "a tracker", "an analog device", …
    pub fn with_article(self) -> String {
        let noun = self.noun();
        let article = if noun.starts_with(['a', 'e', 'i', 'o', 'u']) {
            "an"
        } else {
            "a"
        };
        format!("{article} {noun}")
    }

    /// What its count counts ("sensors", "buttons", …).
    pub fn unit(self) -> &'static str {
        match self {
            Interface::Tracker => "sensors",
            Interface::Button => "buttons",
            Interface::Analog => "channels",
            Interface::Dial => "dials",
            Interface::Text => "messages",
        }
    }

    /// The largest count accepted (the same as in `vrpn.cfg`).
    pub fn max_count(self) -> usize {
        let max = match self {
            Interface::Tracker => MAX_TRACKER_SENSORS,
            Interface::Button => MAX_BUTTONS,
            Interface::Analog => MAX_CHANNELS,
            Interface::Dial => MAX_DIALS,
            Interface::Text => 0,
        };
        max as usize
    }
}

/// Why a device server cannot be made.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PublishError {
    /// The count is outside 1..=[`Interface::max_count`].
    Count(String),
    /// The name cannot be opened by a client (empty, `@`, too long, NUL).
    Name(String),
    /// A device of the same interface already has this name on this server.
    Duplicate(String),
}

impl std::fmt::Display for PublishError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PublishError::Count(t) | PublishError::Name(t) | PublishError::Duplicate(t) => {
                f.write_str(t)
            }
        }
    }
}

impl std::error::Error for PublishError {}

/// Checks the count a device server is made with; `n` is whatever integer the caller was
/// given (negative and huge values included), `shown` its text for the message when it did
/// not even fit an `i128`.
pub fn check_count(kind: Interface, n: Option<i128>, shown: &str) -> Result<usize, PublishError> {
    let max = kind.max_count();
    match n {
        Some(n) if n >= 1 && n <= max as i128 => Ok(n as usize),
        _ => Err(PublishError::Count(format!(
            "{} has 1 to {max} {} (the limit vrpn.cfg applies too), got {shown}",
            kind.with_article(),
            kind.unit()
        ))),
    }
}

/// Checks a name a server publishes a device under: clients open `NAME@host`, so it cannot be
/// empty or contain `@`, and VRPN names are at most [`MAX_NAME_LEN`] bytes.
pub fn check_name(name: &str) -> Result<(), PublishError> {
    let problem = if name.is_empty() {
        "a device name cannot be empty".to_owned()
    } else if name.contains('@') {
        format!(
            "device name {name:?} must not contain '@' (clients connect to NAME@host, so the \
             name itself cannot have one)"
        )
    } else if name.contains('\0') {
        format!("device name {name:?} contains a NUL character")
    } else if name.len() > MAX_NAME_LEN {
        format!(
            "device name {name:?} is {} bytes long; VRPN names are at most {MAX_NAME_LEN}",
            name.len()
        )
    } else {
        return Ok(());
    };
    Err(PublishError::Name(problem))
}

/// The names published on one server connection, one device per interface and name: a
/// second tracker named `Tracker0` would interleave its reports with the first one's, and no
/// client could tell them apart. (`vrpn.cfg` runs such a pair with a warning, as C++ does; a
/// program asking for it is refused.) A name is free again once its [`Claim`] is dropped.
#[derive(Default)]
pub struct Published {
    names: RefCell<Vec<(Interface, String, Weak<()>)>>,
}

/// Holds a published name; dropping it (with the device server) frees the name.
#[derive(Debug)]
pub struct Claim {
    _token: Rc<()>,
}

impl Published {
    /// Checks `name` and claims it for a device of `kind`.
    pub fn claim(&self, kind: Interface, name: &str) -> Result<Claim, PublishError> {
        check_name(name)?;
        let mut names = self.names.borrow_mut();
        names.retain(|(_, _, alive)| alive.strong_count() > 0);
        if names.iter().any(|(k, n, _)| *k == kind && n == name) {
            return Err(PublishError::Duplicate(format!(
                "{} named {name:?} already exists on this server (a client could not tell \
                 their reports apart); close it first or choose another name",
                kind.with_article()
            )));
        }
        let token = Rc::new(());
        names.push((kind, name.to_owned(), Rc::downgrade(&token)));
        Ok(Claim { _token: token })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_bounded_as_in_the_config_file() {
        assert_eq!(
            check_count(Interface::Tracker, Some(1024), "1024"),
            Ok(1024)
        );
        for (n, shown) in [
            (Some(0), "0"),
            (Some(1025), "1025"),
            (Some(-1), "-1"),
            (None, "2**200"),
        ] {
            let e = check_count(Interface::Tracker, n, shown)
                .unwrap_err()
                .to_string();
            assert_eq!(
                e,
                format!(
                    "a tracker has 1 to 1024 sensors (the limit vrpn.cfg applies too), got {shown}"
                )
            );
        }
        assert!(check_count(Interface::Button, Some(257), "257").is_err());
        assert_eq!(check_count(Interface::Button, Some(256), "256"), Ok(256));
        let e = check_count(Interface::Analog, Some(129), "129").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("an analog device has 1 to 128 channels"),
            "{e}"
        );
        assert!(check_count(Interface::Dial, Some(129), "129").is_err());
        assert!(check_count(Interface::Dial, Some(i128::from(u64::MAX)), "x").is_err());
    }

    #[test]
    fn names_clients_cannot_open_are_refused() {
        assert!(check_name("Rigid Body 1").is_ok());
        for bad in ["", "T@host", "a\0b", &"x".repeat(MAX_NAME_LEN + 1)] {
            assert!(
                matches!(check_name(bad), Err(PublishError::Name(_))),
                "{bad:?}"
            );
        }
        assert!(check_name(&"x".repeat(MAX_NAME_LEN)).is_ok());
    }

    #[test]
    fn one_device_per_interface_and_name_until_it_goes() {
        let p = Published::default();
        let first = p.claim(Interface::Tracker, "T").unwrap();
        let e = p.claim(Interface::Tracker, "T").unwrap_err();
        assert!(matches!(e, PublishError::Duplicate(_)));
        assert!(
            e.to_string()
                .contains(r#"a tracker named "T" already exists"#),
            "{e}"
        );
        // Another interface under the same name is a normal VRPN device (tracker + buttons).
        let _buttons = p.claim(Interface::Button, "T").unwrap();
        drop(first);
        assert!(p.claim(Interface::Tracker, "T").is_ok());
    }
}

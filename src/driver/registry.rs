//! The registry: what a driver declares so that `vrpn.cfg` can name it.
//!
//! Each driver folder exports one [`Driver`] (its keywords and its line parser); the server
//! finds an entry's driver by keyword in one list ([`crate::drivers::REGISTRY`]), hands it the
//! [`ConfigLine`], and later asks the parsed [`DeviceSpec`] what it serves and to build its
//! running devices. Nothing outside the folder knows the driver's types.

use std::any::Any;
use std::fmt;

use crate::config::{ConfigError, ConfigLine};
use crate::connection::Connection;
use crate::devices::ServerDevice;
use crate::error::Error;

/// One kind of device (or a family sharing a parser) that `vrpn.cfg` lines can configure.
pub struct Driver {
    /// The keywords it serves, spelled as in `vrpn.cfg` (matched exactly, case-sensitive).
    pub keywords: &'static [&'static str],
    /// Parses an entry whose keyword is one of [`keywords`](Self::keywords): the first line
    /// and any continuation lines it reads through the [`ConfigLine`].
    pub parse: fn(&mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError>,
    /// Explanations for keywords that are *not* served but that a user of this driver might
    /// write (a C++ keyword served another way, a common misspelling).
    pub hints: &'static [Hint],
}

impl fmt::Debug for Driver {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Driver")
            .field("keywords", &self.keywords)
            .finish_non_exhaustive()
    }
}

/// An explanation given when an unknown keyword is met.
#[derive(Clone, Copy, Debug)]
pub struct Hint {
    /// The keyword this server does not know.
    pub keyword: &'static str,
    /// What to write instead, appended to "unknown device type KEYWORD: ".
    pub text: &'static str,
}

/// The driver serving `keyword` in `registry`, if any.
pub fn find(registry: &[&'static Driver], keyword: &str) -> Option<&'static Driver> {
    registry
        .iter()
        .copied()
        .find(|d| d.keywords.contains(&keyword))
}

/// A parsed entry: the device's typed configuration, which knows what it serves and how to
/// build itself. Each driver's configuration struct implements it.
///
/// Code that needs the concrete type (tests, tools) gets it back with
/// [`downcast_ref`](trait.DeviceSpec.html#method.downcast_ref).
pub trait DeviceSpec: AsAny + fmt::Debug {
    /// The device's name (the first it serves under).
    fn name(&self) -> &str;

    /// Every (name, interface) pair the entry serves, in the order the devices are built:
    /// its own interfaces under its name, then those of any sub-devices (a Fastrak's wands)
    /// under theirs. Every device can also send text messages; only a device that exists to
    /// send them counts as serving [`Interface::Text`].
    fn served(&self) -> Vec<Served<'_>>;

    /// Every name the entry publishes under (its own first), from [`served`](Self::served).
    fn device_names(&self) -> Vec<&str> {
        let mut names: Vec<&str> = Vec::new();
        for s in self.served() {
            if !names.contains(&s.name) {
                names.push(s.name);
            }
        }
        if names.is_empty() {
            names.push(self.name());
        }
        names
    }

    /// Builds the running devices: usually one; a device on several ports runs one per port.
    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error>;
}

impl dyn DeviceSpec {
    /// The concrete configuration, if it is a `T`.
    pub fn downcast_ref<T: DeviceSpec>(&self) -> Option<&T> {
        self.as_any().downcast_ref::<T>()
    }
}

/// Any `'static` type as [`Any`], so that [`DeviceSpec`] can be downcast (implemented for
/// every type: a driver never writes it).
pub trait AsAny: Any {
    /// `self` as `&dyn Any`.
    fn as_any(&self) -> &dyn Any;
}

impl<T: Any> AsAny for T {
    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// What a [`DeviceSpec`] builds its devices with: the server's connection, where the
/// devices report their state to the program running them, and where USB and input devices
/// are found (the system's `/sys` and `/dev`, or a simulator's tree).
pub struct BuildContext<'a> {
    conn: &'a Connection,
    status: Option<super::status::StatusSink>,
    tree: crate::hid::DeviceTree,
    hub: std::cell::OnceCell<crate::hid::DeviceHub>,
}

impl<'a> BuildContext<'a> {
    /// Devices on `conn`, whose state changes go nowhere but to the clients.
    pub fn new(conn: &'a Connection) -> BuildContext<'a> {
        BuildContext {
            conn,
            status: None,
            tree: crate::hid::DeviceTree::system(),
            hub: std::cell::OnceCell::new(),
        }
    }

    /// Devices that also tell `sink` about their state changes (a port that cannot be
    /// opened, a device lost and back), for the program to show.
    pub fn with_status(conn: &'a Connection, sink: super::status::StatusSink) -> BuildContext<'a> {
        BuildContext {
            status: Some(sink),
            ..BuildContext::new(conn)
        }
    }

    /// HID and input devices are looked for in `tree` (`vrpn_server -devroot`), not the
    /// system's.
    pub fn with_device_tree(mut self, tree: crate::hid::DeviceTree) -> BuildContext<'a> {
        self.tree = tree;
        self.hub = std::cell::OnceCell::new();
        self
    }

    /// What the HID and input devices built here share: the device tree, one hot-plug
    /// watcher waiting in the connection's reactor, which nodes are taken.
    pub fn hub(&self) -> &crate::hid::DeviceHub {
        self.hub.get_or_init(|| {
            crate::hid::DeviceHub::new(self.tree.clone(), self.conn.reactor().as_ref())
        })
    }

    /// The server's connection.
    pub fn conn(&self) -> &'a Connection {
        self.conn
    }

    /// Where state changes go, if anywhere but to the clients.
    pub fn status(&self) -> Option<&super::status::StatusSink> {
        self.status.as_ref()
    }
}

/// A VRPN device interface: what a client opens a remote of (`TrackerRemote`, `ButtonRemote`,
/// …) to read a device. One name may carry several interfaces, since each has its own message
/// types; two devices serving the same interface under one name send indistinguishable reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Interface {
    /// Poses, velocities and accelerations (`vrpn_Tracker`).
    Tracker,
    /// Button presses (`vrpn_Button`).
    Button,
    /// Analog channels (`vrpn_Analog`).
    Analog,
    /// Dial turns (`vrpn_Dial`).
    Dial,
    /// Text messages as the device's purpose (`vrpn_Text_Example`).
    Text,
    /// Analog outputs a client sets (`vrpn_Analog_Output`).
    AnalogOutput,
    /// Poses a client requests (`vrpn_Poser`).
    Poser,
    /// Force feedback (`vrpn_ForceDevice`).
    ForceDevice,
    /// Image streams (`vrpn_Imager`).
    Imager,
}

impl Interface {
    /// The interface in lower case, as messages name it (`tracker`, `button`, …).
    pub fn label(self) -> &'static str {
        match self {
            Interface::Tracker => "tracker",
            Interface::Button => "button",
            Interface::Analog => "analog",
            Interface::Dial => "dial",
            Interface::Text => "text sender",
            Interface::AnalogOutput => "analog output",
            Interface::Poser => "poser",
            Interface::ForceDevice => "force device",
            Interface::Imager => "imager",
        }
    }
}

impl fmt::Display for Interface {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())
    }
}

/// One interface an entry serves, and the name it serves it under.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Served<'a> {
    /// The device name clients open (`NAME@host`).
    pub name: &'a str,
    /// The interface.
    pub interface: Interface,
}

impl<'a> Served<'a> {
    /// `name` serving each of `interfaces`, in order.
    pub fn all(name: &'a str, interfaces: &[Interface]) -> Vec<Served<'a>> {
        interfaces
            .iter()
            .map(|&interface| Served { name, interface })
            .collect()
    }
}

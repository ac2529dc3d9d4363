//! The framework every hardware driver is built on: how `vrpn.cfg` names a driver
//! ([`registry`]), the one device lifecycle every driver shares ([`lifecycle`]), how a device
//! tells the program about its port ([`status`]), and text messages without allocation
//! ([`text`]).
//!
//! A driver lives in its folder, `drivers/NAME/`, and is known to the rest of the crate by one
//! line of [`crate::drivers::REGISTRY`]. docs/DRIVERS.md ("Adding a driver") walks through the
//! files to write and the tests every driver has; `drivers/dyna/` is the example to copy.
//!
//! ```text
//! vrpn.cfg line ──▶ Driver::parse ──▶ DeviceSpec ──build──▶ serve(Protocol) ──▶ ServerDevice
//!                   (registry)        (the driver's         Lifecycle<P> on a port in the
//!                                      config struct)       server's one reactor
//! ```

pub mod framing;
pub mod lifecycle;
pub mod registry;
pub mod status;
pub mod text;
pub mod udp;

pub use lifecycle::{
    Cx, Lifecycle, Pause, Phase, Protocol, Recovery, Reset, Retry, Stats, Supervision, Texts,
};
pub use registry::{BuildContext, DeviceSpec, Driver, Hint, Interface, Served};
pub use status::{DeviceStatus, OpenFailure, StatusSink};

use crate::devices::ServerDevice;
use crate::serial::{SerialDevice, SerialDriver};

/// The running device for `protocol`: the shared [`Lifecycle`] under the device's `name`, on
/// the port at `path`, waiting in the server's reactor. What a [`DeviceSpec::build`] returns
/// for a device on one port.
pub fn serve<P: Protocol + 'static>(
    name: &str,
    path: &str,
    protocol: P,
    cx: &BuildContext<'_>,
) -> Box<dyn ServerDevice> {
    serve_port(path, Lifecycle::new(name, protocol, cx.conn()), cx)
}

/// The running device for a driver that is not a [`Protocol`] (one port of a device spread
/// over several, which keeps its own state across them): the port at `path` in the server's
/// reactor, reopened when it fails, its state changes told as [`serve`] tells them.
pub fn serve_port<D: SerialDriver + 'static>(
    path: &str,
    driver: D,
    cx: &BuildContext<'_>,
) -> Box<dyn ServerDevice> {
    let mut device = SerialDevice::new(path, driver, cx.conn());
    if let Some(sink) = cx.status() {
        device.report_status_to(sink.clone());
    }
    Box::new(device)
}

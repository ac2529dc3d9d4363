//! USB HID devices and Linux input devices, read straight from the kernel: hidraw nodes for
//! raw HID reports, evdev nodes for input events, sysfs for finding them, and the kernel's
//! uevent socket for hot-plug. No hidapi, no libusb, no C.
//!
//! - [`sysfs`]: enumeration (vendor, product, interface, serial, name, capabilities) under a
//!   [`DeviceTree`] whose roots are injectable, so tests use a fake tree (module `fake`, with the `sim` feature).
//! - [`uevent`] parses kernel uevent messages; [`hotplug`] listens for them in the reactor.
//! - [`source`]: an open hidraw node (one report per `read`, output reports by `write`,
//!   feature reports by ioctl, [`ioctl`]) or a simulator's socket pair standing in for one;
//!   [`evdev`](crate::drivers::evdev): `input_event` records from an event node or a pipe.
//! - [`driver`]: the sans-IO [`HidDriver`] interface and how a driver names the nodes it
//!   wants ([`HidMatch`]); [`device`]: [`HidDevice`], which runs a driver as a server device,
//!   waiting for absent devices and picking up unplugged ones when they return.
//!
//! Tests here cannot create kernel devices (no `/dev/uhid` or `/dev/uinput`): everything above
//! the open call is exercised on simulators; the hidraw and evdev open path itself is not.

pub mod descriptor;
pub mod device;
pub mod driver;
#[cfg(any(test, feature = "sim"))]
pub mod fake;
pub mod hotplug;
pub mod input_event;
pub mod ioctl;
pub mod list;
#[cfg(test)]
pub(crate) mod rig;
pub mod source;
pub mod sysfs;
pub mod uevent;

pub use device::{serve, DeviceHub, HidDevice};
pub use driver::{HidDriver, HidMatch, HidOp, HidOps, InterfaceRule, NodeInfo, NodeKind, Select};
pub use sysfs::DeviceTree;

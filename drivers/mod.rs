//! Hardware drivers, one folder per device, and the registry: the one list of every device
//! kind a `vrpn.cfg` line can name.
//!
//! Each folder holds the driver's `vrpn.cfg` line (a [`DeviceSpec`](crate::driver::DeviceSpec)
//! and its parser), its protocol (run by the shared
//! [`Lifecycle`](crate::driver::Lifecycle)), and the device simulator its tests use (a
//! `sim::DeviceModel`, built with the `sim` feature). Adding a driver is
//! a new folder plus one line in [`REGISTRY`]; docs/DRIVERS.md ("Adding a driver") says what
//! goes in the folder.

use crate::driver::Driver;

pub mod cerealbox;
pub mod dyna;
pub mod fastrak;
pub mod flock;
pub mod joylin;
pub mod liberty;
pub mod magellan;
pub mod threespace;

/// Every device kind the server knows, by its `vrpn.cfg` keywords. The server finds an
/// entry's parser here; a keyword no entry serves is an error naming it.
pub static REGISTRY: &[&Driver] = &[
    // The built-in example devices.
    &crate::devices::examples::TRACKER_NULL,
    &crate::devices::examples::TRACKER_SPIN,
    &crate::devices::examples::BUTTON_EXAMPLE,
    &crate::devices::examples::DIAL_EXAMPLE,
    &crate::devices::examples::ANALOG_EXAMPLE,
    &crate::devices::examples::TEXT_EXAMPLE,
    // Layered devices (clients of other devices).
    &crate::layered::config::ANALOG_FLY,
    &crate::layered::config::BUTTON_FLY,
    // Hardware, one folder each.
    &cerealbox::DRIVER,
    &dyna::DRIVER,
    &fastrak::DRIVER,
    &flock::DRIVER,
    &joylin::DRIVER,
    &liberty::DRIVER,
    &magellan::DRIVER,
    &threespace::DRIVER,
];

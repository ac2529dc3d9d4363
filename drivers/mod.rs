//! Hardware drivers, one folder per device: the sans-IO driver (a [`SerialDriver`]) and the
//! device simulator its tests use (a [`DeviceModel`]).
//!
//! [`SerialDriver`]: crate::serial::SerialDriver
//! [`DeviceModel`]: crate::serial::testing::DeviceModel

pub mod cerealbox;
pub mod controls;
pub mod dyna;
pub mod evdev;
pub mod fastrak;
pub mod flock;
pub mod gamepads;
pub mod glove5dt_usb;
#[cfg(test)]
mod hid_e2e;
pub mod hid_pad;
pub mod hid_quat;
pub mod hid_trackers;
pub mod hmd;
pub mod joylin;
pub mod magellan;
pub mod spacemouse;
mod stack_text;
pub mod xkeys;

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

pub mod adbox;
pub mod atmel;
pub mod biosciences;
pub mod button_5dt_server;
pub mod cerealbox;
pub mod controls;
pub mod crossbow;
pub mod dead_reckoning;
pub mod dtrack;
pub mod dyna;
pub mod evdev;
pub mod fastrak;
pub mod flock;
pub mod gamepads;
pub mod gametrak;
pub mod glove5dt;
pub mod glove5dt16;
pub mod glove5dt_usb;
pub mod gps;
#[cfg(test)]
mod hid_config_tests;
#[cfg(test)]
mod hid_e2e;
pub mod hid_generic;
pub mod hid_pad;
pub mod hid_quat;
pub mod hid_trackers;
pub mod hmd;
pub mod idea;
pub mod imager_stream_buffer;
pub mod immersionbox;
pub mod imu_magnetometer;
pub mod imu_simple_combiner;
pub mod inertiamouse;
pub mod joyfly;
pub mod joylin;
pub mod jsonnet;
pub mod liberty;
pub mod magellan;
pub mod nikon;
pub mod one_euro;
pub mod orb;
pub mod parport_python;
pub mod pinchglove;
pub mod polaris;
pub mod poser_analog;
pub mod radamec;
pub mod serialmouse;
pub mod sgibox;
pub mod spaceball;
pub mod spacemouse;
pub mod streaming_arduino;
pub mod tek4662;
pub mod threedmouse;
pub mod threespace;
pub mod tng3;
pub mod uncjoystick;
pub mod vpjoystick;
pub mod wanda;
pub mod wiimote_head;
pub mod xkeys;
pub mod yei;
pub mod zaber;

/// For each USB or input device family: the `vrpn.cfg` line that would serve a node, if
/// the family knows it (`vrpn_server --list-devices`). The generic HID driver comes last.
pub static SUGGESTERS: &[fn(&crate::hid::NodeInfo) -> Option<String>] = &[
    spacemouse::suggest,
    xkeys::suggest,
    gamepads::suggest,
    controls::suggest,
    glove5dt_usb::suggest,
    hmd::suggest,
    hid_trackers::suggest,
    hid_generic::suggest,
    evdev::suggest,
];

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
    &one_euro::DRIVER,
    &dead_reckoning::DRIVER,
    &imu_magnetometer::DRIVER,
    &imu_simple_combiner::DRIVER,
    &gametrak::DRIVER,
    &button_5dt_server::DRIVER,
    &poser_analog::DRIVER,
    &joyfly::DRIVER,
    &wiimote_head::DRIVER,
    // Logging and relaying other servers' devices.
    &crate::devices::aux_logger::config::AUX_LOGGER,
    &crate::forward::relay::config::RELAY,
    &imager_stream_buffer::DRIVER,
    // Hardware, one folder each.
    &adbox::DRIVER,
    &atmel::DRIVER,
    &cerealbox::DRIVER,
    &crossbow::DRIVER,
    &dyna::DRIVER,
    &dtrack::DRIVER,
    &jsonnet::DRIVER,
    &fastrak::DRIVER,
    &flock::DRIVER,
    &gps::DRIVER,
    &idea::DRIVER,
    &immersionbox::DRIVER,
    &inertiamouse::DRIVER,
    &joylin::DRIVER,
    &liberty::DRIVER,
    &magellan::DRIVER,
    &nikon::DRIVER,
    &biosciences::DRIVER,
    &glove5dt16::DRIVER,
    &glove5dt::DRIVER,
    &orb::DRIVER,
    &spaceball::DRIVER,
    &streaming_arduino::DRIVER,
    &tek4662::DRIVER,
    &zaber::DRIVER,
    &pinchglove::DRIVER,
    &polaris::DRIVER,
    &parport_python::DRIVER,
    &radamec::DRIVER,
    &serialmouse::DRIVER,
    &sgibox::DRIVER,
    &threedmouse::DRIVER,
    &threespace::DRIVER,
    &tng3::DRIVER,
    &uncjoystick::DRIVER,
    &vpjoystick::DRIVER,
    &wanda::DRIVER,
    &yei::DRIVER,
    // USB HID devices (hidraw) and Linux input devices (evdev).
    &spacemouse::DRIVER,
    &xkeys::DRIVER,
    &gamepads::DRIVER,
    &controls::DRIVER,
    &glove5dt_usb::DRIVER,
    &hmd::DRIVER,
    &hid_trackers::DRIVER,
    &evdev::DRIVER,
    &hid_generic::DRIVER,
];

/// The simulators `vrpn_device_sim` can run (the `sim` feature): a driver with a simulator
/// adds its `sim::SIMULATOR` here.
#[cfg(feature = "sim")]
pub static SIMULATORS: &[&crate::sim::Simulator] = &[
    &adbox::sim::SIMULATOR,
    &atmel::sim::SIMULATOR,
    &biosciences::sim::SIMULATOR,
    &cerealbox::sim::SIMULATOR,
    &crossbow::sim::SIMULATOR,
    &dyna::sim::SIMULATOR,
    &fastrak::sim::SIMULATOR,
    &flock::sim::SIMULATOR,
    &glove5dt::sim::SIMULATOR,
    &glove5dt16::sim::SIMULATOR,
    &gps::sim::SIMULATOR,
    &idea::sim::SIMULATOR,
    &immersionbox::sim::SIMULATOR,
    &inertiamouse::sim::SIMULATOR,
    &joylin::sim::SIMULATOR,
    &liberty::sim::SIMULATOR,
    &magellan::sim::SIMULATOR,
    &serialmouse::sim::SIMULATOR,
    &vpjoystick::sim::SIMULATOR,
    &nikon::sim::SIMULATOR,
    &orb::sim::SIMULATOR,
    &pinchglove::sim::SIMULATOR,
    &radamec::sim::SIMULATOR,
    &sgibox::sim::SIMULATOR,
    &spaceball::sim::SIMULATOR,
    &streaming_arduino::sim::SIMULATOR,
    &tek4662::sim::SIMULATOR,
    &threedmouse::sim::SIMULATOR,
    &threespace::sim::SIMULATOR,
    &tng3::sim::SIMULATOR,
    &uncjoystick::sim::SIMULATOR,
    &wanda::sim::SIMULATOR,
    &zaber::sim::SIMULATOR,
    &yei::sim::SIMULATOR,
    &yei::sim::SIMULATOR_WIRELESS,
];

#[cfg(all(test, feature = "sim"))]
mod tests {
    use super::SIMULATORS;
    use crate::server::config::parse_str;

    /// Every driver folder whose simulator is a serial device model is in the catalog of
    /// `vrpn_device_sim`, under the folder's name, with a `vrpn.cfg` line that parses. (The
    /// Polaris is not: its line is followed by the names of tool files that must exist.)
    #[test]
    fn every_serial_simulator_is_in_the_catalog() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("drivers");
        let mut missing = Vec::new();
        for entry in std::fs::read_dir(dir).unwrap() {
            let entry = entry.unwrap();
            let Ok(text) = std::fs::read_to_string(entry.path().join("sim.rs")) else {
                continue;
            };
            let name = entry.file_name().into_string().unwrap();
            if text.contains("impl DeviceModel for")
                && name != "polaris"
                && !SIMULATORS.iter().any(|s| s.name == name)
            {
                missing.push(name);
            }
        }
        assert!(missing.is_empty(), "not in SIMULATORS: {missing:?}");
        for (i, s) in SIMULATORS.iter().enumerate() {
            assert!(
                SIMULATORS[..i].iter().all(|o| o.name != s.name),
                "{} twice",
                s.name
            );
            let line = format!("{}\n", s.config_line("/dev/ttyS0", s.baud));
            let entries = parse_str(&line, "catalog.cfg")
                .unwrap_or_else(|e| panic!("{}: {line}: {e}", s.name));
            assert_eq!(entries.len(), 1, "{}", s.name);
        }
    }
}

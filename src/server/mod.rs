//! The generic VRPN server (`vrpn_server`): configuration file, command-line options, the
//! table from configuration keyword to device, and the server loop.

pub mod config;
pub mod factory;
pub mod limits;
pub mod options;
pub mod run;

pub use factory::{build_devices, build_devices_in, BuildError, BuildNote};
pub use options::{parse_args, OptionError, ServerCommand, ServerOptions, SleepPolicy};
pub use run::{raise_descriptor_limit, ServerLoop};

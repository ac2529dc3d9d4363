//! VRPN, the Virtual-Reality Peripheral Network, in Rust.

#![warn(missing_docs)]

pub mod server;
pub mod time;
pub mod wire;

pub use time::TimeVal;

//! VRPN, the Virtual-Reality Peripheral Network, in Rust.

#![warn(missing_docs)]

pub mod log;
pub mod time;
pub mod wire;

pub use time::TimeVal;

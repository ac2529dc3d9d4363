//! Moving messages between connections: forwarders (C++ `vrpn_ConnectionForwarder`,
//! `vrpn_StreamForwarder`), remote-controlled forwarding (C++ `vrpn_Forwarder_Brain`:
//! [`ForwarderController`] and [`ForwarderServer`]), and the [`Relay`] that re-serves devices
//! of unreachable servers.

pub mod brain;
pub mod forwarder;
pub mod relay;

pub use brain::{ForwarderController, ForwarderServer};
pub use forwarder::{ConnectionForwarder, ForwardCounts, StreamForwarder};
pub use relay::Relay;

//! VRPN, the Virtual-Reality Peripheral Network, in Rust.
//!
//! Wire-compatible with C++ VRPN 07.x in both directions, synchronous (no async runtime, no
//! threads) and allocation-free once a connection is set up.
//!
//! # The complete program
//!
//! Open a tracker, register a callback, call `mainloop()` once per frame:
//!
//! ```no_run
//! use vrpn::TrackerRemote;
//!
//! fn main() -> Result<(), vrpn::Error> {
//!     let tracker = TrackerRemote::new("Tracker0@localhost")?;
//!     tracker.on_pose(|p| {
//!         println!("sensor {}: pos {:?} quat {:?}", p.sensor, p.pos, p.quat);
//!     });
//!     loop {
//!         tracker.mainloop()?;
//!         std::thread::sleep(std::time::Duration::from_millis(1));
//!     }
//! }
//! ```
//!
//! # Layers
//!
//! Bytes flow one way through the crate, each layer a module:
//!
//! - [`wire`]: the pure codec over byte slices (header, cookie, descriptions, payloads).
//! - [`connection`]: names, handlers, class of service, the public [`Connection`].
//! - `net`: the mio shell that moves bytes between sockets and endpoints.
//! - [`devices`]: tracker (and more), each a server half and a remote half.
//! - [`server`]: the `vrpn_server` loop.

#![warn(missing_docs)]

pub mod clock_sync;
pub mod connection;
pub mod devices;
pub mod dispatch;
#[path = "../drivers/mod.rs"]
pub mod drivers;
mod error;
#[doc(hidden)]
pub mod fuzzing;
pub mod layered;
pub mod log;
pub mod name;
mod net;
pub mod serial;
pub mod server;
pub mod time;
pub mod wire;

pub use connection::{Connection, ConnectionEvent, ConnectionState, Limits, Notice, Severity};
pub use devices::analog::{AnalogExample, AnalogRemote, AnalogReport, AnalogServer};
pub use devices::button::{ButtonChange, ButtonExample, ButtonRemote, ButtonServer, ButtonStates};
pub use devices::dial::{DialExample, DialRemote, DialServer, DialUpdate};
pub use devices::text::TextSeverity;
pub use devices::text_device::{TextExample, TextMessage, TextReceiver, TextSender};
pub use devices::tracker::{
    TrackerAcceleration, TrackerNull, TrackerPose, TrackerRemote, TrackerServer, TrackerVelocity,
};
pub use devices::ServerDevice;
pub use dispatch::{HandlerId, Message, SenderFilter, SenderId, TypeId};
pub use error::Error;
pub use layered::{TrackerAnalogFly, TrackerButtonFly};
pub use name::{DeviceName, Location};
pub use time::{Now, TimeVal};

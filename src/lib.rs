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
//! # Where to start
//!
//! - The remotes ([`TrackerRemote`], [`ButtonRemote`], [`AnalogRemote`], [`DialRemote`], ...)
//!   read devices: callbacks, or the latest state a frame loop polls (`pose`, `take_pose`,
//!   `seq`, arrival times). [`RemoteBuilder`] opens one with [`Limits`] or options.
//! - The servers ([`TrackerServer`], [`ButtonServer`], ...) report devices on a
//!   [`Connection::server`]; [`Connection`] also carries an application's own messages.
//! - docs/USING.md in the repository is the guide: threads, shared connections, when
//!   callbacks run, replying from a handler, polling versus callbacks, sending before the
//!   connection is up.
//!
//! # Threads
//!
//! A connection and every device on it belong to the thread that made them: they are not
//! `Send` (the handles are `Rc`s, and callbacks need not be `Send`). Connection sharing
//! (`Tracker0@host` and `Button0@host` use one connection) and `loopback:` are per thread.
//! An engine whose resources must be `Send` runs the remotes on a worker thread that calls
//! `mainloop()` and publishes the latest states (see `examples/worker_thread.rs`).
//!
//! # Layers
//!
//! Each layer is a module and uses only those below it:
//!
//! - [`wire`]: the pure codec over byte slices (header, cookie, descriptions, payloads), for
//!   tools that read or write VRPN bytes; [`log`] the same for `.vrpn` log files; [`time`]
//!   the timestamps and [`Now`].
//! - The protocol without sockets or clock (internal): a session is fed bytes and the time
//!   and hands back bytes, I/O requests, deliveries and its next deadline.
//! - [`net`]: the shell — a [`Reactor`] (one poll shared by every connection and serial port
//!   of a loop) and the sockets; the only place that reads the clock.
//! - [`connection`]: the public [`Connection`]: names, handlers, `mainloop()`.
//! - [`devices`], [`layered`], [`serial`], [`drivers`]: tracker and the other device types,
//!   the layered trackers, the serial layer and the hardware drivers.
//! - [`forward`]: forwarders between connections, remote-controlled forwarding and the relay
//!   that re-serves devices of servers clients cannot reach.
//! - [`server`]: `vrpn.cfg` and the `vrpn_server` loop.
//!
//! # Printing
//!
//! The library prints nothing an application did not ask for: a connection's notices go to
//! [`Connection::on_notice`] callbacks and device text messages to their handlers; only when
//! nothing is registered does the default printer write them, to stderr, one line each
//! ([`connection::set_text_printer`] chooses C++'s stdout format, or nothing).

#![deny(unsafe_code)]
#![warn(missing_docs)]

// The C ABI; also in the crate's own unit-test build, so `cargo test` covers it without the
// feature.
#[cfg(any(feature = "capi", test))]
pub mod capi;
pub mod config;
pub mod connection;
pub mod devices;
pub use connection::dispatch;
pub mod driver;
#[path = "../drivers/mod.rs"]
pub mod drivers;
mod error;
pub mod forward;
#[doc(hidden)]
pub mod fuzzing;
pub mod hid;
pub mod layered;
pub mod log;
pub mod name;
pub mod net;
// The protocol layer (sessions, endpoints, name tables): internal, public only for the
// crate's own simulation tests. Its user-facing types are re-exported from `connection`.
#[doc(hidden)]
pub mod proto;
#[cfg(feature = "python")]
mod python;
pub mod serial;
pub mod server;
// Device simulators and their rigs: test tools, never in the default library.
#[cfg(any(test, feature = "sim"))]
pub mod sim;
pub mod time;
pub mod wire;

pub use connection::{
    Connection, ConnectionEvent, ConnectionOptions, ConnectionState, DropReason, Limits, NameKind,
    Notice, NoticeKind, ServiceClass, Severity,
};
pub use devices::analog::{AnalogExample, AnalogRemote, AnalogReport, AnalogServer};
pub use devices::aux_logger::{AuxLoggerRemote, AuxLoggerServer, LogFiles, LoggingReport};
pub use devices::builder::RemoteBuilder;
pub use devices::button::{
    ButtonChange, ButtonExample, ButtonRemote, ButtonServer, ButtonState, ButtonStates,
};
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
pub use net::{Reactor, Waiter, Wake};
pub use time::{Now, TimeVal};

/// The linear-algebra crate of the reports' types (`Vector3`, `UnitQuaternion`), re-exported
/// so an application uses the same version without naming it in its own manifest.
pub use nalgebra;

// The README's complete program and the guide's snippets are compiled as doc tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

#[cfg(doctest)]
#[doc = include_str!("../docs/USING.md")]
struct UsingDoctests;

#[cfg(doctest)]
#[doc = include_str!("../docs/IMAGER.md")]
struct ImagerDoctests;

#[cfg(doctest)]
#[doc = include_str!("../docs/LOGGING_REQUESTS.md")]
struct LoggingRequestsDoctests;

#[cfg(doctest)]
#[doc = include_str!("../docs/MUTEX.md")]
struct MutexDoctests;

#[cfg(doctest)]
#[doc = include_str!("../docs/SHARED_OBJECTS.md")]
struct SharedObjectDoctests;

#[cfg(doctest)]
#[doc = include_str!("../docs/FUNCTION_GENERATOR.md")]
struct FunctionGeneratorDoctests;

#[cfg(doctest)]
#[doc = include_str!("../docs/SOUND.md")]
struct SoundDoctests;

#[cfg(doctest)]
#[doc = include_str!("../docs/REDUNDANT_TRANSMISSION.md")]
struct RedundantDoctests;

//! A relay: one reachable server re-serves devices of servers its clients cannot reach (a
//! cluster behind a firewall, a tracker on a private network).
//!
//! For each relayed device the relay keeps a client connection to the device's server (shared
//! by the devices of one server) and forwards, both ways, everything the device's sender
//! carries: reports and texts down to the relay's clients, requests and pings up to the
//! device's server, under the same type names. Only messages read from peers are forwarded,
//! so nothing goes round in circles. A relayed device behaves as the device itself: its
//! clients' liveness pings are answered by the real device (through the relay), and while its
//! server is unreachable they see it as not answering.
//!
//! Forwarded messages keep their timestamps (in the relay's clock when it synchronises with
//! the upstream server, which a server of this crate does) and go out RELIABLE.
//!
//! The source may also be a log (`Tracker0@file:session.vrpn`): the relay re-serves its
//! replay, and clients control it with `vrpn_File_Controller` messages
//! ([`FileController`](crate::connection::FileController), or C++'s), which the relay passes
//! to the replay. Each relayed device of one log passes them on, and the controls are
//! idempotent (a rate, a reset, a time to play to). A log answers no pings, so the relay
//! answers its clients' pings for a relayed log's devices itself.

use std::time::Instant;

use super::forwarder::{ConnectionForwarder, ForwardCounts};
use crate::connection::{Connection, ServiceClass};
use crate::devices::ServerDevice;
use crate::error::Error;
use crate::name::DeviceName;
use crate::time::Now;

/// One device re-served on a server connection (vrpn_server keyword `vrpn_Relay`).
pub struct Relay {
    name: String,
    source: String,
    upstream: Connection,
    down: ConnectionForwarder,
    up: ConnectionForwarder,
}

impl Relay {
    /// Re-serves the device `source` (`Tracker0@cluster-node:3883`) on the server connection
    /// `server`, under `as_name` (default: the device's own name). The connection to the
    /// device's server waits in `server`'s reactor and is shared with other devices relayed
    /// from the same location.
    pub fn new(server: &Connection, source: &str, as_name: Option<&str>) -> Result<Relay, Error> {
        let parsed = DeviceName::parse(source)?;
        let upstream = match server.reactor() {
            Some(r) => Connection::open_in(&r, source)?,
            None => Connection::open_location(&parsed)?,
        };
        if upstream.same_as(server) {
            return Err(Error::Unsupported(
                "a device cannot be relayed onto its own server",
            ));
        }
        let name = as_name.unwrap_or(&parsed.device).to_string();
        let mut down = ConnectionForwarder::new(&upstream, server).from_peers_only(true);
        down.forward_sender(&parsed.device, &name, ServiceClass::RELIABLE)?;
        let mut up = ConnectionForwarder::new(server, &upstream).from_peers_only(true);
        if upstream.is_replay() {
            // A relayed log: nothing upstream answers requests or pings, so the relay answers
            // the clients' pings itself (as the device's server did while it was logged), and
            // clients control the replay (C++ vrpn_File_Controller messages).
            let sender = crate::devices::base::register_sender(server, &name)?;
            let ids = crate::devices::base::register_base_types(server, sender)?;
            crate::devices::base::serve_pings(server, &ids);
            let controller = crate::wire::payload::file_controller::SENDER;
            up.forward_sender(controller, controller, ServiceClass::RELIABLE)?;
        } else {
            up.forward_sender(&name, &parsed.device, ServiceClass::RELIABLE)?;
        }
        Ok(Relay {
            name,
            source: source.to_string(),
            upstream,
            down,
            up,
        })
    }

    /// Where the device is served from (`Tracker0@cluster-node:3883`).
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The connection to the device's server.
    pub fn upstream(&self) -> &Connection {
        &self.upstream
    }

    /// Messages relayed to the relay's clients.
    pub fn relayed_down(&self) -> ForwardCounts {
        self.down.counts()
    }

    /// Messages relayed to the device's server (requests, pings).
    pub fn relayed_up(&self) -> ForwardCounts {
        self.up.counts()
    }
}

impl ServerDevice for Relay {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, _now: Now) {
        let _ = self.upstream.mainloop();
    }

    fn next_deadline(&self) -> Option<Instant> {
        // A relayed replay plays by the clock, not by sockets: look again every millisecond
        // while it plays (a paused or finished replay needs nothing).
        if let Some(r) = self.upstream.replay() {
            if !r.eof() && r.rate() > 0.0 {
                return Some(Instant::now() + std::time::Duration::from_millis(1));
            }
        }
        self.upstream.poll_timeout()
    }
}

/// The `vrpn.cfg` entry `vrpn_Relay DEVICE@HOST[:PORT] [NAME]`.
pub mod config {
    use super::Relay;
    use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
    use crate::devices::ServerDevice;
    use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Served};
    use crate::error::Error;
    use crate::name::{DeviceName, Location};

    /// A parsed entry.
    #[derive(Clone, Debug, PartialEq, Eq)]
    pub struct RelayEntry {
        /// The device to re-serve, `Device@host[:port]` (or `Device@file:LOG`).
        pub source: String,
        /// The name it is served under here.
        pub name: String,
    }

    /// `vrpn_Relay` (our extension: C++ has no relay).
    pub static RELAY: Driver = Driver {
        keywords: &["vrpn_Relay"],
        parse,
        hints: &[],
    };

    fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
        line.need(1, "device@host[:port] [, name]")?;
        let source = line.word(0)?.to_string();
        let parsed =
            DeviceName::parse(&source).map_err(|e| line.err(ConfigErrorKind::BadName, e))?;
        if parsed.location == Location::Loopback {
            return Err(line.err(
                ConfigErrorKind::BadName,
                format!("{source:?}: a relay re-serves a device of another server or a log"),
            ));
        }
        let name = match line.arg(1) {
            Some(_) => line.name(1)?,
            None => parsed.device.clone(),
        };
        Ok(Box::new(RelayEntry { source, name }))
    }

    impl DeviceSpec for RelayEntry {
        fn name(&self) -> &str {
            &self.name
        }

        fn served(&self) -> Vec<Served<'_>> {
            Vec::new() // whatever the device serves, unknown until it is reached
        }

        fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
            Ok(vec![Box::new(Relay::new(
                cx.conn(),
                &self.source,
                Some(&self.name),
            )?)])
        }
    }
}

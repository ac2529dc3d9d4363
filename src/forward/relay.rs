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
        up.forward_sender(&name, &parsed.device, ServiceClass::RELIABLE)?;
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
        self.upstream.poll_timeout()
    }
}

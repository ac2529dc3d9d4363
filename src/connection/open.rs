//! Opening a connection for a device name with options: the limits, the reactor its sockets
//! wait in, and whether it is shared with other devices at the same location.

use super::{new_reactor, Connection};
use crate::error::Error;
use crate::name::{DeviceName, Location};
use crate::net::Reactor;
use crate::proto::Limits;

/// How [`Connection::open_with`] (and a remote's builder) opens a connection.
///
/// The default is what [`Connection::open`] does: default [`Limits`], a reactor of its own,
/// and one connection per location text in this thread, shared by every device opened there.
#[derive(Clone, Debug, Default)]
pub struct ConnectionOptions {
    /// Limits and timings of a new network client (`None`: [`Limits::default`]). When the
    /// connection for the location is already open and shared, its limits must be these, or
    /// opening fails: limits cannot change under devices that already use the connection.
    pub limits: Option<Limits>,
    /// The reactor a new client's sockets wait in (`None`: one of its own), so that one
    /// `wait` covers several connections.
    pub reactor: Option<Reactor>,
    /// A connection of its own, not shared with other devices at the same location and not
    /// found by later opens.
    pub private: bool,
}

impl Connection {
    /// Opens (or shares) the connection for `name`, as [`open`](Self::open) does, with
    /// `options`.
    pub fn open_with(name: &str, options: &ConnectionOptions) -> Result<Connection, Error> {
        Self::open_location_with(&DeviceName::parse(name)?, options)
    }

    /// Like [`open_with`](Self::open_with) for an already parsed name.
    pub fn open_location_with(
        name: &DeviceName,
        options: &ConnectionOptions,
    ) -> Result<Connection, Error> {
        let conn = match &name.location {
            Location::Loopback if options.private => Connection::new_loopback(),
            Location::Loopback => Connection::loopback(),
            Location::File { path } if options.private => Connection::replay_file(path)?,
            Location::File { path } => {
                Self::shared(&name.location_text, || Connection::replay_file(path))?
            }
            Location::Net {
                host,
                port,
                tcp_only,
            } => {
                let make = || {
                    let reactor = match &options.reactor {
                        Some(r) => r.clone(),
                        None => new_reactor()?,
                    };
                    let limits = options.limits.unwrap_or_default();
                    Connection::client_in(&reactor, host, *port, *tcp_only, limits)
                };
                if options.private {
                    make()?
                } else {
                    Self::shared(&name.location_text, make)?
                }
            }
        };
        if let Some(limits) = options.limits {
            if conn.limits() != limits && matches!(name.location, Location::Net { .. }) {
                return Err(Error::Unsupported(
                    "the connection to this location is already open with other limits; \
                     give the limits to the first device opened there, or open this one \
                     privately",
                ));
            }
        }
        Ok(conn)
    }

    /// The limits and timings this connection runs with.
    pub fn limits(&self) -> Limits {
        self.inner.core.borrow().session.limits
    }
}

//! Building a remote with connection options: `TrackerRemote::builder("Tracker0@host")`.

use std::marker::PhantomData;

use crate::connection::{Connection, ConnectionOptions, Limits};
use crate::error::Error;
use crate::name::DeviceName;
use crate::net::Reactor;

/// A client half of a device that can be set up on a connection: what a
/// [`RemoteBuilder`] builds.
pub trait Remote: Sized {
    /// A remote for `device` on `conn`.
    fn on_connection(device: &str, conn: &Connection) -> Result<Self, Error>;
}

/// Opens a remote with [`Limits`], a shared [`Reactor`] or a private connection, without
/// making the [`Connection`] by hand:
///
/// ```no_run
/// use std::time::Duration;
/// use vrpn::{Limits, TrackerRemote};
///
/// let tracker = TrackerRemote::builder("Tracker0@localhost")
///     .limits(Limits {
///         retry_interval: Duration::from_millis(250),
///         ..Limits::default()
///     })
///     .build()?;
/// # Ok::<(), vrpn::Error>(())
/// ```
///
/// Without options it does what `TrackerRemote::new` does. The connection is shared with
/// later devices opened at the same location (unless [`private`](Self::private)), so the
/// limits belong to the first device opened there: a second one asking for other limits is
/// refused with an error rather than silently getting the first one's.
#[must_use = "a builder does nothing until build()"]
pub struct RemoteBuilder<R> {
    name: String,
    options: ConnectionOptions,
    remote: PhantomData<fn() -> R>,
}

impl<R: Remote> RemoteBuilder<R> {
    /// A builder for the remote of `Device@location`.
    pub fn new(name: &str) -> RemoteBuilder<R> {
        RemoteBuilder {
            name: name.to_string(),
            options: ConnectionOptions::default(),
            remote: PhantomData,
        }
    }

    /// Limits and timings of the connection (retry interval, greeting time-out, ...).
    pub fn limits(mut self, limits: Limits) -> Self {
        self.options.limits = Some(limits);
        self
    }

    /// The reactor the connection's sockets wait in (one poll for several connections).
    pub fn reactor(mut self, reactor: &Reactor) -> Self {
        self.options.reactor = Some(reactor.clone());
        self
    }

    /// A connection of its own, not shared with other devices at the same location.
    pub fn private(mut self) -> Self {
        self.options.private = true;
        self
    }

    /// All options at once.
    pub fn options(mut self, options: ConnectionOptions) -> Self {
        self.options = options;
        self
    }

    /// Opens (or shares) the connection and sets up the remote on it.
    pub fn build(self) -> Result<R, Error> {
        let name = DeviceName::parse_remote(&self.name)?;
        let conn = Connection::open_location_with(&name, &self.options)?;
        R::on_connection(&name.device, &conn)
    }
}

/// `impl Remote` and `builder()` for remotes whose `on_connection` has the usual shape.
macro_rules! remote_builder {
    ($($t:ty),* $(,)?) => {$(
        impl crate::devices::builder::Remote for $t {
            fn on_connection(
                device: &str,
                conn: &crate::connection::Connection,
            ) -> Result<Self, crate::error::Error> {
                <$t>::on_connection(device, conn)
            }
        }

        impl $t {
            /// A builder that opens this remote with connection options (limits, reactor,
            /// a private connection); see [`RemoteBuilder`](crate::devices::builder::RemoteBuilder).
            pub fn builder(name: &str) -> crate::devices::builder::RemoteBuilder<$t> {
                crate::devices::builder::RemoteBuilder::new(name)
            }
        }
    )*};
}
pub(crate) use remote_builder;

//! Remote-controlled forwarding (C++ `vrpn_Forwarder_Brain`): a client's
//! [`ForwarderController`] tells a server's [`ForwarderServer`] to open another port and to
//! forward message types of its devices there, for other clients to read.
//!
//! C++ `vrpn_server` opens any port any client names. Here the operator gives the ports a
//! client may open ([`ForwarderServer::allow_ports`], `vrpn_server -forwardports LOW-HIGH`);
//! without them every request is refused with a notice on the server.

use std::cell::RefCell;
use std::net::Ipv4Addr;
use std::ops::RangeInclusive;
use std::rc::{Rc, Weak};
use std::time::Instant;

use super::forwarder::ConnectionForwarder;
use crate::connection::{Connection, Limits, ServiceClass};
use crate::devices::ServerDevice;
use crate::dispatch::{SenderFilter, SenderId, TypeId};
use crate::error::Error;
use crate::proto::{Notice, NoticeKind, Severity};
use crate::time::Now;
use crate::wire::class;
use crate::wire::payload::forwarder::{self as codec, Forward};

/// The brain's sender and types on one connection.
#[derive(Clone, Copy, Debug)]
pub struct BrainIds {
    /// `vrpn_Forwarder_Brain`.
    pub sender: SenderId,
    /// Open a port.
    pub start: TypeId,
    /// Forward a type of a sender on a port.
    pub forward: TypeId,
}

impl BrainIds {
    /// Registers the sender and the two types, in C++ order.
    pub fn register(conn: &Connection) -> Result<BrainIds, Error> {
        Ok(BrainIds {
            sender: conn.register_sender(codec::SENDER)?,
            start: conn.register_type(codec::START_FORWARDING)?,
            forward: conn.register_type(codec::FORWARD)?,
        })
    }
}

/// Client half (C++ `vrpn_Forwarder_Controller`): asks the server at the other end of a
/// connection to forward.
pub struct ForwarderController {
    conn: Connection,
    ids: BrainIds,
}

impl ForwarderController {
    /// A controller on `conn` (usually a client connection to the server to control).
    pub fn new(conn: &Connection) -> Result<ForwarderController, Error> {
        Ok(ForwarderController {
            conn: conn.clone(),
            ids: BrainIds::register(conn)?,
        })
    }

    /// Asks the server to open `port` for forwarded messages.
    pub fn start_remote_forwarding(&self, port: u16) -> Result<(), Error> {
        let mut buf = [0u8; codec::START_LEN];
        let n = codec::encode_start(&mut buf, i32::from(port));
        self.send(self.ids.start, &buf[..n])
    }

    /// Asks the server to forward messages of `type_name` from `sender` on `port`.
    pub fn forward_message_type(
        &self,
        port: u16,
        sender: &str,
        type_name: &str,
    ) -> Result<(), Error> {
        let f = Forward {
            port: i32::from(port),
            sender: sender.as_bytes(),
            type_name: type_name.as_bytes(),
        };
        let mut buf = vec![0u8; f.encoded_len()];
        let n = f.encode(&mut buf);
        self.send(self.ids.forward, &buf[..n])
    }

    fn send(&self, type_id: TypeId, payload: &[u8]) -> Result<(), Error> {
        self.conn.pack_message(
            self.conn.now().wall,
            type_id,
            self.ids.sender,
            payload,
            class::RELIABLE,
        )
    }
}

/// One port a server forwards on.
struct Forwarding {
    port: u16,
    connection: Connection,
    forwarder: ConnectionForwarder,
}

/// Why a client's forwarding request is refused (told as a warning notice on the server).
#[derive(Debug)]
enum Refusal {
    /// The port asked for is not a port number.
    NotAPort(i32),
    /// No ports are allowed (`vrpn_server -forwardports` was not given).
    ForwardingOff(u16),
    /// The port lies outside the allowed range.
    NotAllowed {
        port: u16,
        allowed: RangeInclusive<u16>,
    },
    /// The port is already being forwarded on.
    AlreadyForwarding(u16),
    /// The server connection has been dropped.
    ServerGone,
    /// The port could not be listened on.
    CannotListen { port: u16, error: Error },
    /// A forward request names a port no start request opened.
    NotOpen(i32),
    /// The forwarder refused the type or sender.
    CannotForward {
        type_name: String,
        sender: String,
        error: Error,
    },
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refusal::NotAPort(port) => write!(f, "port {port} is not a port number"),
            Refusal::ForwardingOff(port) => write!(
                f,
                "a client asked to forward on port {port}; forwarding is off (vrpn_server \
                 -forwardports LOW-HIGH allows it)"
            ),
            Refusal::NotAllowed { port, allowed } => write!(
                f,
                "a client asked to forward on port {port}, outside the ports allowed ({}-{})",
                allowed.start(),
                allowed.end()
            ),
            Refusal::AlreadyForwarding(port) => write!(f, "already forwarding on port {port}"),
            Refusal::ServerGone => f.write_str("the server is gone"),
            Refusal::CannotListen { port, error } => {
                write!(f, "cannot forward on port {port}: {error}")
            }
            Refusal::NotOpen(port) => write!(f, "no forwarding open on port {port}"),
            Refusal::CannotForward {
                type_name,
                sender,
                error,
            } => write!(f, "cannot forward {type_name:?} of {sender:?}: {error}"),
        }
    }
}

struct State {
    source: crate::connection::WeakConnection,
    allowed: Option<RangeInclusive<u16>>,
    nic: Option<Ipv4Addr>,
    limits: Limits,
    ports: Vec<Forwarding>,
}

impl State {
    fn notice(&self, severity: Severity, text: String) {
        if let Some(c) = self.source.upgrade() {
            c.dispatch_notice(Notice::new(severity, NoticeKind::Forwarding, text));
        }
    }

    fn start(&mut self, port: i32) -> Result<u16, Refusal> {
        let Ok(port) = u16::try_from(port) else {
            return Err(Refusal::NotAPort(port));
        };
        let Some(allowed) = &self.allowed else {
            return Err(Refusal::ForwardingOff(port));
        };
        if !allowed.contains(&port) {
            return Err(Refusal::NotAllowed {
                port,
                allowed: allowed.clone(),
            });
        }
        if self.ports.iter().any(|f| f.port == port) {
            return Err(Refusal::AlreadyForwarding(port));
        }
        let source = self.source.upgrade().ok_or(Refusal::ServerGone)?;
        let connection = match source.reactor() {
            Some(r) => Connection::server_in(&r, self.nic, port, self.limits),
            None => Connection::server_with_limits(self.nic, port, self.limits),
        }
        .map_err(|error| Refusal::CannotListen { port, error })?;
        let forwarder = ConnectionForwarder::new(&source, &connection);
        self.ports.push(Forwarding {
            port,
            connection,
            forwarder,
        });
        Ok(port)
    }

    fn forward(&mut self, f: &Forward<'_>) -> Result<String, Refusal> {
        let sender = String::from_utf8_lossy(f.sender).into_owned();
        let type_name = String::from_utf8_lossy(f.type_name).into_owned();
        let Some(it) = self.ports.iter_mut().find(|p| i32::from(p.port) == f.port) else {
            return Err(Refusal::NotOpen(f.port));
        };
        it.forwarder
            .forward(
                &type_name,
                &sender,
                &type_name,
                &sender,
                ServiceClass::RELIABLE,
            )
            .map_err(|error| Refusal::CannotForward {
                type_name: type_name.clone(),
                sender: sender.clone(),
                error,
            })?;
        Ok(format!(
            "forwarding {type_name:?} of {sender:?} on port {}",
            it.port
        ))
    }
}

/// Server half (C++ `vrpn_Forwarder_Server`, which C++ `vrpn_server` always runs): opens the
/// ports clients ask for and forwards there the message types they name. Its forwarding
/// connections wait in the server connection's reactor; run it as a [`ServerDevice`] (or call
/// [`mainloop`](ServerDevice::mainloop)) so that they are served.
pub struct ForwarderServer {
    state: Rc<RefCell<State>>,
}

impl ForwarderServer {
    /// A forwarder server on the server connection `conn`, refusing every request until
    /// [`allow_ports`](Self::allow_ports).
    pub fn new(conn: &Connection) -> Result<ForwarderServer, Error> {
        let ids = BrainIds::register(conn)?;
        let state = Rc::new(RefCell::new(State {
            source: conn.downgrade(),
            allowed: None,
            nic: None,
            limits: Limits::default(),
            ports: Vec::new(),
        }));
        let s: Weak<RefCell<State>> = Rc::downgrade(&state);
        conn.register_handler(ids.start, SenderFilter::Only(ids.sender), move |m| {
            let (Some(s), Ok(port)) = (s.upgrade(), codec::decode_start(m.payload)) else {
                return;
            };
            let outcome = s.borrow_mut().start(port);
            let st = s.borrow();
            match outcome {
                Ok(port) => st.notice(Severity::Info, format!("forwarding port {port} open")),
                Err(e) => st.notice(Severity::Warning, e.to_string()),
            }
        });
        let s: Weak<RefCell<State>> = Rc::downgrade(&state);
        conn.register_handler(ids.forward, SenderFilter::Only(ids.sender), move |m| {
            let (Some(s), Ok(f)) = (s.upgrade(), Forward::decode(m.payload)) else {
                return;
            };
            let outcome = s.borrow_mut().forward(&f);
            let st = s.borrow();
            match outcome {
                Ok(text) => st.notice(Severity::Info, text),
                Err(e) => st.notice(Severity::Warning, e.to_string()),
            }
        });
        Ok(ForwarderServer { state })
    }

    /// Lets clients open ports in `ports` (and no other).
    pub fn allow_ports(&self, ports: RangeInclusive<u16>) {
        self.state.borrow_mut().allowed = Some(ports);
    }

    /// Opens forwarding ports on this interface only (the server's `-NIC`).
    pub fn set_nic(&self, nic: Option<Ipv4Addr>) {
        self.state.borrow_mut().nic = nic;
    }

    /// Opens `port` as a client's request would (C++ `start_remote_forwarding`).
    pub fn start_remote_forwarding(&self, port: u16) -> Result<(), Error> {
        self.state
            .borrow_mut()
            .start(i32::from(port))
            .map(|_| ())
            .map_err(|_| Error::Unsupported("the port is not allowed, taken, or open already"))
    }

    /// Forwards `type_name` of `sender` on `port` as a client's request would.
    pub fn forward_message_type(&self, port: u16, sender: &str, type_name: &str) -> bool {
        let f = Forward {
            port: i32::from(port),
            sender: sender.as_bytes(),
            type_name: type_name.as_bytes(),
        };
        self.state.borrow_mut().forward(&f).is_ok()
    }

    /// The ports open for forwarding.
    pub fn ports(&self) -> Vec<u16> {
        self.state.borrow().ports.iter().map(|f| f.port).collect()
    }
}

impl ServerDevice for ForwarderServer {
    fn name(&self) -> &str {
        codec::SENDER
    }

    fn mainloop(&mut self, _now: Now) {
        // One port at a time, the state released while its connection runs handlers.
        for i in 0.. {
            let Some(c) = self
                .state
                .borrow()
                .ports
                .get(i)
                .map(|f| f.connection.clone())
            else {
                break;
            };
            let _ = c.mainloop();
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.state
            .borrow()
            .ports
            .iter()
            .filter_map(|f| f.connection.poll_timeout())
            .min()
    }
}

//! Auxiliary logger (C++ `vrpn_Auxiliary_Logger`): a client asks a server to start and stop
//! logging a connection, at full rate, while the client itself may read only a preview.
//!
//! [`AuxLoggerRemote`] sends requests of four file names and hears the server's report of
//! the logs it opened. [`AuxLoggerServer`] (C++ `vrpn_Auxiliary_Logger_Server_Generic`)
//! answers them: for each request it closes its logging connection, then opens a new one to
//! the connection it was told to log, writing the "local" logs itself and asking the logged
//! server for the "remote" ones.
//!
//! Unlike C++, which writes any path a client names, the server writes only inside a folder
//! its operator chose ([`LogFolder`]): each local name must be a plain file name that does
//! not exist there yet, each remote name a plain file name (the logged server applies its
//! own rule). A refused request is answered with an error text from the logger and a report
//! of four empty names, so the client sees it.

use std::cell::RefCell;
use std::ops::Deref;
use std::path::PathBuf;
use std::rc::Rc;
use std::time::Instant;

use super::base::{self, BaseIds, RemoteCore};
use super::text::TextSeverity;
use super::ServerDevice;
use crate::connection::{Connection, ConnectionEvent, Limits};
use crate::dispatch::{CallbackList, HandlerId, SenderFilter, TypeId};
use crate::error::Error;
use crate::log::folder::{LogFolder, Refusal};
use crate::name::{DeviceName, Location};
use crate::net::Reactor;
use crate::time::{Now, TimeVal};
use crate::wire::class;
use crate::wire::payload::aux_logger::{self as codec, LogNames};

/// Ids of the auxiliary logger's types on one connection.
#[derive(Clone, Copy, Debug)]
pub struct AuxLoggerIds {
    /// Client to server: the logs to open.
    pub request: TypeId,
    /// Server to client: the logs open.
    pub response: TypeId,
    /// Client to server: "which logs are open?".
    pub status_request: TypeId,
}

impl AuxLoggerIds {
    /// Registers the three types in C++ order.
    pub fn register(conn: &Connection) -> Result<AuxLoggerIds, Error> {
        Ok(AuxLoggerIds {
            request: conn.register_type(codec::REQUEST)?,
            response: conn.register_type(codec::RESPONSE)?,
            status_request: conn.register_type(codec::STATUS_REQUEST)?,
        })
    }
}

/// Four log file names ("" for none), owned: what a client asks for, what a server reports.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LogFiles {
    /// What the logging connection receives, written on the logging server's machine.
    pub local_in: String,
    /// What the logging connection sends, written on the logging server's machine.
    pub local_out: String,
    /// What the logged server receives from the logging connection (written by it).
    pub remote_in: String,
    /// What the logged server sends to the logging connection (written by it).
    pub remote_out: String,
}

impl LogFiles {
    /// Four names; "" for a log that is not wanted.
    pub fn new(local_in: &str, local_out: &str, remote_in: &str, remote_out: &str) -> LogFiles {
        LogFiles {
            local_in: local_in.into(),
            local_out: local_out.into(),
            remote_in: remote_in.into(),
            remote_out: remote_out.into(),
        }
    }

    /// True when no log is named.
    pub fn is_empty(&self) -> bool {
        self.wire().is_empty()
    }

    fn wire(&self) -> LogNames<'_> {
        LogNames::new(
            &self.local_in,
            &self.local_out,
            &self.remote_in,
            &self.remote_out,
        )
    }

    fn from_wire(names: &LogNames<'_>) -> LogFiles {
        let s = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
        LogFiles {
            local_in: s(names.local_in),
            local_out: s(names.local_out),
            remote_in: s(names.remote_in),
            remote_out: s(names.remote_out),
        }
    }
}

/// A server's report of the logs it has open (C++ `vrpn_AUXLOGGERCB`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoggingReport {
    /// When the server sent it.
    pub time: TimeVal,
    /// The logs open; all empty when none is (a stop, or a refused request).
    pub files: LogFiles,
}

fn send_names(
    conn: &Connection,
    type_id: TypeId,
    sender: crate::dispatch::SenderId,
    names: &LogNames<'_>,
) -> Result<(), Error> {
    let mut buf = vec![0u8; names.encoded_len()];
    let n = names.encode(&mut buf);
    conn.pack_message(conn.now().wall, type_id, sender, &buf[..n], class::RELIABLE)
}

#[derive(Default)]
struct RemoteShared {
    reports: CallbackList<LoggingReport>,
    latest: RefCell<Option<LoggingReport>>,
}

/// Client half: asks an auxiliary logging server to start or stop logs, and hears its reports
/// (C++ `vrpn_Auxiliary_Logger_Remote`).
pub struct AuxLoggerRemote {
    core: RemoteCore,
    ids: AuxLoggerIds,
    shared: Rc<RemoteShared>,
}

impl Deref for AuxLoggerRemote {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl AuxLoggerRemote {
    /// Opens `Logger@location`.
    pub fn new(name: &str) -> Result<AuxLoggerRemote, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// The remote of logger `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<AuxLoggerRemote, Error> {
        let (mut core, ids) = RemoteCore::new(device, conn, AuxLoggerIds::register)?;
        let shared = Rc::new(RemoteShared::default());
        let s = shared.clone();
        core.handle(ids.response, move |m| {
            let Ok(names) = LogNames::decode(m.payload) else {
                return;
            };
            let report = LoggingReport {
                time: m.time,
                files: LogFiles::from_wire(&names),
            };
            *s.latest.borrow_mut() = Some(report.clone());
            s.reports.call(&report);
        });
        Ok(AuxLoggerRemote { core, ids, shared })
    }

    /// Asks the server to close its logs and open these (all empty: just close). The server
    /// answers with a report.
    pub fn request_logging(&self, files: &LogFiles) -> Result<(), Error> {
        send_names(
            self.connection(),
            self.ids.request,
            self.sender(),
            &files.wire(),
        )
    }

    /// Asks the server to stop logging (a request of four empty names).
    pub fn stop_logging(&self) -> Result<(), Error> {
        self.request_logging(&LogFiles::default())
    }

    /// Asks which logs are open; the server answers with a report.
    pub fn request_status(&self) -> Result<(), Error> {
        send_names(
            self.connection(),
            self.ids.status_request,
            self.sender(),
            &LogNames::default(),
        )
    }

    /// Calls `f` with each report from the server.
    pub fn on_report(&self, f: impl FnMut(&LoggingReport) + 'static) -> HandlerId {
        self.shared.reports.add(f)
    }

    /// Removes a callback.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.shared.reports.remove(id)
    }

    /// The last report received.
    pub fn latest_report(&self) -> Option<LoggingReport> {
        self.shared.latest.borrow().clone()
    }
}

/// Where the server's logging connection goes, from its configuration text.
#[derive(Clone, Debug)]
struct Target {
    host: String,
    port: u16,
    tcp_only: bool,
}

impl Target {
    /// `host`, `host:port`, `tcp://host:port`, or any of these after `Name@` (C++ keeps the
    /// part after the last `@`).
    /// `None` when the text is not a network server's location.
    fn parse(text: &str) -> Option<Target> {
        let location = text.rsplit('@').next().unwrap_or(text);
        match DeviceName::parse_location(location).ok()? {
            Location::Net {
                host,
                port,
                tcp_only,
            } => Some(Target {
                host,
                port,
                tcp_only,
            }),
            _ => None,
        }
    }
}

/// Why a logging request was refused (sent to the requester as text).
#[derive(Debug)]
enum RequestError {
    /// A file name the folder refuses.
    Refused(&'static str, Refusal),
    /// The same local file for both directions.
    SameFile,
    /// No poll for the logging connection.
    Poll(std::io::Error),
    /// The server to log cannot be reached.
    Connect(String, u16, Error),
    /// The remote logs cannot be asked for.
    Remote(Error),
}

impl std::fmt::Display for RequestError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RequestError::Refused(what, r) => write!(f, "{what} log: {r}"),
            RequestError::SameFile => {
                f.write_str("the local incoming and outgoing logs must be two files")
            }
            RequestError::Poll(e) => write!(f, "cannot poll: {e}"),
            RequestError::Connect(host, port, e) => write!(f, "cannot reach {host}:{port}: {e}"),
            RequestError::Remote(e) => e.fmt(f),
        }
    }
}

struct ServerState {
    name: String,
    base: BaseIds,
    ids: AuxLoggerIds,
    target: Target,
    folder: LogFolder,
    reactor: Option<Reactor>,
    limits: Limits,
    /// The connection being logged through, while logging.
    logging: Option<Connection>,
    current: LogFiles,
    /// Files this logger created (full paths), for the operator's record.
    created: Vec<PathBuf>,
}

impl ServerState {
    /// Closes the current logs, then opens those asked for (C++ `handle_request_logging`).
    /// Returns the names to report and the refusal to send as a text, if any.
    fn start(&mut self, files: LogFiles) -> (LogFiles, Option<RequestError>) {
        // Dropping the connection closes its logs (and its sockets).
        self.logging = None;
        self.current = LogFiles::default();
        if files.is_empty() {
            return (LogFiles::default(), None);
        }
        match self.open(&files) {
            Ok(conn) => {
                self.logging = Some(conn);
                self.current = files.clone();
                (files, None)
            }
            Err(why) => (LogFiles::default(), Some(why)),
        }
    }

    fn open(&mut self, files: &LogFiles) -> Result<Connection, RequestError> {
        let refused = RequestError::Refused;
        for (what, name) in [
            ("remote incoming", &files.remote_in),
            ("remote outgoing", &files.remote_out),
        ] {
            if !name.is_empty() {
                LogFolder::check_name(name.as_bytes()).map_err(|r| refused(what, r))?;
            }
        }
        // Check both local names before creating either, so a refusal leaves no file behind.
        for (what, name) in [
            ("local incoming", &files.local_in),
            ("local outgoing", &files.local_out),
        ] {
            if !name.is_empty() {
                let path = self
                    .folder
                    .resolve(name.as_bytes())
                    .map_err(|r| refused(what, r))?;
                if std::fs::symlink_metadata(&path).is_ok() {
                    return Err(refused(what, Refusal::Exists(path)));
                }
            }
        }
        if !files.local_in.is_empty() && files.local_in == files.local_out {
            return Err(RequestError::SameFile);
        }
        let reactor = match &self.reactor {
            Some(r) => r.clone(),
            None => Reactor::new().map_err(RequestError::Poll)?,
        };
        let t = &self.target;
        let conn = Connection::client_in(&reactor, &t.host, t.port, t.tcp_only, self.limits)
            .map_err(|e| RequestError::Connect(t.host.clone(), t.port, e))?;
        let mut made = Vec::new();
        let mut create = |what: &'static str, name: &str| {
            let (path, file) = self
                .folder
                .create(name.as_bytes())
                .map_err(|r| refused(what, r))?;
            made.push(path.clone());
            Ok::<_, RequestError>((path, file))
        };
        let outcome = (|| {
            if !files.local_in.is_empty() {
                let (path, file) = create("local incoming", &files.local_in)?;
                conn.log_incoming_file(file, &path);
            }
            if !files.local_out.is_empty() {
                let (path, file) = create("local outgoing", &files.local_out)?;
                conn.log_outgoing_file(file, &path);
            }
            Ok(())
        })();
        if let Err(e) = outcome {
            drop(conn);
            for p in &made {
                let _ = std::fs::remove_file(p);
            }
            return Err(e);
        }
        self.created.extend(made);
        if !files.remote_in.is_empty() || !files.remote_out.is_empty() {
            conn.request_remote_logging(&files.remote_in, &files.remote_out)
                .map_err(RequestError::Remote)?;
        }
        Ok(conn)
    }

    fn report(&self, conn: &Connection, files: &LogFiles) {
        let _ = send_names(conn, self.ids.response, self.base.sender, &files.wire());
    }
}

/// Server half (C++ `vrpn_Auxiliary_Logger_Server_Generic`, vrpn_server keyword
/// `vrpn_Auxiliary_Logger_Server_Generic NAME CONNECTION_TO_LOG`): on request, opens a
/// connection of its own to the server it was told to log and writes its logs inside
/// `folder`. One set of logs at a time; a new request closes the previous set, and the last
/// client leaving stops logging.
pub struct AuxLoggerServer {
    state: Rc<RefCell<ServerState>>,
    name: String,
}

impl AuxLoggerServer {
    /// A logger named `device` on the server connection `conn`, logging `connection_to_log`
    /// (`host`, `host:port`, or `Name@host:port` as C++ configuration lines give it) into
    /// `folder`. The logging connection's sockets wait in `conn`'s reactor.
    pub fn new(
        device: &str,
        conn: &Connection,
        connection_to_log: &str,
        folder: LogFolder,
    ) -> Result<AuxLoggerServer, Error> {
        let target = Target::parse(connection_to_log).ok_or(Error::Unsupported(
            "the connection to log must be a network server (host:port)",
        ))?;
        let (base, ids) = base::register_server(conn, device, AuxLoggerIds::register)?;
        let state = Rc::new(RefCell::new(ServerState {
            name: device.to_string(),
            base,
            ids,
            target,
            folder,
            reactor: conn.reactor(),
            limits: Limits::default(),
            logging: None,
            current: LogFiles::default(),
            created: Vec::new(),
        }));
        let s = Rc::downgrade(&state);
        conn.register_handler(ids.request, SenderFilter::Only(base.sender), move |m| {
            let (Some(s), Ok(names)) = (s.upgrade(), LogNames::decode(m.payload)) else {
                return;
            };
            let files = LogFiles::from_wire(&names);
            let (reported, refusal) = s.borrow_mut().start(files);
            let st = s.borrow();
            if let Some(why) = refusal {
                let _ = m.connection().send_text(
                    st.base.sender,
                    TextSeverity::Error,
                    0,
                    &format!("{}: logging request refused: {why}", st.name),
                );
            }
            st.report(m.connection(), &reported);
        });
        let s = Rc::downgrade(&state);
        conn.register_handler(
            ids.status_request,
            SenderFilter::Only(base.sender),
            move |m| {
                if let Some(s) = s.upgrade() {
                    let st = s.borrow();
                    st.report(m.connection(), &st.current);
                }
            },
        );
        let s = Rc::downgrade(&state);
        let weak_conn = conn.downgrade();
        conn.on_event(ConnectionEvent::DroppedLastConnection, move || {
            if let (Some(s), Some(c)) = (s.upgrade(), weak_conn.upgrade()) {
                let (reported, _) = s.borrow_mut().start(LogFiles::default());
                s.borrow().report(&c, &reported);
            }
        });
        Ok(AuxLoggerServer {
            state,
            name: device.to_string(),
        })
    }

    /// The logs open now.
    pub fn current(&self) -> LogFiles {
        self.state.borrow().current.clone()
    }

    /// The connection the logs are written from, while logging.
    pub fn logging_connection(&self) -> Option<Connection> {
        self.state.borrow().logging.clone()
    }

    /// Every file this logger created so far (full paths).
    pub fn created_files(&self) -> Vec<PathBuf> {
        self.state.borrow().created.clone()
    }

    /// Limits of the logging connections opened from now on.
    pub fn set_limits(&self, limits: Limits) {
        self.state.borrow_mut().limits = limits;
    }
}

impl ServerDevice for AuxLoggerServer {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, _now: Now) {
        let logging = self.state.borrow().logging.clone();
        if let Some(c) = logging {
            let _ = c.mainloop();
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.state
            .borrow()
            .logging
            .as_ref()
            .and_then(|c| c.poll_timeout())
    }
}

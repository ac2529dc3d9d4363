//! Logs one side asks the other to write (C++ `vrpn_get_connection_by_name`'s remote log
//! names): the client announces the log mode in its cookie and sends a LOG_DESCRIPTION with
//! two file names as soon as the greeting is done; the server writes what it receives from
//! that client and what it sends to it.
//!
//! A server honours such requests only when its operator named a folder for them
//! ([`Session::set_remote_log_folder`]); the names must then be plain file names, created
//! inside that folder and never over an existing file. A request the server cannot honour
//! closes the connection, which is how a C++ client learns that logging failed. Without a
//! folder, requests are refused with a notice and the client keeps being served.

use super::{Kind, Session};
use crate::log::folder::{LogFolder, Refusal};
use crate::proto::endpoint::LogSink;
use crate::proto::{DropReason, NoticeKind, PeerId, Severity};
use crate::time::{Now, TimeVal};
use crate::wire::{class, system};

/// Remote log names a client sends when it connects.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RemoteLogRequest {
    /// What the server receives from this client ("" for none).
    pub incoming: String,
    /// What the server sends to this client ("" for none).
    pub outgoing: String,
}

impl RemoteLogRequest {
    /// The log mode of the cookie and of the LOG_DESCRIPTION's sender field: 1 incoming,
    /// 2 outgoing.
    pub fn mode(&self) -> u8 {
        u8::from(!self.incoming.is_empty()) | (u8::from(!self.outgoing.is_empty()) << 1)
    }
}

/// The logs a server writes for one peer at the peer's request.
#[derive(Default)]
pub(crate) struct RequestedLogs {
    pub(crate) incoming: Option<LogSink>,
    pub(crate) outgoing: Option<LogSink>,
}

impl Session {
    /// Client: asks the server to log this connection, at the next connect (and only then:
    /// after a reconnect the files would exist already). Names are the server's to interpret;
    /// a server of this crate takes plain file names inside a folder its operator chose.
    pub fn set_remote_log_request(&mut self, request: Option<RemoteLogRequest>) {
        self.remote_log_request = request.filter(|r| r.mode() != 0);
    }

    /// The request not yet sent, if any.
    pub fn remote_log_request(&self) -> Option<&RemoteLogRequest> {
        self.remote_log_request.as_ref()
    }

    /// Server: honours the log requests of peers, writing them into `folder` (`None`: refuse
    /// them with a notice, the default).
    pub fn set_remote_log_folder(&mut self, folder: Option<LogFolder>) {
        self.logs.remote_folder = folder;
    }

    /// The cookie's log-mode digit for a new greeting.
    pub(super) fn greeting_log_mode(&self) -> u8 {
        match (&self.kind, &self.remote_log_request) {
            (Kind::Client(_), Some(r)) => r.mode(),
            _ => 0,
        }
    }

    /// Client, greeting done: send the log request first (C++ sends it before its UDP
    /// description), once.
    pub(super) fn send_remote_log_request(&mut self, now: Now, id: PeerId) {
        if !matches!(self.kind, Kind::Client(_)) {
            return;
        }
        let Some(request) = self.remote_log_request.take() else {
            return;
        };
        let len = system::log_description_len(&request.incoming, &request.outgoing);
        let mut buf = vec![0u8; len];
        let n = system::encode_log_description(&mut buf, &request.incoming, &request.outgoing);
        let mode = i32::from(request.mode());
        let Session { peers, logs, .. } = self;
        let Some(p) = peers[id.slot].as_mut().filter(|p| p.id == id) else {
            return;
        };
        let _ = p.pack_always(
            now.wall,
            mode,
            system::LOG_DESCRIPTION,
            &buf[..n],
            class::RELIABLE,
        );
        if let Some(w) = logs.outgoing.as_mut() {
            let _ = w.log_message(system::LOG_DESCRIPTION, mode, now.wall, &buf[..n]);
        }
    }

    /// Server: a peer's LOG_DESCRIPTION (its payload in `scratch[..len]`, the mode in
    /// `mode`). Opens the logs in the folder, or refuses: with a notice when no folder is
    /// set, by dropping the peer (the C++ contract) when the names cannot be honoured.
    pub(super) fn handle_log_request(&mut self, slot: usize, mode: i32, len: usize, now: Now) {
        let Ok(d) = system::decode_log_description(&self.scratch[..len]) else {
            return;
        };
        let (incoming, outgoing) = (d.incoming.to_string(), d.outgoing.to_string());
        let Some(p) = self.peers[slot].as_ref() else {
            return;
        };
        let label = p.label.clone();
        if matches!(self.kind, Kind::Client(_) | Kind::File(_)) {
            return; // only servers log for their peers; a replayed request is history
        }
        let Some(folder) = self.logs.remote_folder.clone() else {
            let text = format!(
                "{label} asked this side to log (incoming {incoming:?}, outgoing \
                 {outgoing:?}); remote logging requests are refused: log locally with -li/-lo, \
                 or name a folder for them (vrpn_server -logdir DIR)"
            );
            let kind = NoticeKind::RemoteLogRefused { peer: label };
            self.notice(Severity::Warning, kind, text);
            return;
        };
        let open = |name: &str| -> Result<Option<LogSink>, Refusal> {
            if name.is_empty() {
                return Ok(None);
            }
            let (path, file) = folder.create(name.as_bytes())?;
            Ok(Some(crate::log::sink_from_file(file, &path)))
        };
        // The mode says which of the names count (C++ opens a file for a non-empty name).
        let _ = mode;
        let opened = open(&incoming).and_then(|i| Ok((i, open(&outgoing)?)));
        let (log_in, log_out) = match opened {
            Ok(logs) => logs,
            Err(refusal) => {
                self.notice(
                    Severity::Warning,
                    NoticeKind::RemoteLogRefused {
                        peer: label.clone(),
                    },
                    format!(
                        "{label} asked to be logged, which this server cannot do: {refusal}; \
                         connection closed (how a VRPN client learns that remote logging \
                         failed)"
                    ),
                );
                self.refusal = Some((
                    DropReason::RemoteLogRefused,
                    format!("{label}: remote logging refused"),
                ));
                return;
            }
        };
        let mut requested = RequestedLogs {
            incoming: log_in,
            outgoing: log_out,
        };
        if let Some(w) = requested.incoming.as_mut() {
            if let Some(cookie) = self.peers[slot].as_ref().and_then(|p| p.greeting_bytes()) {
                w.set_cookie(&crate::log::log_cookie_from_peer(&cookie));
            }
        }
        if let Some(w) = requested.outgoing.as_mut() {
            // What this side described to the peer in the greeting, so the log replays alone.
            let mut buf = [0u8; 128];
            for (kind, table) in [
                (system::SENDER_DESCRIPTION, &self.names.senders),
                (system::TYPE_DESCRIPTION, &self.names.types),
            ] {
                for (local, name) in table.iter() {
                    let n = system::encode_description(&mut buf, name);
                    let _ = w.log_message(kind, local, now.wall, &buf[..n]);
                }
            }
        }
        let text = format!(
            "{label} asked to be logged: {}{}{}",
            if incoming.is_empty() {
                String::new()
            } else {
                format!("what it sends in {incoming}")
            },
            if !incoming.is_empty() && !outgoing.is_empty() {
                ", "
            } else {
                ""
            },
            if outgoing.is_empty() {
                String::new()
            } else {
                format!("what it receives in {outgoing}")
            },
        );
        self.logs.any = true;
        if let Some(p) = self.peers[slot].as_mut() {
            p.requested_logs = Some(Box::new(requested));
        }
        self.notice(
            Severity::Info,
            NoticeKind::RemoteLogOpened { peer: label },
            text,
        );
    }

    /// Writes a message packed for peers into the outgoing logs peers asked for.
    pub(super) fn log_to_requested(
        &mut self,
        type_id: i32,
        sender: i32,
        time: TimeVal,
        payload: &[u8],
    ) {
        for p in self.peers.iter_mut().flatten() {
            if let Some(w) = p.requested_logs.as_mut().and_then(|r| r.outgoing.as_mut()) {
                let _ = w.log_message(type_id, sender, time, payload);
            }
        }
    }
}

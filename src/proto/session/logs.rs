//! The logs a session writes: what it receives (one file, or one per peer for a server) and
//! what it packs, in C++'s `.vrpn` format, buffered and written a bounded amount per pass.

use super::{Kind, PeerLogFactory, Session};
use crate::log::LogError;
use crate::proto::endpoint::LogSink;
use crate::proto::{NoticeKind, Severity};
use crate::time::{Now, TimeVal};
use crate::wire::system;

impl Session {
    // ------------------------------------------------------------------ logging

    pub(crate) fn log_outgoing(
        &mut self,
        type_id: i32,
        sender: i32,
        time: TimeVal,
        payload: &[u8],
    ) {
        if let Some(w) = self.logs.outgoing.as_mut() {
            if let Err(e) = w.log_message(type_id, sender, time, payload) {
                self.log_error(e.to_string());
            }
        }
    }

    /// A message this side packs: into the outgoing log and the logs peers asked for.
    #[inline(never)]
    pub(crate) fn log_packed(&mut self, type_id: i32, sender: i32, time: TimeVal, payload: &[u8]) {
        if self.logs.outgoing.is_some() {
            self.log_outgoing(type_id, sender, time, payload);
        }
        self.log_to_requested(type_id, sender, time, payload);
    }

    pub(crate) fn log_error(&mut self, e: String) {
        if !self.logs.failed {
            self.logs.failed = true;
            self.notice(
                Severity::Error,
                NoticeKind::LogFailed,
                format!("logging failed: {e}"),
            );
        }
    }

    /// Starts logging what this side receives: into `sink` for a client (one file across
    /// reconnects), or through `per_peer` for a server (one file per accepted client).
    pub fn set_incoming_log(&mut self, sink: Option<LogSink>, per_peer: Option<PeerLogFactory>) {
        self.logs.any |= sink.is_some() || per_peer.is_some();
        self.logs.incoming = sink;
        self.logs.per_peer = per_peer;
    }

    /// Starts logging everything this side packs.
    pub fn set_outgoing_log(&mut self, sink: LogSink) {
        self.logs.any = true;
        self.logs.outgoing = Some(sink);
    }

    /// Writes a bounded amount of buffered log data (called every pass; never stalls long).
    #[inline]
    pub fn flush_logs_some(&mut self, max_bytes: usize) {
        if self.logs.any {
            self.flush_some_of_each_log(max_bytes);
        }
    }

    fn flush_some_of_each_log(&mut self, max_bytes: usize) {
        let mut err = None;
        for w in self.log_sinks() {
            if w.pending() > 0 {
                if let Err(e) = w.flush_some(max_bytes) {
                    err = Some(e.to_string());
                }
            }
        }
        if let Some(e) = err {
            self.log_error(e);
        }
    }

    fn log_sinks(&mut self) -> impl Iterator<Item = &mut LogSink> {
        self.logs
            .incoming
            .iter_mut()
            .chain(self.logs.outgoing.iter_mut())
            .chain(self.peers.iter_mut().flatten().flat_map(|p| {
                let requested = p
                    .requested_logs
                    .as_deref_mut()
                    .map(|r| r.incoming.iter_mut().chain(r.outgoing.iter_mut()));
                p.log_in.iter_mut().chain(requested.into_iter().flatten())
            }))
    }

    /// Writes every buffered log byte.
    pub fn flush_logs_all(&mut self) -> Result<(), LogError> {
        for w in self.log_sinks() {
            w.flush_all()?;
        }
        Ok(())
    }

    /// Ends logging: a DISCONNECT entry closes the outgoing log (as C++ at shutdown).
    pub fn close_logs(&mut self, now: Now) -> Result<(), LogError> {
        let client = matches!(self.kind, Kind::Client(_));
        if self.logs.outgoing.is_some() && !client || self.connected > 0 {
            self.log_outgoing(system::DISCONNECT, 0, now.wall, &[]);
        }
        let r = self.flush_logs_all();
        self.logs.outgoing = None;
        self.logs.incoming = None;
        self.logs.per_peer = None;
        for p in self.peers.iter_mut().flatten() {
            p.log_in = None;
            p.requested_logs = None;
        }
        r
    }
}

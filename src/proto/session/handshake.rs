//! The greeting: cookies both ways, then our UDP port and every name we know.
//!
//! Both sides send their 24-byte cookie as soon as TCP is up. On reading the peer's cookie a
//! side checks the major version, then (unless on the TCP-only path) binds a UDP socket for
//! the peer's datagrams and announces it in a UDP description, then describes every local
//! sender and every local type, in id order — C++'s order, which a peer may rely on (senders
//! before types is how a client tells the server's own senders from echoes of its own).

use std::net::{Ipv4Addr, SocketAddrV4};

use super::{ClockIds, Kind, Session};
use crate::log::log_cookie_from_peer;
use crate::proto::clock::ClockSync;
use crate::proto::endpoint::Phase;
use crate::proto::{
    ConnectionEvent, Delivery, DropReason, IoRequest, NoticeKind, PeerId, Severity,
};
use crate::time::Now;
use crate::wire::framing::StreamDecoder;
use crate::wire::payload::clock;
use crate::wire::{class, system, Cookie};

impl Session {
    /// TCP is up: queue our cookie and start the greeting clock.
    pub(super) fn start_greeting(&mut self, now: Now, id: PeerId, local: SocketAddrV4) {
        self.timeouts_changed();
        let timeout = self.limits.handshake_timeout;
        let log_mode = self.greeting_log_mode();
        let Some(p) = self.peer_mut(id) else {
            return;
        };
        p.phase = Phase::AwaitingCookie;
        p.local = Some(local);
        p.deadline = Some(now.mono + timeout);
        let _ = p.tx.push_raw(&Cookie::ours(log_mode).to_bytes());
    }

    /// The peer's 24 bytes are in: accept or drop it.
    pub(super) fn handle_cookie(&mut self, now: Now, id: PeerId) {
        self.timeouts_changed();
        let Some(p) = self.peer(id) else {
            return;
        };
        let Some(bytes) = p.cookie() else {
            return;
        };
        let cookie = Cookie::parse(bytes).expect("24 bytes");
        let who = p.label.clone();
        if let Err(e) = cookie.check() {
            let text = if self.is_client() {
                let shown: String = bytes
                    .iter()
                    .take_while(|&&b| b != 0)
                    .map(|&b| {
                        if b.is_ascii_graphic() || b == b' ' {
                            b as char
                        } else {
                            '.'
                        }
                    })
                    .collect();
                format!(
                    "{who} answered, but not with a VRPN greeting ({e}; it sent {shown:?}): check \
                     the host and port (will keep retrying every {:?})",
                    self.limits.retry_interval
                )
            } else {
                format!("{who}: {e}")
            };
            self.drop_peer(now, id, DropReason::BadGreeting, text);
            return;
        }
        if cookie.minor_differs() {
            let t = format!(
                "{who} speaks VRPN {} and we speak {}: minor versions differ, which is not \
                 normally a problem",
                cookie.version(),
                Cookie::ours(0).version()
            );
            self.notice(Severity::Info, NoticeKind::MinorVersion { peer: who }, t);
        }
        // An incoming log carries the peer's cookie.
        let peer_cookie = log_cookie_from_peer(&cookie.to_bytes());
        let Session { peers, logs, .. } = self;
        let Some(p) = peers[id.slot].as_mut() else {
            return;
        };
        if let Some(w) = p.log_in.as_mut().or(logs.incoming.as_mut()) {
            w.set_cookie(&peer_cookie);
        }
        p.peer_version = Some(cookie.version());
        p.phase = Phase::Describing;
        p.deadline = None;
        p.rx = Some(StreamDecoder::default());
        let tcp_only = p.tcp_only;
        // A client's request to be logged goes first, as C++ sends it.
        self.send_remote_log_request(now, id);
        if tcp_only {
            self.finish_handshake(now, id, None);
        } else {
            self.io.push_back(IoRequest::BindUdp { peer: id });
        }
    }

    /// Our UDP socket for the peer is bound (or not): describe ourselves and count the peer
    /// as connected.
    pub(super) fn finish_handshake(&mut self, now: Now, id: PeerId, udp_port: Option<u16>) {
        self.timeouts_changed();
        let tv = now.wall;
        let log_handshake = matches!(self.kind, Kind::Client(_)) && self.logs.outgoing.is_some();
        let nic = self.nic;
        let Session {
            peers, names, logs, ..
        } = self;
        let Some(p) = peers[id.slot].as_mut().filter(|p| p.id == id) else {
            return;
        };
        if let Some(port) = udp_port {
            p.udp_rx = Some(Default::default());
            let local_ip = p.local.map_or(Ipv4Addr::LOCALHOST, |l| *l.ip());
            let ip = nic.unwrap_or(if local_ip.is_unspecified() {
                Ipv4Addr::LOCALHOST
            } else {
                local_ip
            });
            let ip_text = ip.to_string();
            let mut buf = [0u8; 32];
            let n = system::encode_udp_description(&mut buf, &ip_text);
            let _ = p.pack_always(
                tv,
                i32::from(port),
                system::UDP_DESCRIPTION,
                &buf[..n],
                class::RELIABLE,
            );
            if log_handshake {
                if let Some(w) = logs.outgoing.as_mut() {
                    let _ = w.log_message(system::UDP_DESCRIPTION, i32::from(port), tv, &buf[..n]);
                }
            }
        }
        let mut buf = [0u8; 128];
        for (kind, table) in [
            (system::SENDER_DESCRIPTION, &names.senders),
            (system::TYPE_DESCRIPTION, &names.types),
        ] {
            for (local, name) in table.iter() {
                let n = system::encode_description(&mut buf, name);
                let _ = p.pack_always(tv, local, kind, &buf[..n], class::RELIABLE);
                if log_handshake {
                    if let Some(w) = logs.outgoing.as_mut() {
                        let _ = w.log_message(kind, local, tv, &buf[..n]);
                    }
                }
            }
        }
        p.phase = Phase::Connected;
        p.connected_at = Some(now.mono);
        p.hold_udp(now.mono, self.limits.udp_after_descriptions);
        if let Kind::Client(c) = &mut self.kind {
            c.connected();
        }
        if self.connected == 0 {
            self.queue
                .push_back(Delivery::Event(ConnectionEvent::GotFirstConnection));
        }
        self.connected += 1;
        self.queue
            .push_back(Delivery::Event(ConnectionEvent::GotConnection));
        self.note_state();
        self.start_clock_sync(now, id);
    }

    /// Starts clock synchronisation with a peer that just connected.
    fn start_clock_sync(&mut self, now: Now, id: PeerId) {
        let Some(config) = self.limits.clock_sync else {
            return;
        };
        if matches!(self.kind, Kind::File(_) | Kind::Loopback) {
            return;
        }
        if let Some(p) = self.peer_mut(id) {
            p.clock = Some(Box::new(ClockSync::new(config, now)));
        }
    }

    /// Registers the clock-synchronisation names (describing them to every peer) the first
    /// time they are needed: before this side's first query, or when a peer describes them
    /// (it is about to query). Not earlier, so that a handshake stays byte-for-byte what C++
    /// sends.
    pub(super) fn ensure_clock_ids(&mut self, now: Now) -> Option<ClockIds> {
        if self.clock_ids.is_none() && self.limits.clock_sync.is_some() {
            let ids = ClockIds {
                sender: self.register(now, true, clock::SENDER.as_bytes()).ok()?,
                query: self.register(now, false, clock::QUERY.as_bytes()).ok()?,
                reply: self.register(now, false, clock::REPLY.as_bytes()).ok()?,
            };
            self.clock_ids = Some(ids);
        }
        self.clock_ids
    }
}

//! Turning received bytes into deliveries: framing, the cookie, system messages, id
//! translation, fairness between peers, and log replay through the same path.

use super::{Kind, Session, RESERVED_FOR_LOCAL};
use crate::proto::endpoint::{ClockPass, Phase, RemoteNames};
use crate::proto::names::NameLimit;
use crate::proto::{
    ConnectionEvent, Delivery, DropReason, IoRequest, NameKind, Notice, NoticeKind, Severity,
};
use crate::time::TimeSource;
use crate::wire::payload::clock::{Query, Reply};
use crate::wire::{self, system, MAX_IDS};

/// Where a message came from, for the rules that depend on it.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Via {
    Tcp,
    Udp,
    Log,
}

impl Session {
    /// The next thing to deliver, or `None` when everything buffered has been consumed (the
    /// shell should then read more for the peers that want it).
    #[inline]
    pub fn poll_delivery(&mut self, now: &dyn TimeSource) -> Option<Delivery> {
        if !self.input_pending
            && self.queue.is_empty()
            && self.to_describe.is_empty()
            && !matches!(self.kind, Kind::File(_))
        {
            return None;
        }
        self.poll_delivery_walk(now)
    }

    fn poll_delivery_walk(&mut self, now: &dyn TimeSource) -> Option<Delivery> {
        self.delivering_from = None;
        loop {
            if let Some(d) = self.queue.pop_front() {
                return Some(d);
            }
            if !self.to_describe.is_empty() {
                self.describe_new_names(now.now());
                continue;
            }
            if matches!(self.kind, Kind::File(_)) {
                return self.next_from_file(now);
            }
            let n = self.peers.len();
            let mut produced = false;
            let start = self.cursor.min(n);
            // Round robin from the peer served last (a plain index walk: this runs per message).
            for k in 0..n {
                let i = if start + k < n {
                    start + k
                } else {
                    start + k - n
                };
                let Some(p) = self.peers[i].as_ref() else {
                    continue;
                };
                if p.budget >= self.limits.max_messages_per_peer_per_loop {
                    continue;
                }
                let d = self.next_from_peer(now, i);
                if d.is_some() {
                    self.cursor = i;
                    if let Some(p) = self.peers[i].as_ref() {
                        self.delivering_from = Some(p.id);
                        // The only peer has nothing more buffered: the next poll need not walk
                        // (a pass that received one report would otherwise walk twice).
                        if n == 1 && p.input_drained() {
                            self.input_pending = false;
                        }
                    }
                    return d;
                }
                if !self.queue.is_empty() || !self.to_describe.is_empty() {
                    produced = true;
                    self.cursor = i;
                    break;
                }
            }
            if !produced {
                self.input_pending = false;
                return None;
            }
        }
    }

    /// The next delivery from the bytes buffered for the peer in `slot`.
    ///
    /// Every message taken counts against the peer's budget for the pass, whether or not it
    /// brings a delivery (clock queries, descriptions and messages of unknown types bring
    /// none), so no peer keeps a pass busy: once it is spent, the rest waits for the next.
    ///
    /// The steady-state path (a described message on the stream or in a datagram) stays in
    /// this function; set-up and every kind of bad input are handled out of line.
    fn next_from_peer(&mut self, now: &dyn TimeSource, slot: usize) -> Option<Delivery> {
        let budget = self.limits.max_messages_per_peer_per_loop;
        loop {
            let p = self.peers[slot].as_mut()?;
            match p.phase {
                Phase::Connecting => return None,
                Phase::AwaitingCookie => match self.cookie_step(now, slot) {
                    Some(d) => return d,
                    None => continue,
                },
                Phase::Describing | Phase::Connected => {}
            }
            if p.budget >= budget {
                return None;
            }
            let rx = p.rx.as_mut()?;
            match rx.next_message() {
                Some(Ok((h, payload))) => {
                    let len = payload.len();
                    self.scratch[..len].copy_from_slice(payload);
                    p.budget += 1;
                    // Returned as built (a delivery copied on its way out would be read
                    // back before its stores land: see handle_message).
                    let d = self.handle_message(slot, h, len, Via::Tcp, now);
                    if d.is_some() {
                        return d;
                    }
                    if let Some(reason) = self.refusal.take() {
                        return self.drop_for(now, slot, reason);
                    }
                    if self.clock_names_seen && self.clock_ids.is_none() {
                        self.ensure_clock_ids(now.now());
                    }
                    if !self.queue.is_empty() || !self.to_describe.is_empty() {
                        return None;
                    }
                    continue;
                }
                Some(Err(e)) => return self.malformed_stream(now, slot, e),
                None => {}
            }
            // Then the datagrams received for this peer.
            let p = self.peers[slot].as_mut()?;
            if p.phase != Phase::Connected {
                return None;
            }
            let peer_ip = *p.addr.ip();
            let named = self.limits.callback_to_named_address;
            let pin = !named && !p.udp_source_pinned;
            let inbox = p.udp_rx.as_mut()?;
            if inbox.is_drained() {
                return None;
            }
            if !named && *inbox.current_source().ip() != peer_ip {
                match self.foreign_datagram(slot) {
                    Some(d) => return d,
                    None => continue,
                }
            }
            if pin {
                let source = inbox.current_source();
                self.pin_udp_source(slot, source);
                continue;
            }
            let dg = inbox.current();
            let mut it = wire::DatagramMessages::new(dg);
            match it.next() {
                Some(Ok((h, payload))) => {
                    let advance = h.wire_size().min(dg.len());
                    let len = payload.len();
                    self.scratch[..len].copy_from_slice(payload);
                    inbox.advance(advance);
                    p.budget += 1;
                    let d = self.handle_message(slot, h, len, Via::Udp, now);
                    if d.is_some() {
                        return d;
                    }
                    if let Some(reason) = self.refusal.take() {
                        return self.drop_for(now, slot, reason);
                    }
                    if !self.queue.is_empty() || !self.to_describe.is_empty() {
                        return None;
                    }
                }
                Some(Err(e)) => return self.malformed_datagram(slot, e),
                None => inbox.skip_datagram(),
            }
        }
    }

    /// A peer that has not sent its cookie yet: check it once it is all here. `None` to go
    /// on walking the peer's bytes, `Some(d)` to return `d`.
    #[inline(never)]
    fn cookie_step(&mut self, now: &dyn TimeSource, slot: usize) -> Option<Option<Delivery>> {
        let p = self.peers[slot].as_mut()?;
        let id = p.id;
        if p.cookie().is_none() {
            return Some(None);
        }
        self.handle_cookie(now.now(), id);
        if !self.queue.is_empty() {
            return Some(self.queue.pop_front());
        }
        None
    }

    /// Drops the peer in `slot` for breaking the protocol.
    #[cold]
    #[inline(never)]
    fn drop_for(
        &mut self,
        now: &dyn TimeSource,
        slot: usize,
        (reason, text): (DropReason, String),
    ) -> Option<Delivery> {
        let id = self.peers[slot].as_ref()?.id;
        self.drop_peer(now.now(), id, reason, text);
        self.queue.pop_front()
    }

    /// The peer's stream cannot be framed any more: drop it.
    #[cold]
    #[inline(never)]
    fn malformed_stream(
        &mut self,
        now: &dyn TimeSource,
        slot: usize,
        e: wire::WireError,
    ) -> Option<Delivery> {
        let p = self.peers[slot].as_ref()?;
        let (id, text) = (p.id, format!("malformed message from {}: {e}", p.label));
        self.drop_peer(now.now(), id, DropReason::Malformed, text);
        self.queue.pop_front()
    }

    /// Only the peer may speak on its UDP channel: a datagram from anyone else is dropped
    /// unread (it could otherwise inject messages into the session). Returns as
    /// [`cookie_step`](Self::cookie_step).
    #[cold]
    #[inline(never)]
    fn foreign_datagram(&mut self, slot: usize) -> Option<Option<Delivery>> {
        let p = self.peers[slot].as_mut()?;
        let inbox = p.udp_rx.as_mut()?;
        let source = inbox.current_source();
        inbox.skip_datagram();
        p.foreign_datagrams += 1;
        if p.foreign_datagrams == 1 {
            let text = format!(
                "ignoring UDP datagrams sent to {}'s channel from another address ({source})",
                p.label
            );
            let kind = NoticeKind::ForeignDatagrams {
                peer: p.label.clone(),
                from: source,
            };
            self.notice(Severity::Warning, kind, text);
            return Some(self.queue.pop_front());
        }
        None
    }

    /// The first datagram from the peer's own address: ask the shell to pin its source (see
    /// [`IoRequest::PinUdpSource`]), once.
    #[cold]
    #[inline(never)]
    fn pin_udp_source(&mut self, slot: usize, source: std::net::SocketAddrV4) {
        if let Some(p) = self.peers[slot].as_mut() {
            p.udp_source_pinned = true;
            let peer = p.id;
            self.io.push_back(IoRequest::PinUdpSource { peer, source });
        }
    }

    /// A datagram that does not frame: C++ drops the whole connection; we drop the datagram.
    #[cold]
    #[inline(never)]
    fn malformed_datagram(&mut self, slot: usize, e: wire::WireError) -> Option<Delivery> {
        let p = self.peers[slot].as_mut()?;
        let inbox = p.udp_rx.as_mut()?;
        inbox.skip_datagram();
        let t = format!("discarded a malformed UDP datagram from {}: {e}", p.label);
        let peer = p.label.clone();
        self.notice(Severity::Warning, NoticeKind::MalformedDatagram { peer }, t);
        self.queue.pop_front()
    }

    /// The next entry of a replayed log that is due, through the same handling as a live
    /// peer's message.
    fn next_from_file(&mut self, now: &dyn TimeSource) -> Option<Delivery> {
        loop {
            let Kind::File(replay) = &mut self.kind else {
                return None;
            };
            if replay.take_reset() {
                if let Some(p) = self.peers[0].as_mut() {
                    p.senders.clear();
                    p.types.clear();
                }
                return Some(Delivery::Event(ConnectionEvent::DroppedConnection));
            }
            let Some(due) = replay.next_due() else {
                // A jump ends where nothing more is due.
                self.replay_skipping = false;
                if let Some(e) = replay.take_error() {
                    let text = format!(
                        "replay stopped at damaged data (every whole message before it was \
                         played): {e}"
                    );
                    return Some(Delivery::Notice(Notice::new(
                        Severity::Error,
                        NoticeKind::ReplayDamaged,
                        text,
                    )));
                }
                return None;
            };
            let payload = replay.payload(&due);
            let len = payload.len();
            self.scratch[..len].copy_from_slice(payload);
            if let Some(w) = self.logs.incoming.as_mut() {
                // Re-log of a replay: original entry, playback wall-clock time (as C++).
                let _ = w.log_message(
                    due.header.type_id,
                    due.header.sender,
                    now.now().wall,
                    &self.scratch[..len],
                );
            }
            let h = wire::Header {
                payload_len: len,
                time: due.header.time(),
                sender: due.header.sender,
                type_id: due.header.type_id,
                seq: 0,
            };
            let d = self.handle_message(0, h, len, Via::Log, now);
            if d.is_some() && !self.replay_skipping {
                return d;
            }
            if let Some((reason, text)) = self.refusal.take() {
                // A log cannot be dropped: say what was wrong and play on.
                let peer = self.peers[0].as_ref().map(|p| p.label.clone());
                let peer = peer.unwrap_or_default();
                self.notice(
                    Severity::Warning,
                    NoticeKind::PeerDropped { peer, reason },
                    text,
                );
            }
            if !self.to_describe.is_empty() {
                self.describe_new_names(now.now());
            }
            if let Some(d) = self.queue.pop_front() {
                return Some(d);
            }
        }
    }

    /// Interprets one message whose payload is in `scratch[..len]`: system messages update
    /// tables; user messages are translated and returned for delivery.
    ///
    /// Device reports take the short way (`handle_user_message`); system messages, which
    /// come during set-up, have a function of their own. A refusal (the peer must be
    /// dropped) is left in `refusal`.
    ///
    /// The delivery is returned as it was built, up to the walk's caller: unpacking it from
    /// another enum on the way (as an earlier version did) copied it with wide loads right
    /// after its fields were stored one by one, which the CPU cannot forward from its store
    /// buffer; that stall cost more than the rest of the message's handling.
    #[inline(always)]
    fn handle_message(
        &mut self,
        slot: usize,
        h: wire::Header,
        len: usize,
        via: Via,
        now: &dyn TimeSource,
    ) -> Option<Delivery> {
        let Session {
            peers,
            logs,
            scratch,
            limits,
            refusal,
            ..
        } = self;
        let p = peers[slot].as_mut()?;
        if logs.any && via != Via::Log {
            if let Some(w) = p.log_in.as_mut().or(logs.incoming.as_mut()) {
                let _ = w.log_message(h.type_id, h.sender, h.time, &scratch[..len]);
            }
            if let Some(w) = p.requested_logs.as_mut().and_then(|r| r.incoming.as_mut()) {
                let _ = w.log_message(h.type_id, h.sender, h.time, &scratch[..len]);
            }
        }
        if len > limits.max_message_payload {
            return oversized(refusal, &p.label, len, limits.max_message_payload);
        }
        if h.type_id < 0 {
            return self.handle_system_message(slot, h, len, via, now);
        }
        self.handle_user_message(slot, h, len, via, now)
    }

    /// A message of the protocol itself (negative type id).
    #[inline(never)]
    fn handle_system_message(
        &mut self,
        slot: usize,
        h: wire::Header,
        len: usize,
        via: Via,
        now: &dyn TimeSource,
    ) -> Option<Delivery> {
        if matches!(
            h.type_id,
            system::SENDER_DESCRIPTION | system::TYPE_DESCRIPTION
        ) {
            return self.handle_description(slot, h, len);
        }
        if h.type_id == system::LOG_DESCRIPTION {
            if via != Via::Log {
                self.handle_log_request(slot, h.sender, len, now.now());
            }
            return None;
        }
        let Session {
            peers,
            scratch,
            limits,
            ..
        } = self;
        let p = peers[slot].as_mut()?;
        let payload = &scratch[..len];
        match h.type_id {
            system::UDP_DESCRIPTION => {
                if via != Via::Tcp || p.tcp_only {
                    // Only the peer's own TCP stream may set its UDP channel (a datagram could
                    // come from anyone); replayed logs open nothing.
                    return None;
                }
                let Ok(host) = system::decode_udp_description(payload) else {
                    return None;
                };
                let port = h.sender;
                if !(1..=65535).contains(&port) {
                    return None;
                }
                // The datagrams go to the peer's own address unless the server was set up for
                // multi-homed clients; a host name is never resolved in the loop.
                let ip = match (limits.callback_to_named_address, host.parse()) {
                    (true, Ok(ip)) => ip,
                    _ => *p.addr.ip(),
                };
                p.udp_ready = false;
                let addr = std::net::SocketAddrV4::new(ip, port as u16);
                let id = p.id;
                self.io.push_back(IoRequest::OpenUdpOut { peer: id, addr });
                None
            }
            system::DISCONNECT => {
                p.senders.clear();
                p.types.clear();
                None
            }
            _ => None,
        }
    }

    /// A message of a device or an application: translate its ids (and its time, when the
    /// peer's clock is known) and deliver it.
    #[inline(always)]
    fn handle_user_message(
        &mut self,
        slot: usize,
        h: wire::Header,
        len: usize,
        via: Via,
        now: &dyn TimeSource,
    ) -> Option<Delivery> {
        let Session {
            peers, clock_ids, ..
        } = self;
        let p = peers[slot].as_mut()?;
        let local_type = p.types.lookup(h.type_id);
        if local_type < 0 {
            return None; // never described: ignored, as C++ does
        }
        if let Some(ids) = clock_ids.filter(|ids| ids.is_clock_type(local_type)) {
            if via != Via::Log {
                return self.handle_clock_message(slot, ids, local_type, len, now);
            }
            return None;
        }
        let local_sender = p.senders.lookup(h.sender);
        // In local time when the peer's clock is known. The translation of this stretch of
        // time comes first (used in place; the session clears it when a reply changes the
        // estimate or its reuse limit passes); only without one is the estimator asked, a
        // cheap test for a peer that never answered (a C++ one).
        let time = match &mut p.clock_pass {
            Some(pass) => pass.translate(h.time),
            None => match p.clock.as_deref() {
                Some(c) if c.has_estimate() => {
                    let (translation, until) = c.translation_until(now.now());
                    let mut pass = ClockPass {
                        translation,
                        until,
                        last: None,
                    };
                    let time = pass.translate(h.time);
                    p.clock_pass = Some(pass);
                    // Its limit is a deadline of the session.
                    self.timeout_cache.set(None);
                    time
                }
                _ => h.time,
            },
        };
        Some(Delivery::Message {
            time,
            sender_time: h.time,
            sender: local_sender,
            type_id: local_type,
            len,
        })
    }

    /// A sender or type description: learn the name, map the peer's id to ours.
    fn handle_description(&mut self, slot: usize, h: wire::Header, len: usize) -> Option<Delivery> {
        let is_sender = h.type_id == system::SENDER_DESCRIPTION;
        let kind = NameKind::of(is_sender);
        let Session {
            peers,
            names,
            scratch,
            limits,
            to_describe,
            queue,
            names_refused,
            clock_names_seen,
            refusal,
            ..
        } = self;
        let p = peers[slot].as_mut()?;
        // The id first: a description with an id no C++ peer could send is a protocol error,
        // and must not leave its name behind in our table.
        if !RemoteNames::valid_id(h.sender) {
            return refuse(
                refusal,
                DropReason::BadDescription,
                format!(
                    "{} described id {} outside VRPN's 0..{MAX_IDS} range",
                    p.label, h.sender
                ),
            );
        }
        let name = match system::decode_description_bytes(&scratch[..len]) {
            Ok(n) => n,
            Err(e) => {
                let text = format!("bad description from {}: {e}", p.label);
                return refuse(refusal, DropReason::BadDescription, text);
            }
        };
        if !is_sender
            && (name == wire::payload::clock::QUERY.as_bytes()
                || name == wire::payload::clock::REPLY.as_bytes())
        {
            // A peer that takes part in clock synchronisation: our names must exist before
            // its first query arrives (right after this description).
            *clock_names_seen = true;
        }
        let completes = !is_sender && !p.senders_complete;
        if completes {
            p.senders_complete = true;
            queue.push_back(Delivery::PeerSendersComplete);
        }
        let table = names.table(is_sender);
        let remote = if is_sender {
            &mut p.senders
        } else {
            &mut p.types
        };
        let already = table.get(name);
        // Counted: a name new here, or an id bound before and now bound to another name. A
        // known name given to an unbound id (each session of a log after its DISCONNECT entry
        // describes the same names again) costs nothing and is not counted.
        let bound = remote.lookup(h.sender);
        let rebinds = already.map_or(true, |l| bound >= 0 && bound != l);
        if rebinds {
            remote.described += 1;
            if remote.described > limits.max_names_per_peer {
                let limit = limits.max_names_per_peer;
                return refuse(
                    refusal,
                    DropReason::TooManyNames { kind, limit },
                    format!(
                        "{} described more than {limit} {kind} names (Limits::max_names_per_peer)",
                        p.label
                    ),
                );
            }
        }
        let room = table.learned_count() < MAX_IDS - RESERVED_FOR_LOCAL;
        let local = match table.learn(name, room) {
            Ok((local, new, held)) => {
                if held && !remote.held.insert(local) {
                    // Described again under another id: the peer holds the name only once.
                    table.release(local);
                }
                if new {
                    to_describe.push((is_sender, local));
                }
                local
            }
            Err(NameLimit::TableFull) => {
                // No room: the name stays unknown here (its messages are ignored, as those of
                // an undescribed name), and nobody is dropped for it.
                remote.bind(h.sender, -1);
                *names_refused += 1;
                if *names_refused == 1 || names_refused.is_power_of_two() {
                    let text = format!(
                        "no room for {kind} name {:?} from {} ({} names refused so far: the \
                         name table is full of names peers described); its messages are \
                         ignored",
                        String::from_utf8_lossy(name),
                        p.label,
                        names_refused
                    );
                    queue.push_back(Delivery::Notice(Notice::new(
                        Severity::Warning,
                        NoticeKind::NameTableFull { kind },
                        text,
                    )));
                }
                return None;
            }
            Err(e) => {
                return refuse(
                    refusal,
                    DropReason::BadDescription,
                    format!("{} described a name we cannot hold: {e}", p.label),
                )
            }
        };
        remote.bind(h.sender, local);
        if is_sender {
            // A sender is one the peer offers if it is in the peer's own table (described
            // before its first type) or a name this side never registered. The control and
            // clock-sync senders are the protocol's own, not devices.
            let own = !p.senders_complete || !names.senders.is_registered(local);
            let device = !crate::proto::names::is_protocol_sender(name);
            if own && device && p.offered.insert(local) {
                return Some(Delivery::PeerSender(local));
            }
        }
        None
    }

    /// A clock query (answered to this peer only, with the time it arrived and the time the
    /// answer leaves) or a reply (given to this peer's estimator). Never delivered to handlers.
    fn handle_clock_message(
        &mut self,
        slot: usize,
        ids: super::ClockIds,
        local_type: i32,
        len: usize,
        now: &dyn TimeSource,
    ) -> Option<Delivery> {
        let payload = &self.scratch[..len];
        let p = self.peers[slot].as_mut()?;
        if local_type == ids.query {
            // A foreign or future layout is ignored, never a reason to drop the peer.
            let Ok(q) = Query::decode(payload) else {
                return None;
            };
            // t2 and t3: after the query's bytes were read (the pass's clock may be older).
            let at = now.fresh().wall;
            let reply = Reply::answer(&q, at, at);
            let mut buf = [0u8; Reply::LEN];
            let n = reply.encode(&mut buf);
            let _ = p.pack(
                at,
                ids.sender,
                ids.reply,
                &buf[..n],
                crate::wire::class::LOW_LATENCY,
            );
        } else if local_type == ids.reply {
            let Ok(r) = Reply::decode(payload) else {
                return None;
            };
            // The peer has read what went before the query: unreliable messages may take UDP.
            let hold_ended = p.note_clock_reply(r.id);
            if let Some(c) = p.clock.as_deref_mut() {
                // t4: after the reply's bytes were read.
                c.handle_reply(&r, now.fresh());
                p.clock_pass = None;
                self.timeouts_changed();
            } else if hold_ended {
                self.timeouts_changed();
            }
        }
        None
    }
}

/// Records why the peer must be dropped (taken by the caller from `Session::refusal`); nothing
/// to deliver.
#[cold]
#[inline(never)]
fn refuse(
    refusal: &mut Option<(DropReason, String)>,
    reason: DropReason,
    text: String,
) -> Option<Delivery> {
    *refusal = Some((reason, text));
    None
}

/// The refusal of a message over [`Limits::max_message_payload`](crate::Limits).
#[cold]
#[inline(never)]
fn oversized(
    refusal: &mut Option<(DropReason, String)>,
    label: &str,
    len: usize,
    limit: usize,
) -> Option<Delivery> {
    refuse(
        refusal,
        DropReason::Oversized { len, limit },
        format!(
            "{label} sent a {len}-byte message; the limit is {limit} bytes \
             (Limits::max_message_payload)"
        ),
    )
}

//! Names and sending: registering and describing names, packing messages to every peer with
//! its channel and shedding policy, and dropping peers.

use super::{Kind, Session};
use crate::proto::buffers::Backlogged;
use crate::proto::endpoint::{Channel, Endpoint, Phase};
use crate::proto::names::NameLimit;
use std::collections::VecDeque;

use crate::proto::{
    ConnectionEvent, Delivery, DropReason, IoRequest, Notice, NoticeKind, PeerId, Severity,
};
use crate::time::{Now, TimeVal};
use crate::wire::header::{encode_message, Header};
use crate::wire::{class, system};

impl Session {
    // ------------------------------------------------------------------ names

    /// Registers a sender (`true`) or type name for this side and describes it to every
    /// connected peer when it is new.
    pub fn register(&mut self, now: Now, is_sender: bool, name: &[u8]) -> Result<i32, NameLimit> {
        let (id, new) = self.names.table(is_sender).register(name)?;
        if new {
            self.describe_to_all(now, is_sender, id);
        }
        Ok(id)
    }

    /// The name of a local sender (`true`) or type id, as bytes.
    pub fn name_of(&self, is_sender: bool, id: i32) -> Option<&[u8]> {
        if is_sender {
            self.names.senders.name(id)
        } else {
            self.names.types.name(id)
        }
    }

    /// The local id of a name, if known.
    pub fn id_of(&self, is_sender: bool, name: &[u8]) -> Option<i32> {
        if is_sender {
            self.names.senders.get(name)
        } else {
            self.names.types.get(name)
        }
    }

    /// Sends one description to every connected peer (and the outgoing log).
    pub(crate) fn describe_to_all(&mut self, now: Now, is_sender: bool, id: i32) {
        let names = &self.names;
        let name = if is_sender {
            names.senders.name(id)
        } else {
            names.types.name(id)
        };
        let Some(name) = name else {
            return;
        };
        let mut buf = [0u8; 128];
        let n = system::encode_description(&mut buf, name);
        let t = if is_sender {
            system::SENDER_DESCRIPTION
        } else {
            system::TYPE_DESCRIPTION
        };
        let replay = self.is_replay();
        let hold = self.limits.udp_after_descriptions;
        for p in self.peers.iter_mut().flatten() {
            if !(replay && p.id.slot == 0) {
                let _ = p.pack(now.wall, id, t, &buf[..n], class::RELIABLE);
                p.hold_udp(now.mono, hold);
            }
        }
        self.timeouts_changed();
        self.log_outgoing(t, id, now.wall, &buf[..n]);
    }

    /// Describes names that peers taught us to every connected peer (the C++ echo).
    pub(crate) fn describe_new_names(&mut self, now: Now) {
        let list = std::mem::take(&mut self.to_describe);
        for &(is_sender, id) in &list {
            self.describe_to_all(now, is_sender, id);
        }
        self.to_describe = list;
        self.to_describe.clear();
    }

    // ------------------------------------------------------------------ sending

    /// Queues a message to every connected peer. Returns true when a peer's reliable backlog
    /// overflowed: the caller then calls [`drop_backlogged`](Self::drop_backlogged) with the
    /// time (the only path here that needs it). A peer that falls behind sheds unreliable
    /// messages first, with a notice.
    #[inline]
    pub fn pack(
        &mut self,
        time: TimeVal,
        sender: i32,
        type_id: i32,
        payload: &[u8],
        class_of_service: u32,
    ) -> bool {
        // Inline: an in-process connection has no log and no peer, and this is all it pays.
        if self.logs.any {
            self.log_packed(type_id, sender, time, payload);
        }
        if !self.peers.is_empty() {
            self.pack_to_peers(time, sender, type_id, payload, class_of_service);
        }
        self.backlogged.is_some()
    }

    /// Queues a message to the one peer `to` (a reply to its request), logged as any packed
    /// message. Returns what [`pack`](Self::pack) returns; a peer gone meanwhile gets nothing.
    pub fn pack_to(
        &mut self,
        to: PeerId,
        time: TimeVal,
        sender: i32,
        type_id: i32,
        payload: &[u8],
        class_of_service: u32,
    ) -> bool {
        if self.logs.any {
            self.log_packed(type_id, sender, time, payload);
        }
        let Session {
            peers,
            backlogged,
            queue,
            ..
        } = self;
        let Some(p) = peers.get_mut(to.slot).and_then(|p| p.as_mut()) else {
            return false;
        };
        if p.id != to {
            return false;
        }
        let r = p.pack(time, sender, type_id, payload, class_of_service);
        note_pack_result(r, p, backlogged, queue);
        backlogged.is_some()
    }

    /// Queues a message to every connected peer. The message is encoded once and each peer
    /// gets a copy of those bytes with its own sequence number: the ids in it are this side's,
    /// so nothing else differs between peers (a server with 255 clients used to spend a third
    /// of its time encoding every report 255 times).
    fn pack_to_peers(
        &mut self,
        time: TimeVal,
        sender: i32,
        type_id: i32,
        payload: &[u8],
        class_of_service: u32,
    ) {
        let replay = self.is_replay();
        let Session {
            peers,
            backlogged,
            queue,
            encoded,
            ..
        } = self;
        let h = Header {
            payload_len: payload.len(),
            time,
            sender,
            type_id,
            seq: 0,
        };
        let Some(len) = encode_message(encoded, &h, payload) else {
            // Only a payload past the wire's limit gets here (the in-process connection has no
            // buffer, and no peers either); the peers' own checks decide what becomes of it.
            for p in peers.iter_mut().flatten() {
                if !(replay && p.id.slot == 0) {
                    let r = p.pack(time, sender, type_id, payload, class_of_service);
                    note_pack_result(r, p, backlogged, queue);
                }
            }
            return;
        };
        let msg = &encoded[..len];
        for p in peers.iter_mut().flatten() {
            if replay && p.id.slot == 0 {
                continue;
            }
            let r = p.pack_encoded(msg, class_of_service);
            note_pack_result(r, p, backlogged, queue);
        }
    }

    /// Drops the peer whose reliable backlog overflowed in [`pack`](Self::pack).
    pub fn drop_backlogged(&mut self, now: Now) {
        let Some(id) = self.backlogged.take() else {
            return;
        };
        let limit = self.limits.max_pending_output;
        let who = self.peer(id).map(|p| p.label.clone()).unwrap_or_default();
        self.drop_peer(
            now,
            id,
            DropReason::NotReading { limit },
            format!("{who} is not reading: more than {limit} bytes of reliable output pending"),
        );
    }

    /// Reliable bytes queued for peers and not yet written.
    pub fn pending_output(&self) -> usize {
        self.peers
            .iter()
            .flatten()
            .map(|p| p.tx.pending_len())
            .sum()
    }

    // ------------------------------------------------------------------ drops

    /// Forgets a peer: releases the names it held, asks the shell to close its sockets, fires
    /// the dropped events if it had connected, and (client) schedules the next attempt. The
    /// notice (when one is due) says `text` and carries `reason`.
    pub(crate) fn drop_peer(&mut self, now: Now, id: PeerId, reason: DropReason, text: String) {
        self.timeouts_changed();
        let Some(mut p) = self
            .peers
            .get_mut(id.slot)
            .and_then(|s| s.take_if(|p| p.id == id))
        else {
            return;
        };
        let was_connected = p.phase == Phase::Connected;
        p.senders
            .held
            .drain(|local| self.names.senders.release(local));
        p.types.held.drain(|local| self.names.types.release(local));
        self.io.push_back(IoRequest::Close { peer: id });
        let limits = self.limits;
        let is_client = matches!(self.kind, Kind::Client(_));
        let mut explain = true;
        if let Kind::Client(c) = &mut self.kind {
            c.seq = (p.seq_tcp, p.seq_udp);
            if was_connected {
                c.dropped(now.mono, p.connected_at.unwrap_or(now.mono), &limits);
            } else {
                explain = c.failed(now.mono, reason, &limits);
            }
        }
        let peer = std::mem::take(&mut p.label);
        drop(p);
        if is_client && was_connected {
            self.log_outgoing(system::DISCONNECT, 0, now.wall, &[]);
        }
        let severity = if is_client {
            Severity::Warning
        } else {
            Severity::Info
        };
        if explain {
            let text = if is_client && was_connected {
                format!("{text}; reconnecting")
            } else {
                text
            };
            self.notice(severity, NoticeKind::PeerDropped { peer, reason }, text);
        }
        if was_connected {
            self.connected -= 1;
            self.queue
                .push_back(Delivery::Event(ConnectionEvent::DroppedConnection));
            if self.connected == 0 {
                self.queue
                    .push_back(Delivery::Event(ConnectionEvent::DroppedLastConnection));
            }
        }
        self.note_state();
    }
}

/// Notes what packing for one peer came to: the first peer whose reliable backlog overflowed
/// (dropped by [`Session::drop_backlogged`]), and a notice when a peer first sheds unreliable
/// traffic.
#[inline]
fn note_pack_result(
    r: Result<Channel, Backlogged>,
    p: &Endpoint,
    backlogged: &mut Option<PeerId>,
    queue: &mut VecDeque<Delivery>,
) {
    match r {
        Err(_) => {
            if backlogged.is_none() {
                *backlogged = Some(p.id);
            }
        }
        // Say so once per peer, when it first sheds unreliable traffic.
        Ok(Channel::Discarded) if p.unreliable_dropped == 1 => {
            falling_behind(queue, &p.label, p.tx.pending_len());
        }
        Ok(_) => {}
    }
}

/// The notice a peer gets when it starts shedding unreliable traffic (once per peer).
#[cold]
#[inline(never)]
fn falling_behind(queue: &mut VecDeque<Delivery>, who: &str, pending: usize) {
    queue.push_back(Delivery::Notice(Notice::new(
        Severity::Warning,
        NoticeKind::FallingBehind {
            peer: who.to_string(),
        },
        format!(
            "{who} is falling behind ({pending} bytes of output pending): dropping its \
             unreliable messages while the backlog exceeds half of Limits::max_pending_output"
        ),
    )));
}

//! Re-serving an upstream imager under another name, in the server's own loop (what C++
//! `vrpn_Imager_Stream_Buffer` does with a second thread): frames pass through at full rate
//! while the clients keep up, and are dropped whole, with a discarded-frames notice, while
//! they do not or while a client's throttle says so.

use std::cell::RefCell;
use std::rc::{Rc, Weak};
use std::time::{Duration, Instant};

use super::{ImagerIds, ImagerRemote, ImagerServer};
use crate::connection::{Connection, ConnectionEvent, ConnectionOptions};
use crate::devices::base::BaseIds;
use crate::devices::text::TextSeverity;
use crate::devices::ServerDevice;
use crate::dispatch::{HandlerId, Message, SenderFilter, TypeId};
use crate::error::Error;
use crate::name::DeviceName;
use crate::time::Now;
use crate::wire::class;
use crate::wire::payload::imager::{DiscardedFrames, ThrottleFrames};
use crate::wire::payload::text::{PONG_MESSAGE, TEXT_MESSAGE};

/// How long the upstream imager has to describe itself before the clients are warned.
const DESCRIPTION_WAIT: Duration = Duration::from_secs(3);
/// The least output backlog that counts as a full queue (C++ allows two frames queued).
const MIN_BACKLOG: usize = 64 * 1024;

/// The upstream side while a client is connected.
struct Upstream {
    conn: Connection,
    remote: ImagerRemote,
    /// Upstream type ids: the nine imager types, text, pong.
    ids: ImagerIds,
    text: TypeId,
    pong: TypeId,
    forward: HandlerId,
    /// Warn the clients if no description came by then.
    warn_at: Option<Instant>,
}

struct State {
    name: String,
    /// The upstream imager's name (`Name@host:port`, or a name on this server).
    upstream_name: String,
    server_conn: Connection,
    ids: ImagerIds,
    base: BaseIds,
    upstream: Option<Upstream>,
    /// Frames the clients' throttle still allows (-1: no limit).
    frames_to_send: i32,
    /// Frames dropped since the last one forwarded.
    dropped: u16,
    dropped_total: u64,
    /// Bytes forwarded for the frame in progress, and for the last whole one.
    frame_bytes: usize,
    last_frame_bytes: usize,
}

impl State {
    fn text(&self, severity: TextSeverity, text: &str) {
        let _ = self
            .server_conn
            .send_text(self.base.sender, severity, 0, text);
    }

    fn pack(&mut self, m: &Message<'_>, type_id: TypeId) {
        self.frame_bytes += m.payload.len();
        let _ = self.server_conn.pack_message(
            m.sender_time,
            type_id,
            self.base.sender,
            m.payload,
            class::RELIABLE,
        );
    }

    /// One message from the upstream imager (C++ `handle_server_messages`).
    fn forward(&mut self, m: &Message<'_>) {
        let Some(up) = &self.upstream else { return };
        let (u, text, pong) = (up.ids, up.text, up.pong);
        let t = m.type_id;
        if t == u.begin_frame {
            let backlog = self.server_conn.pending_output();
            let full = backlog > MIN_BACKLOG.max(2 * self.last_frame_bytes);
            if self.frames_to_send == 0 || full {
                self.dropped = self.dropped.saturating_add(1);
                self.dropped_total += 1;
                return;
            }
            if self.dropped > 0 {
                let mut buf = [0u8; DiscardedFrames::LEN];
                DiscardedFrames {
                    count: self.dropped,
                }
                .encode(&mut buf);
                let _ = self.server_conn.pack_message(
                    m.sender_time,
                    self.ids.discarded_frames,
                    self.base.sender,
                    &buf,
                    class::RELIABLE,
                );
                self.dropped = 0;
            }
            if self.frames_to_send > 0 {
                self.frames_to_send -= 1;
            }
            self.frame_bytes = 0;
            self.pack(m, self.ids.begin_frame);
        } else if t == u.end_frame {
            if self.dropped == 0 {
                self.pack(m, self.ids.end_frame);
                self.last_frame_bytes = self.frame_bytes;
            }
        } else if let Some(ours) = [
            (u.region_u8, self.ids.region_u8),
            (u.region_u16, self.ids.region_u16),
            (u.region_u12in16, self.ids.region_u12in16),
            (u.region_f32, self.ids.region_f32),
        ]
        .iter()
        .find(|(up_t, _)| *up_t == t)
        .map(|(_, ours)| *ours)
        {
            if self.dropped == 0 {
                self.pack(m, ours);
            }
        } else if t == u.discarded_frames {
            self.pack(m, self.ids.discarded_frames);
        } else if t == text {
            self.pack(m, self.base.text);
        } else if t == pong {
            self.pack(m, self.base.pong);
        } else if t == u.description || t == u.throttle_frames || t == up.remote.base_ids().ping {
            // The description reaches the clients through our own (ImagerServer), sent when
            // the remote has decoded it; pings and throttles are never sent by a server.
        } else {
            let what = format!("Unknown message type from server: {}", t.0);
            self.text(TextSeverity::Error, &what);
        }
    }

    fn throttle(&mut self, frames: i32) {
        if frames < 0 {
            self.frames_to_send = -1;
        } else if self.frames_to_send == -1 {
            self.frames_to_send = frames;
        } else {
            self.frames_to_send = self.frames_to_send.saturating_add(frames);
        }
    }
}

/// Opens the upstream imager for the first client (C++ starts its logging thread then).
fn open_upstream(state: &Rc<RefCell<State>>, server: &Rc<ImagerServer>) -> Result<(), Error> {
    let (name, server_conn) = {
        let s = state.borrow();
        if s.upstream.is_some() {
            return Ok(());
        }
        (s.upstream_name.clone(), s.server_conn.clone())
    };
    let (device, conn) = if name.contains('@') {
        let parsed = DeviceName::parse(&name)?;
        let options = ConnectionOptions {
            reactor: server_conn.reactor(),
            private: true,
            ..ConnectionOptions::default()
        };
        let conn = Connection::open_location_with(&parsed, &options)?;
        (parsed.device, conn)
    } else {
        (name.clone(), server_conn.clone())
    };
    let remote = ImagerRemote::on_connection(&device, &conn)?;
    let ids = ImagerIds::register(&conn)?;
    let sender = remote.sender();
    let (text, pong) = (
        conn.register_type(TEXT_MESSAGE)?,
        conn.register_type(PONG_MESSAGE)?,
    );
    let (st, srv) = (Rc::downgrade(state), Rc::downgrade(server));
    remote.on_description(move |d| {
        let (Some(st), Some(srv)) = (st.upgrade(), srv.upgrade()) else {
            return;
        };
        if let Some(up) = st.borrow_mut().upstream.as_mut() {
            up.warn_at = None;
        }
        let channels: Vec<_> = {
            let st = st.borrow();
            let up = st.upstream.as_ref();
            (0..d.channels)
                .filter_map(|i| up.and_then(|u| u.remote.channel(i)))
                .collect()
        };
        let _ = srv.set_description(d.cols, d.rows, d.depth, &channels);
        srv.set_announce(true);
    });
    let st: Weak<RefCell<State>> = Rc::downgrade(state);
    let forward = conn.register_any_type_handler(SenderFilter::Only(sender), move |m| {
        if let Some(st) = st.upgrade() {
            if let Ok(mut s) = st.try_borrow_mut() {
                s.forward(m);
            }
        }
    });
    let mut s = state.borrow_mut();
    s.frames_to_send = -1;
    s.dropped = 0;
    s.upstream = Some(Upstream {
        conn,
        remote,
        ids,
        text,
        pong,
        forward,
        warn_at: Some(server_conn.now().mono + DESCRIPTION_WAIT),
    });
    Ok(())
}

/// An imager served under `name` whose frames come from another imager server (C++
/// `vrpn_Imager_Stream_Buffer`, vrpn_server keyword `vrpn_Imager_Stream_Buffer NAME
/// UPSTREAM`).
///
/// When its first client connects it opens the upstream imager (its own connection, in the
/// server's reactor: one loop, no thread), copies the upstream's description, and from then
/// on forwards every frame as it arrives. A frame is dropped whole, and counted in a
/// discarded-frames notice before the next frame forwarded, when a client's throttle says so
/// or when the clients are behind (the server's output backlog holds more than two frames),
/// so a slow client sees fewer frames instead of older ones. The upstream connection closes
/// when the last client leaves.
pub struct ImagerRelay {
    name: String,
    server: Rc<ImagerServer>,
    state: Rc<RefCell<State>>,
    handlers: Vec<HandlerId>,
}

impl ImagerRelay {
    /// Serves `name` on `server_conn`, relaying `upstream` (`Name@host[:port]`, or the name
    /// of an imager on this same connection).
    pub fn new(name: &str, server_conn: &Connection, upstream: &str) -> Result<ImagerRelay, Error> {
        if upstream.contains('@') {
            DeviceName::parse(upstream)?;
        }
        let server = Rc::new(ImagerServer::new(name, server_conn, 0, 0, 1)?);
        // No description until the upstream's arrives (C++ blocks its first client until
        // then; a C++ client keeps the first size it hears).
        server.set_announce(false);
        let ids = server.ids();
        let base = server.base_ids();
        let state = Rc::new(RefCell::new(State {
            name: name.to_string(),
            upstream_name: upstream.to_string(),
            server_conn: server_conn.clone(),
            ids,
            base,
            upstream: None,
            frames_to_send: -1,
            dropped: 0,
            dropped_total: 0,
            frame_bytes: 0,
            last_frame_bytes: 0,
        }));
        let mut handlers = Vec::new();
        let (st, srv) = (Rc::downgrade(&state), Rc::downgrade(&server));
        handlers.push(
            server_conn.on_event(ConnectionEvent::GotFirstConnection, move || {
                if let (Some(st), Some(srv)) = (st.upgrade(), srv.upgrade()) {
                    if let Err(e) = open_upstream(&st, &srv) {
                        let s = st.borrow();
                        let text = format!("cannot open {}: {e}", s.upstream_name);
                        s.text(TextSeverity::Error, &text);
                    }
                }
            }),
        );
        let (st, srv) = (Rc::downgrade(&state), Rc::downgrade(&server));
        handlers.push(
            server_conn.on_event(ConnectionEvent::DroppedLastConnection, move || {
                if let (Some(st), Some(srv)) = (st.upgrade(), srv.upgrade()) {
                    let up = st.borrow_mut().upstream.take();
                    if let Some(up) = up {
                        up.conn.remove_handler(up.forward);
                    }
                    srv.set_announce(false);
                }
            }),
        );
        let st = Rc::downgrade(&state);
        handlers.push(server_conn.register_handler(
            ids.throttle_frames,
            SenderFilter::Only(base.sender),
            move |m| {
                if let (Some(st), Ok(t)) = (st.upgrade(), ThrottleFrames::decode(m.payload)) {
                    st.borrow_mut().throttle(t.frames);
                }
            },
        ));
        Ok(ImagerRelay {
            name: name.to_string(),
            server,
            state,
            handlers,
        })
    }

    /// True while the upstream imager is open (a client is connected).
    pub fn upstream_open(&self) -> bool {
        self.state.borrow().upstream.is_some()
    }

    /// True once the upstream imager described itself.
    pub fn upstream_described(&self) -> bool {
        self.state
            .borrow()
            .upstream
            .as_ref()
            .is_some_and(|u| u.remote.description().is_some())
    }

    /// Frames dropped so far (throttle or backlog).
    pub fn frames_dropped(&self) -> u64 {
        self.state.borrow().dropped_total
    }

    /// The imager server it serves through.
    pub fn server(&self) -> &ImagerServer {
        &self.server
    }
}

impl Drop for ImagerRelay {
    fn drop(&mut self) {
        let s = self.state.borrow();
        for h in &self.handlers {
            s.server_conn.remove_handler(*h);
        }
        if let Some(up) = &s.upstream {
            up.conn.remove_handler(up.forward);
        }
    }
}

impl ServerDevice for ImagerRelay {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        let (conn, own, warn) = {
            let s = self.state.borrow();
            let Some(up) = &s.upstream else { return };
            let own = up.conn.same_as(&s.server_conn);
            (
                up.conn.clone(),
                own,
                up.warn_at.is_some_and(|t| now.mono >= t),
            )
        };
        if !own {
            let _ = conn.mainloop();
        }
        if warn {
            let mut s = self.state.borrow_mut();
            if let Some(up) = s.upstream.as_mut() {
                up.warn_at = None;
            }
            let text = format!(
                "{}: no description from the imager {} after {} s; still trying",
                s.name,
                s.upstream_name,
                DESCRIPTION_WAIT.as_secs()
            );
            s.text(TextSeverity::Warning, &text);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let s = self.state.borrow();
        let up = s.upstream.as_ref()?;
        let own = up.conn.same_as(&s.server_conn);
        let conn_due = if own { None } else { up.conn.poll_timeout() };
        match (conn_due, up.warn_at) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

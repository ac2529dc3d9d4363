//! The liveness cycles of the remotes on a connection (ping, pong, "no response" texts), run
//! from the connection's own loop so that one `mainloop()` serves every remote on it and a
//! server loop knows when the next ping is due.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;

use super::dispatch::{SenderId, TypeId};
use super::{Connection, ConnectionEvent, ConnectionState, Notice, NoticeKind, Severity};
use crate::proto::ping::{PingAction, PingCycle, BACK_TEXT, ERROR_TEXT, WARN_TEXT};
use crate::time::{Now, TimeSource};
use crate::wire::class;
use crate::wire::payload::text::TextSeverity;

/// One remote's liveness state, shared by the remote (which owns it) and its connection (which
/// runs it while the remote exists).
#[derive(Debug)]
pub(crate) struct Liveness {
    /// The device name (the remote's sender).
    pub(crate) device: String,
    pub(crate) sender: SenderId,
    pub(crate) ping: TypeId,
    pub(crate) cycle: RefCell<PingCycle>,
    /// The remote's own `mainloop()` ran once: as in C++, a remote pings only from then on.
    pub(crate) started: std::cell::Cell<bool>,
}

impl Liveness {
    /// A pong from the device arrived: ends the cycle, and a flatline with a text.
    pub(crate) fn pong(&self, conn: &Connection, time: crate::time::TimeVal) {
        conn.liveness_changed();
        let back = self.cycle.borrow_mut().on_pong(time);
        if back {
            let _ = conn.send_text(self.sender, TextSeverity::Error, 0, BACK_TEXT);
        }
    }
}

impl Connection {
    /// Runs `l` from this connection's loop while `l` exists.
    pub(crate) fn watch_liveness(&self, l: &Rc<Liveness>) {
        self.inner.liveness.borrow_mut().push(Rc::downgrade(l));
        self.liveness_changed();
    }

    /// Some cycle may have changed: its deadline is worked out again when next asked.
    pub(crate) fn liveness_changed(&self) {
        self.inner.liveness_next.set(None);
    }

    /// A remote's cycle started (its first `mainloop()`): poll it on this pass.
    pub(crate) fn liveness_start(&self) {
        self.inner.liveness_started.set(true);
        self.liveness_changed();
    }

    /// The cycles still alive (dead ones are forgotten on the way).
    fn live_cycles(&self) -> impl Iterator<Item = Rc<Liveness>> + '_ {
        let mut list = self.inner.liveness.borrow_mut();
        list.retain(|w| w.strong_count() > 0);
        // Upgrading a weak `Rc` allocates nothing; the list is short (one entry per remote).
        let len = list.len();
        drop(list);
        (0..len).filter_map(move |i| {
            self.inner
                .liveness
                .borrow()
                .get(i)
                .and_then(|w| w.upgrade())
        })
    }

    pub(super) fn run_liveness(&self, clock: &dyn TimeSource) {
        // Nothing is due unless some started cycle waits for a pong (the common steady state
        // is every cycle answered: then no clock is read).
        let started = self.inner.liveness_started.get();
        let due = self.liveness_deadline();
        if due.is_none() && !started {
            return;
        }
        let now = clock.now();
        if !started && due.is_some_and(|d| now.mono < d) || self.is_replay() {
            return; // nobody answers pings in a log
        }
        self.inner.liveness_started.set(false);
        let connected = self.state() == ConnectionState::Connected;
        self.liveness_changed();
        for l in self.live_cycles() {
            if !l.started.get() {
                continue;
            }
            let action = l.cycle.borrow_mut().poll(now.mono, connected);
            let text = match action {
                PingAction::Idle => continue,
                PingAction::Ping => None,
                PingAction::PingAndWarn(s) => Some((TextSeverity::Warning, s, WARN_TEXT)),
                PingAction::PingAndError(s) => Some((TextSeverity::Error, s, ERROR_TEXT)),
            };
            let _ = self.pack_message(now.wall, l.ping, l.sender, &[], class::RELIABLE);
            if let Some((severity, level, text)) = text {
                let _ = self.send_text(l.sender, severity, level, text);
            }
        }
    }

    pub(super) fn liveness_event(&self, now: Now, ev: ConnectionEvent) {
        if self.inner.liveness.borrow().is_empty() {
            return;
        }
        self.liveness_changed();
        for l in self.live_cycles() {
            let mut c = l.cycle.borrow_mut();
            match ev {
                ConnectionEvent::GotConnection => c.on_connected(now.mono),
                ConnectionEvent::DroppedConnection => c.on_dropped(now.mono),
                _ => {}
            }
        }
    }

    /// The earliest ping deadline of the started cycles, worked out again only after a change
    /// (inline: every pass asks).
    #[inline]
    pub(super) fn liveness_deadline(&self) -> Option<Instant> {
        match self.inner.liveness_next.get() {
            Some(known) => known,
            None => self.liveness_deadline_changed(),
        }
    }

    #[inline(never)]
    fn liveness_deadline_changed(&self) -> Option<Instant> {
        let list = self.inner.liveness.borrow();
        let next = list
            .iter()
            .filter_map(|w| w.upgrade())
            .filter(|l| l.started.get())
            .filter_map(|l| l.cycle.borrow().next_deadline())
            .min();
        self.inner.liveness_next.set(Some(next));
        next
    }

    /// The devices the connected peers offer: [`peer_senders`](Self::peer_senders) without the
    /// senders a server announces for its own services rather than for a device (the
    /// remote-forwarding control every C++ `vrpn_server` runs, and clock synchronisation).
    pub fn peer_devices(&self) -> Vec<String> {
        let mut names = self.peer_senders();
        names.retain(|n| !is_service_sender(n));
        names
    }

    /// A server finished describing its devices: say so at once if a remote asks for a device
    /// the server does not offer (a typo in the name would otherwise mean silence).
    pub(super) fn check_wanted_devices(&self) {
        if !self.inner.core.borrow().session.is_client() {
            return;
        }
        // The control sender is the protocol's own; `peer_senders` never lists it.
        let offered = self.peer_devices();
        let peer = self
            .peers()
            .first()
            .map_or_else(|| "the server".to_string(), |p| p.0.clone());
        // One remote per interface of a device (a tracker, a button, … of one name) each has
        // a cycle: one notice per missing name.
        let mut missing: Vec<String> = Vec::new();
        for device in self.live_cycles().map(|l| l.device.clone()) {
            if !offered.contains(&device) && !missing.contains(&device) {
                missing.push(device);
            }
        }
        for device in missing {
            let list = offered.join(", ");
            let text = if list.is_empty() {
                format!("the server at {peer} offers no devices; none is named {device:?}")
            } else {
                format!("the server at {peer} offers {list}; none is named {device:?}")
            };
            let kind = NoticeKind::NoSuchDevice {
                device,
                offered: offered.clone(),
            };
            self.dispatch_notice(Notice::new(Severity::Warning, kind, text));
        }
    }
}

/// Senders that name a server's service, not a device: listing them as devices would mislead.
pub fn is_service_sender(name: &str) -> bool {
    name == "VRPN Control"
        || name == crate::wire::payload::forwarder::SENDER
        || name == crate::wire::payload::clock::SENDER
}

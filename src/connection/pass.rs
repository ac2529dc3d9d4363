//! One pass of [`Connection::mainloop`]: service the sockets, deliver what arrived (bounded
//! by the pass budget), run liveness, flush output.

use super::dispatch::{Message, SenderId, TypeId};
use super::{Connection, Core, LOG_FLUSH_PER_PASS};
use crate::error::Error;
use crate::net::PassBudget;
use crate::proto::Delivery;
use crate::time::TimeSource;

impl Connection {
    // -------------------------------------------------------------- the loop

    /// Does all pending work without blocking: accepts and (re)connects peers, reads and
    /// dispatches the messages that arrived, runs the remotes' liveness pings, and writes
    /// queued output.
    ///
    /// A pass is bounded, so it returns even while data arrives faster than callbacks handle
    /// it: it takes at most [`Limits::max_messages_per_peer_per_loop`](crate::Limits::max_messages_per_peer_per_loop) messages from each
    /// peer and stops delivering after [`Limits::max_pass_time`](crate::Limits::max_pass_time) (plus the callback running
    /// then); what remains stays buffered for the next call, and
    /// [`poll_timeout`](Self::poll_timeout) is then due at once, so a loop waiting in
    /// [`wait`](Self::wait) does not sleep on it. A callback can end the pass early with
    /// [`interrupt_pass`](crate::connection::interrupt_pass).
    ///
    /// One call serves every device on this connection (remotes sharing a connection need
    /// only one of them called). Called from inside a callback it returns at once (the outer
    /// call does the work).
    pub fn mainloop(&self) -> Result<(), Error> {
        self.pass(true)
    }

    /// [`mainloop`](Self::mainloop) right after this connection's reactor was polled (the
    /// server loop's wait): the readiness that poll recorded is what this pass's own poll would
    /// find, so the pass does without one (one `epoll_wait` per server pass instead of two).
    /// What arrives after that poll wakes the next wait at once.
    pub(crate) fn mainloop_after_poll(&self) -> Result<(), Error> {
        self.pass(false)
    }

    #[inline(always)]
    fn pass(&self, poll: bool) -> Result<(), Error> {
        if self.inner.depth.get() > 0 {
            return Ok(());
        }
        crate::net::clear_interrupt();
        if let Some(r) = self.inner.reactor.as_ref().filter(|_| poll) {
            r.poll_now().map_err(|e| Error::io("polling sockets", e))?;
        }
        let clock = &self.inner.clock;
        let outer = clock.begin();
        {
            let mut core = self.inner.core.borrow_mut();
            let Core { session, shell } = &mut *core;
            shell.service(clock, session);
            if shell.deadline_passed(session.poll_timeout(), clock) {
                session.handle_timeout(clock.now());
            }
            if session.has_io() {
                shell.carry_out(clock, session);
            }
            session.begin_pass(clock);
        }
        let mut budget = PassBudget::new(Some(self.inner.pass_time));
        let finished = self.pump(clock, &mut budget);
        self.run_liveness(clock);
        {
            let mut core = self.inner.core.borrow_mut();
            let Core { session, shell } = &mut *core;
            shell.flush(clock, session);
            session.flush_logs_some(LOG_FLUSH_PER_PASS);
        }
        // Deliveries queued by the flush (a peer that failed on write).
        let finished = if finished && self.inner.core.borrow().session.has_deliveries() {
            self.pump(clock, &mut budget)
        } else {
            finished
        };
        self.inner.left_over.set(!finished);
        if outer {
            clock.end();
        }
        if self.inner.watched.get() {
            self.arm_wakeup();
        }
        Ok(())
    }

    /// Takes deliveries from the session and hands them to handlers, reading more from the
    /// sockets whenever the session runs dry, until nothing more arrives (true) or `budget`
    /// is spent (false: deliveries remain).
    pub(super) fn pump(&self, clock: &dyn TimeSource, budget: &mut PassBudget) -> bool {
        loop {
            // One borrow of the core per delivery: poll, carry out I/O requests, read more.
            let (d, scratch) = {
                let mut core = self.inner.core.borrow_mut();
                let Core { session, shell } = &mut *core;
                let d = loop {
                    if let Some(d) = session.poll_delivery(clock) {
                        break Some(d);
                    }
                    if session.has_io() {
                        shell.carry_out(clock, session);
                    }
                    if shell.read(clock, session) || session.has_deliveries() {
                        continue;
                    }
                    break None;
                };
                let scratch = match d {
                    Some(Delivery::Message { .. }) => {
                        Some((session.take_scratch(), session.delivering_from()))
                    }
                    _ => None,
                };
                (d, scratch)
            };
            match (d, scratch) {
                (None, _) => return true,
                (
                    Some(Delivery::Message {
                        time,
                        sender_time,
                        sender,
                        type_id,
                        len,
                    }),
                    Some((scratch, peer)),
                ) => {
                    self.deliver(&Message {
                        time,
                        sender_time,
                        sender: SenderId(sender),
                        type_id: TypeId(type_id),
                        payload: &scratch[..len],
                        conn: self,
                        from_peer: true,
                        peer,
                    });
                    self.inner
                        .core
                        .borrow_mut()
                        .session
                        .restore_scratch(scratch);
                    if !budget.spend() {
                        return false;
                    }
                }
                (Some(d), _) => self.dispatch_delivery(clock, d),
            }
        }
    }

    pub(super) fn dispatch_delivery(&self, clock: &dyn TimeSource, d: Delivery) {
        match d {
            // Messages are delivered by `pump`, which lends the payload buffer.
            Delivery::Message { .. } => {}
            Delivery::Event(ev) => {
                let now = clock.now();
                self.liveness_event(now, ev);
                self.deliver(&Message {
                    time: now.wall,
                    sender_time: now.wall,
                    sender: SenderId(0),
                    type_id: TypeId(ev.type_id()),
                    payload: &[],
                    conn: self,
                    from_peer: false,
                    peer: None,
                });
            }
            Delivery::Notice(n) => self.dispatch_notice(n),
            Delivery::PeerSender(local) => {
                if let Some(name) = self.sender_name(SenderId(local)) {
                    self.inner.peer_senders.call(name.as_str());
                }
            }
            Delivery::State(s) => self.inner.states.call(&s),
            Delivery::PeerSendersComplete => self.check_wanted_devices(),
        }
    }
}

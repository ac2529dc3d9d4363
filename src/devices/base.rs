//! What every device shares (C++ `vrpn_BaseClass`): its sender, the text/ping/pong types, the
//! server's pong answer, the remote's ping cycle with its 3 s warning and 10 s error, and the
//! default printer of warnings and errors.

use std::cell::{Cell, RefCell};
use std::collections::HashSet;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::text::{decode_text, encode_text, TextSeverity, TEXT_PAYLOAD_LEN};
use crate::connection::{Connection, ConnectionEvent};
use crate::dispatch::{SenderFilter, SenderId, TypeId};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::class;

/// Type name of text messages.
pub const TEXT_MESSAGE: &str = "vrpn_Base text_message";
/// Type name of pings (client to server).
pub const PING_MESSAGE: &str = "vrpn_Base ping_message";
/// Type name of pongs (server to client).
pub const PONG_MESSAGE: &str = "vrpn_Base pong_message";

/// Ids every device object holds.
#[derive(Clone, Copy, Debug)]
pub struct BaseIds {
    /// The device's sender id.
    pub sender: SenderId,
    /// `vrpn_Base text_message`.
    pub text: TypeId,
    /// `vrpn_Base ping_message`.
    pub ping: TypeId,
    /// `vrpn_Base pong_message`.
    pub pong: TypeId,
}

/// Registers the device's sender; the caller then registers its own types and calls
/// [`register_base_types`] (C++ order: sender, device types, then the three base types).
pub fn register_sender(conn: &Connection, device: &str) -> Result<SenderId, Error> {
    conn.register_sender(device)
}

/// Registers the three base types shared by all devices on a connection.
pub fn register_base_types(conn: &Connection, sender: SenderId) -> Result<BaseIds, Error> {
    Ok(BaseIds {
        sender,
        text: conn.register_type(TEXT_MESSAGE)?,
        ping: conn.register_type(PING_MESSAGE)?,
        pong: conn.register_type(PONG_MESSAGE)?,
    })
}

/// Sends a text message from `sender` (1032-byte payload, zero-filled, RELIABLE).
pub fn send_text(
    conn: &Connection,
    sender: SenderId,
    severity: TextSeverity,
    level: u32,
    text: &str,
) -> Result<(), Error> {
    let text_type = conn.register_type(TEXT_MESSAGE)?;
    let mut buf = [0u8; TEXT_PAYLOAD_LEN];
    if encode_text(&mut buf, severity, level, text).is_none() {
        return Err(Error::PayloadTooLarge(text.len() + 9));
    }
    conn.pack_message(TimeVal::now(), text_type, sender, &buf, class::RELIABLE)
}

thread_local! {
    /// (connection address, sender) pairs that already have the default printer.
    static PRINTERS: RefCell<HashSet<(usize, i32)>> = RefCell::new(HashSet::new());
    static PRINT_THRESHOLD: Cell<TextSeverity> = const { Cell::new(TextSeverity::Warning) };
}

/// Sets the lowest severity the default printer shows (`vrpn_server -v` shows everything).
pub fn set_print_threshold(severity: TextSeverity) {
    PRINT_THRESHOLD.with(|t| t.set(severity));
}

/// Attaches the default printer for text from `sender` (once per connection and sender), which
/// prints warnings and errors to stdout the way C++ does:
/// `VRPN Warning` then ` (LEVEL) from SENDER: TEXT`.
pub fn attach_default_printer(conn: &Connection, ids: &BaseIds) {
    let key = (conn_key(conn), ids.sender.0);
    let fresh = PRINTERS.with(|p| p.borrow_mut().insert(key));
    if !fresh {
        return;
    }
    let name = conn.sender_name(ids.sender).unwrap_or_default();
    conn.register_handler(ids.text, SenderFilter::Only(ids.sender), move |m| {
        if let Some((sev, level, text)) = decode_text(m.payload) {
            if sev >= PRINT_THRESHOLD.with(Cell::get) {
                println!("{}\n ({level}) from {name}: {text}", sev.heading());
            }
        }
    });
}

fn conn_key(conn: &Connection) -> usize {
    conn.identity()
}

/// Server half: answers each ping from the device's own sender with a pong.
pub fn serve_pings(conn: &Connection, ids: &BaseIds) {
    let weak = conn.downgrade();
    let ids = *ids;
    conn.register_handler(ids.ping, SenderFilter::Only(ids.sender), move |_| {
        if let Some(c) = weak.upgrade() {
            let _ = c.pack_message(TimeVal::now(), ids.pong, ids.sender, &[], class::RELIABLE);
        }
    });
}

/// Remote half: the ping cycle that tells whether the server is alive.
pub struct PingCycle {
    ids: BaseIds,
    state: Rc<PingState>,
}

#[derive(Default)]
struct PingState {
    started: Cell<bool>,
    unanswered: Cell<bool>,
    flatlined: Cell<bool>,
    cycle_start: Cell<Option<Instant>>,
    last_ping: Cell<Option<Instant>>,
    /// Set by a dropped-connection event: begin a new cycle on the next mainloop.
    restart: Cell<bool>,
    last_pong: Cell<Option<TimeVal>>,
    /// Suppresses the warning texts (pings still go out).
    pub(crate) shutup: Cell<bool>,
}

impl PingCycle {
    /// Registers the pong and dropped-connection handlers.
    pub fn new(conn: &Connection, ids: BaseIds) -> PingCycle {
        let state = Rc::new(PingState::default());
        let (s, weak) = (state.clone(), conn.downgrade());
        conn.register_handler(ids.pong, SenderFilter::Only(ids.sender), move |m| {
            s.last_pong.set(Some(m.time));
            if s.unanswered.replace(false) && s.flatlined.replace(false) {
                if let Some(c) = weak.upgrade() {
                    let _ = send_text(
                        &c,
                        ids.sender,
                        TextSeverity::Error,
                        0,
                        "Server connection re-established!",
                    );
                }
            }
        });
        let s = state.clone();
        conn.on_event(ConnectionEvent::DroppedConnection, move || {
            if !s.unanswered.get() {
                s.restart.set(true);
            }
        });
        PingCycle { ids, state }
    }

    /// Runs the cycle: call once per remote mainloop.
    pub fn poll(&self, conn: &Connection) {
        if conn.is_replay() {
            return; // nobody answers pings in a log
        }
        let now = Instant::now();
        let st = &self.state;
        if !st.started.get() || st.restart.replace(false) {
            st.started.set(true);
            st.unanswered.set(true);
            st.cycle_start.set(Some(now));
            st.last_ping.set(Some(now));
            self.ping(conn);
            return;
        }
        if !st.unanswered.get() {
            return;
        }
        let last = st.last_ping.get().unwrap_or(now);
        if now.duration_since(last) < Duration::from_secs(1) {
            return;
        }
        st.last_ping.set(Some(now));
        self.ping(conn);
        if st.shutup.get() {
            return;
        }
        let elapsed = now
            .duration_since(st.cycle_start.get().unwrap_or(now))
            .as_secs();
        if elapsed >= 10 {
            st.flatlined.set(true);
            let _ = send_text(
                conn,
                self.ids.sender,
                TextSeverity::Error,
                elapsed as u32,
                "No response from server for >= 10 seconds",
            );
        } else if elapsed >= 3 {
            let _ = send_text(
                conn,
                self.ids.sender,
                TextSeverity::Warning,
                elapsed as u32,
                "No response from server for >= 3 seconds",
            );
        }
    }

    fn ping(&self, conn: &Connection) {
        let _ = conn.pack_message(
            TimeVal::now(),
            self.ids.ping,
            self.ids.sender,
            &[],
            class::RELIABLE,
        );
    }

    /// True while a ping waits for its pong.
    pub fn waiting_for_pong(&self) -> bool {
        self.state.unanswered.get()
    }

    /// Time of the last pong received (the server's clock).
    pub fn last_pong(&self) -> Option<TimeVal> {
        self.state.last_pong.get()
    }

    /// Suppresses (or re-enables) the "no response" texts.
    pub fn set_quiet(&self, quiet: bool) {
        self.state.shutup.set(quiet);
    }
}

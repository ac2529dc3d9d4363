//! Text devices: [`TextSender`] and [`TextReceiver`] over the base
//! `vrpn_Base text_message` type, and [`TextExample`] (our extension for `vrpn_server`).

use std::cell::Cell;
use std::ops::Deref;
use std::rc::Rc;
use std::time::Instant;

use super::base::{self, BaseIds, RemoteCore};
use super::text::{decode_text, encode_text, TextSeverity, MAX_TEXT, TEXT_PAYLOAD_LEN};
use super::{Cadence, ServerDevice};
use crate::connection::Connection;
use crate::dispatch::{CallbackList, HandlerId};
use crate::error::Error;
use crate::time::checked_duration;
use crate::time::{Now, TimeVal};
use crate::wire::class;

/// A text message (C++ `vrpn_TEXTCB`). The text is kept in a fixed buffer (no allocation).
#[derive(Clone, Copy, Debug)]
pub struct TextMessage {
    /// When the sender stamped the message, in local time when clock synchronisation with it
    /// is in effect (see [`Connection::clock_estimate`](crate::Connection::clock_estimate)).
    pub time: TimeVal,
    /// The time as the sender stamped it, on its own clock.
    pub sender_time: TimeVal,
    /// Severity.
    pub severity: TextSeverity,
    /// Level (free-form).
    pub level: u32,
    len: usize,
    buf: [u8; MAX_TEXT],
}

impl TextMessage {
    /// The text.
    pub fn text(&self) -> &str {
        std::str::from_utf8(&self.buf[..self.len]).unwrap_or("")
    }
}

impl PartialEq for TextMessage {
    fn eq(&self, o: &Self) -> bool {
        self.time == o.time
            && self.severity == o.severity
            && self.level == o.level
            && self.text() == o.text()
    }
}

#[derive(Default)]
struct ReceiverShared {
    message: CallbackList<TextMessage>,
    count: Cell<u64>,
}

/// Client half: calls back for every text message from its device (C++ `vrpn_Text_Receiver`).
pub struct TextReceiver {
    core: RemoteCore,
    shared: Rc<ReceiverShared>,
}

impl Deref for TextReceiver {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl TextReceiver {
    /// Opens `Device@location` (sharing the connection with other devices at that location).
    pub fn new(name: &str) -> Result<TextReceiver, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// A receiver for `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<TextReceiver, Error> {
        // No types of its own: text messages are a base type.
        let (mut core, ()) = RemoteCore::new(device, conn, |_| Ok(()))?;
        let shared = Rc::new(ReceiverShared::default());
        let s = shared.clone();
        let text = core.base_ids().text;
        core.handle(text, move |m| {
            if let Some((severity, level, text)) = decode_text(m.payload) {
                let mut msg = TextMessage {
                    time: m.time,
                    sender_time: m.sender_time,
                    severity,
                    level,
                    len: text.len().min(MAX_TEXT),
                    buf: [0; MAX_TEXT],
                };
                msg.buf[..msg.len].copy_from_slice(&text.as_bytes()[..msg.len]);
                s.count.set(s.count.get() + 1);
                s.message.call(&msg);
            }
        });
        Ok(TextReceiver { core, shared })
    }

    /// Calls `f` for every text message from the device.
    pub fn on_message(&self, f: impl FnMut(&TextMessage) + 'static) -> HandlerId {
        self.shared.message.add(f)
    }

    /// Removes a callback.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.shared.message.remove(id)
    }

    /// Messages received so far.
    pub fn received(&self) -> u64 {
        self.shared.count.get()
    }
}

/// Server half: sends text messages as a device (C++ `vrpn_Text_Sender`).
pub struct TextSender {
    conn: Connection,
    base: BaseIds,
}

impl TextSender {
    /// This device's sender id on its connection.
    pub fn sender(&self) -> crate::dispatch::SenderId {
        self.base.sender
    }

    /// Registers `device` on a server (or loopback) connection and answers its pings.
    pub fn new(device: &str, conn: &Connection) -> Result<TextSender, Error> {
        let (base, ()) = base::register_server(conn, device, |_| Ok(()))?;
        Ok(TextSender {
            conn: conn.clone(),
            base,
        })
    }

    /// Sends `text` (at most 1023 bytes) with a severity and level, stamped `time` (`None`:
    /// now, as C++'s {0,0}).
    pub fn send_message(
        &self,
        text: &str,
        severity: TextSeverity,
        level: u32,
        time: Option<TimeVal>,
    ) -> Result<(), Error> {
        let mut buf = [0u8; TEXT_PAYLOAD_LEN];
        if encode_text(&mut buf, severity, level, text).is_none() {
            return Err(Error::PayloadTooLarge(text.len() + 9));
        }
        self.conn.pack_message(
            time.unwrap_or_else(|| self.conn.now().wall),
            self.base.text,
            self.base.sender,
            &buf,
            class::RELIABLE,
        )
    }

    /// The connection this sender uses.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }
}

/// **Our extension**, `vrpn_Text_Example NAME PERIOD MESSAGE...`: sends `MESSAGE` (severity
/// normal, level 0) every `PERIOD` seconds, the first one on the first mainloop.
pub struct TextExample {
    sender: TextSender,
    name: String,
    message: String,
    cadence: Cadence,
}

impl TextExample {
    /// An example text server sending every `period` seconds (never for a period that is not
    /// positive or exceeds [`MAX_PERIOD`](crate::time::MAX_PERIOD)).
    pub fn new(
        device: &str,
        conn: &Connection,
        period: f64,
        message: &str,
    ) -> Result<TextExample, Error> {
        if message.len() > MAX_TEXT {
            return Err(Error::PayloadTooLarge(message.len() + 9));
        }
        Ok(TextExample {
            sender: TextSender::new(device, conn)?,
            name: device.to_string(),
            message: message.to_string(),
            cadence: Cadence::every(checked_duration(period).filter(|_| period > 0.0)),
        })
    }
}

impl ServerDevice for TextExample {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        if self.cadence.due(now.mono) {
            let _ =
                self.sender
                    .send_message(&self.message, TextSeverity::Normal, 0, Some(now.wall));
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.cadence.deadline()
    }
}

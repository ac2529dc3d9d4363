//! Text devices (DEVICES.md §7): [`TextSender`] and [`TextReceiver`] over the base
//! `vrpn_Base text_message` type, and [`TextExample`] (our extension for `vrpn_server`).

use std::cell::Cell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::base::{self, BaseIds, PingCycle};
use super::text::{decode_text, encode_text, TextSeverity, MAX_TEXT, TEXT_PAYLOAD_LEN};
use super::ServerDevice;
use crate::connection::Connection;
use crate::dispatch::{CallbackList, HandlerId, SenderFilter};
use crate::error::Error;
use crate::name::DeviceName;
use crate::time::TimeVal;
use crate::wire::class;

/// A text message (C++ `vrpn_TEXTCB`). The text is kept in a fixed buffer (no allocation).
#[derive(Clone, Copy, Debug)]
pub struct TextMessage {
    /// Time the sender stamped on the message.
    pub time: TimeVal,
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
    conn: Connection,
    ping: PingCycle,
    shared: Rc<ReceiverShared>,
    device: String,
    handlers: Vec<HandlerId>,
}

impl TextReceiver {
    /// Opens `Device@location` (sharing the connection with other devices at that location).
    pub fn new(name: &str) -> Result<TextReceiver, Error> {
        let parsed = DeviceName::parse(name)?;
        let conn = Connection::open_location(&parsed)?;
        Self::on_connection(&parsed.device, &conn)
    }

    /// A receiver for `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<TextReceiver, Error> {
        let sender = base::register_sender(conn, device)?;
        let base = base::register_base_types(conn, sender)?;
        base::attach_default_printer(conn, &base);
        let ping = PingCycle::new(conn, base);
        let shared = Rc::new(ReceiverShared::default());
        let s = shared.clone();
        let h = conn.register_handler(base.text, SenderFilter::Only(sender), move |m| {
            if let Some((severity, level, text)) = decode_text(m.payload) {
                let mut msg = TextMessage {
                    time: m.time,
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
        Ok(TextReceiver {
            conn: conn.clone(),
            ping,
            shared,
            device: device.to_string(),
            handlers: vec![h],
        })
    }

    /// Services the connection, then the ping cycle.
    pub fn mainloop(&self) -> Result<(), Error> {
        self.conn.mainloop()?;
        self.ping.poll(&self.conn);
        Ok(())
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

    /// The device (sender) name.
    pub fn device(&self) -> &str {
        &self.device
    }

    /// The connection this receiver uses.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// The ping cycle (server liveness).
    pub fn ping_cycle(&self) -> &PingCycle {
        &self.ping
    }
}

impl Drop for TextReceiver {
    fn drop(&mut self) {
        for h in self.handlers.drain(..) {
            self.conn.remove_handler(h);
        }
    }
}

/// Server half: sends text messages as a device (C++ `vrpn_Text_Sender`).
pub struct TextSender {
    conn: Connection,
    base: BaseIds,
}

impl TextSender {
    /// Registers `device` on a server (or loopback) connection and answers its pings.
    pub fn new(device: &str, conn: &Connection) -> Result<TextSender, Error> {
        let sender = base::register_sender(conn, device)?;
        let base = base::register_base_types(conn, sender)?;
        base::serve_pings(conn, &base);
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
            time.unwrap_or_else(TimeVal::now),
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
    period: Option<Duration>,
    next: Instant,
}

impl TextExample {
    /// An example text server.
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
            period: (period > 0.0 && period.is_finite()).then(|| Duration::from_secs_f64(period)),
            next: Instant::now(),
        })
    }
}

impl ServerDevice for TextExample {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Instant) {
        let Some(period) = self.period else { return };
        if now < self.next {
            return;
        }
        let _ = self
            .sender
            .send_message(&self.message, TextSeverity::Normal, 0, None);
        self.next += period;
        if self.next <= now {
            self.next = now + period;
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.period.map(|_| self.next)
    }
}

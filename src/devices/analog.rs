//! Analog: a vector of up to 128 channel values, always sent whole.
//! [`AnalogRemote`] is the client half, [`AnalogServer`] the server half,
//! [`AnalogExample`] our example server (sine waves).

use std::cell::{Cell, RefCell};
use std::ops::Deref;
use std::rc::Rc;
use std::time::Instant;

use super::base::{self, BaseIds, RemoteCore};
use super::latest::Stamp;
use super::text::TextSeverity;
use super::{Cadence, ServerDevice};
use crate::connection::{Connection, ServiceClass};
use crate::dispatch::{CallbackList, HandlerId, SenderId, TypeId};
use crate::error::Error;
use crate::time::{Now, TimeVal};
use crate::wire::payload::analog as codec;

pub use codec::CHANNEL_MAX;

/// Ids of the analog types on one connection.
#[derive(Clone, Copy, Debug)]
pub struct AnalogIds {
    /// `vrpn_Analog Channel`.
    pub channel: TypeId,
}

impl AnalogIds {
    /// Registers the analog type.
    pub fn register(conn: &Connection) -> Result<AnalogIds, Error> {
        Ok(AnalogIds {
            channel: conn.register_type(codec::CHANNEL)?,
        })
    }
}

/// A channel report (C++ `vrpn_ANALOGCB`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnalogReport {
    /// Time the server stamped on the report, translated to the local clock when clock
    /// synchronisation is in effect.
    pub time: TimeVal,
    /// The time exactly as the server stamped it.
    pub sender_time: TimeVal,
    /// When it arrived here (local wall clock of the `mainloop()` pass that read it).
    pub arrival: TimeVal,
    /// Which report it is: 1 for the first this remote received, then 2, ... (0 before any).
    pub seq: u64,
    /// Number of channels.
    pub num_channel: usize,
    /// Values of channels `0..num_channel`; the rest is zero.
    pub channel: [f64; CHANNEL_MAX],
}

impl AnalogReport {
    /// The values of channels `0..num_channel`.
    pub fn channels(&self) -> &[f64] {
        &self.channel[..self.num_channel.min(CHANNEL_MAX)]
    }
}

struct RemoteShared {
    report: CallbackList<AnalogReport>,
    latest: RefCell<AnalogReport>,
    /// The `seq` of the report the application last took.
    taken: Cell<u64>,
    bad_messages: Cell<u64>,
}

/// Client half of an analog device: callbacks and the latest channel values.
pub struct AnalogRemote {
    core: RemoteCore,
    shared: Rc<RemoteShared>,
}

impl Deref for AnalogRemote {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl AnalogRemote {
    /// Opens `Device@location` (sharing the connection with other devices at that location).
    pub fn new(name: &str) -> Result<AnalogRemote, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// A remote for `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<AnalogRemote, Error> {
        let (mut core, ids) = RemoteCore::new(device, conn, AnalogIds::register)?;
        let shared = Rc::new(RemoteShared {
            report: CallbackList::default(),
            latest: RefCell::new(AnalogReport {
                time: TimeVal::ZERO,
                sender_time: TimeVal::ZERO,
                arrival: TimeVal::ZERO,
                seq: 0,
                num_channel: CHANNEL_MAX,
                channel: [0.0; CHANNEL_MAX],
            }),
            taken: Cell::new(0),
            bad_messages: Cell::new(0),
        });
        let s = shared.clone();
        core.handle(ids.channel, move |m| {
            let r = {
                let mut l = s.latest.borrow_mut();
                match codec::decode_channels_into(m.payload, &mut l.channel) {
                    Ok(n) => {
                        let stamp = Stamp::of(m);
                        l.num_channel = n;
                        l.time = m.time;
                        l.sender_time = stamp.sender_time;
                        l.arrival = stamp.arrival;
                        l.seq += 1;
                        *l
                    }
                    Err(_) => {
                        s.bad_messages.set(s.bad_messages.get() + 1);
                        return;
                    }
                }
            };
            s.report.call(&r);
        });
        Ok(AnalogRemote { core, shared })
    }

    /// Calls `f` for every channel report.
    pub fn on_report(&self, f: impl FnMut(&AnalogReport) + 'static) -> HandlerId {
        self.shared.report.add(f)
    }

    /// Removes a callback.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.shared.report.remove(id)
    }

    /// The latest report (128 zero channels and `seq` 0 before the first one, as C++).
    pub fn latest(&self) -> AnalogReport {
        *self.shared.latest.borrow()
    }

    /// The latest report if it arrived since the last `take_report()`: a frame loop gets
    /// each new report once and `None` in frames where none came.
    pub fn take_report(&self) -> Option<AnalogReport> {
        let l = self.shared.latest.borrow();
        (l.seq != self.shared.taken.replace(l.seq)).then_some(*l)
    }

    /// Latest value of channel `i` (0.0 before any report or beyond the count).
    pub fn channel(&self, i: usize) -> f64 {
        let l = self.shared.latest.borrow();
        l.channels().get(i).copied().unwrap_or(0.0)
    }

    /// Number of channels in the latest report (128 before the first one, as C++).
    pub fn num_channels(&self) -> usize {
        self.shared.latest.borrow().num_channel
    }

    /// True once a report arrived.
    pub fn got_report(&self) -> bool {
        self.shared.latest.borrow().seq > 0
    }

    /// Reports that could not be decoded and were ignored.
    pub fn bad_messages(&self) -> u64 {
        self.shared.bad_messages.get()
    }
}

/// Server half of an analog device (C++ `vrpn_Analog_Server`): set channels, then
/// [`report`](Self::report) or [`report_changes`](Self::report_changes).
pub struct AnalogServer {
    conn: Connection,
    ids: AnalogIds,
    base: BaseIds,
    num: usize,
    channels: [f64; CHANNEL_MAX],
    last: [f64; CHANNEL_MAX],
    class: ServiceClass,
}

impl AnalogServer {
    /// Registers `device` with `channels` channels (clamped to 128).
    pub fn new(device: &str, conn: &Connection, channels: usize) -> Result<AnalogServer, Error> {
        let (base, ids) = base::register_server(conn, device, AnalogIds::register)?;
        Ok(AnalogServer {
            conn: conn.clone(),
            ids,
            base,
            num: channels.min(CHANNEL_MAX),
            channels: [0.0; CHANNEL_MAX],
            last: [0.0; CHANNEL_MAX],
            class: ServiceClass::LOW_LATENCY,
        })
    }

    /// Number of channels.
    pub fn num_channels(&self) -> usize {
        self.num
    }

    /// Sets the number of channels (clamped to 0..=128).
    pub fn set_num_channels(&mut self, n: usize) {
        self.num = n.min(CHANNEL_MAX);
    }

    /// Class of service for reports (LOW_LATENCY by default).
    pub fn set_class_of_service(&mut self, class_of_service: impl Into<ServiceClass>) {
        self.class = class_of_service.into();
    }

    /// The current channel values (mutable).
    pub fn channels_mut(&mut self) -> &mut [f64] {
        &mut self.channels[..self.num]
    }

    /// The current channel values.
    pub fn channels(&self) -> &[f64] {
        &self.channels[..self.num]
    }

    /// Sets channel `i` (ignored beyond the count).
    pub fn set_channel(&mut self, i: usize, v: f64) {
        if i < self.num {
            self.channels[i] = v;
        }
    }

    /// Sends all channels now, stamped `time` (`None`: now, as C++'s {0,0} sentinel).
    pub fn report(&mut self, time: Option<TimeVal>) -> Result<(), Error> {
        self.last[..self.num].copy_from_slice(&self.channels[..self.num]);
        let mut buf = [0u8; codec::channels_len(CHANNEL_MAX)];
        let len = codec::encode_channels(&self.channels[..self.num], &mut buf);
        self.conn.pack_message(
            time.unwrap_or_else(|| self.conn.now().wall),
            self.ids.channel,
            self.base.sender,
            &buf[..len],
            self.class,
        )
    }

    /// Sends all channels if any changed since the last report; returns whether it sent.
    pub fn report_changes(&mut self, time: Option<TimeVal>) -> Result<bool, Error> {
        if self.channels[..self.num] == self.last[..self.num] {
            return Ok(false);
        }
        self.report(time).map(|_| true)
    }

    /// Sends a text message from this device.
    pub fn send_text(&self, severity: TextSeverity, level: u32, text: &str) -> Result<(), Error> {
        base::send_text(&self.conn, self.base.sender, severity, level, text)
    }

    /// The connection this server reports on.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// This device's sender id on its connection.
    pub fn sender(&self) -> SenderId {
        self.base.sender
    }
}

/// **Our extension**, `vrpn_Analog_Example NAME CHANNELS RATE`: channel `i` is
/// `sin(2π·t·(i+1)/10)` (t in seconds since start: channel 0 turns once per 10 s, channel 1
/// twice, ...), reported `RATE` times a second with `report_changes`.
pub struct AnalogExample {
    server: AnalogServer,
    name: String,
    cadence: Cadence,
    started: Option<Instant>,
}

impl AnalogExample {
    /// An example analog server.
    pub fn new(
        device: &str,
        conn: &Connection,
        channels: usize,
        rate: f64,
    ) -> Result<AnalogExample, Error> {
        Ok(AnalogExample {
            server: AnalogServer::new(device, conn, channels)?,
            name: device.to_string(),
            cadence: Cadence::per_second(rate),
            started: None,
        })
    }

    /// The value of channel `i` at `t` seconds after start.
    pub fn value_at(i: usize, t: f64) -> f64 {
        (2.0 * std::f64::consts::PI * t * (i as f64 + 1.0) / 10.0).sin()
    }

    /// The underlying analog server.
    pub fn server(&self) -> &AnalogServer {
        &self.server
    }
}

impl ServerDevice for AnalogExample {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        let first = self.cadence.is_first();
        if !self.cadence.due(now.mono) {
            return;
        }
        let started = *self.started.get_or_insert(now.mono);
        let t = now.mono.duration_since(started).as_secs_f64();
        for (i, v) in self.server.channels_mut().iter_mut().enumerate() {
            *v = Self::value_at(i, t);
        }
        // The first report always goes out (all-zero channels at t = 0 included).
        if first {
            let _ = self.server.report(Some(now.wall));
        } else {
            let _ = self.server.report_changes(Some(now.wall));
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.cadence.deadline()
    }
}

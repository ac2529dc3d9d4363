//! Analog output: clients ask the server to set output channels; the server
//! announces its channel count on every new connection. [`AnalogOutputRemote`] is the client
//! half, [`AnalogOutputServer`] the server half (with the callbacks of C++
//! `vrpn_Analog_Output_Callback_Server`). [`OutputRequests`] keeps what clients asked for
//! until a driver writes it to its device.

use std::cell::{Cell, RefCell};
use std::ops::Deref;
use std::rc::Rc;

use super::base::{self, BaseIds, RemoteCore};
use super::text::TextSeverity;
use crate::connection::{Connection, ConnectionEvent};
use crate::dispatch::{CallbackList, HandlerId, SenderFilter, SenderId, TypeId};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::class;
use crate::wire::payload::analog::CHANNEL_MAX;
use crate::wire::payload::analog_output as codec;

/// Ids of the analog output types on one connection.
#[derive(Clone, Copy, Debug)]
pub struct AnalogOutputIds {
    /// Set one channel.
    pub change_request: TypeId,
    /// Set channels `0..n`.
    pub change_channels_request: TypeId,
    /// Number of channels (server->client).
    pub num_channels_report: TypeId,
}

impl AnalogOutputIds {
    /// Registers the three types in C++ order.
    pub fn register(conn: &Connection) -> Result<AnalogOutputIds, Error> {
        Ok(AnalogOutputIds {
            change_request: conn.register_type(codec::CHANGE_REQUEST)?,
            change_channels_request: conn.register_type(codec::CHANGE_CHANNELS_REQUEST)?,
            num_channels_report: conn.register_type(codec::NUM_CHANNELS_REPORT)?,
        })
    }
}

/// The server's output values after a request (C++ `vrpn_ANALOGOUTPUTCB`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnalogOutputValues {
    /// Time of the request.
    pub time: TimeVal,
    /// Number of active output channels.
    pub num_channel: i32,
    /// Current values; channels `0..num_channel` are meaningful.
    pub channel: [f64; CHANNEL_MAX],
}

impl AnalogOutputValues {
    /// Values of the active channels.
    pub fn channels(&self) -> &[f64] {
        &self.channel[..(self.num_channel.clamp(0, CHANNEL_MAX as i32) as usize)]
    }
}

/// Client half: sends channel requests, learns the server's channel count.
pub struct AnalogOutputRemote {
    core: RemoteCore,
    ids: AnalogOutputIds,
    num: Rc<Cell<i32>>,
    reports: Rc<CallbackList<i32>>,
}

impl Deref for AnalogOutputRemote {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl AnalogOutputRemote {
    /// Opens `Device@location`.
    pub fn new(name: &str) -> Result<AnalogOutputRemote, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// A remote for `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<AnalogOutputRemote, Error> {
        let (mut core, ids) = RemoteCore::new(device, conn, AnalogOutputIds::register)?;
        let num = Rc::new(Cell::new(CHANNEL_MAX as i32));
        let reports: Rc<CallbackList<i32>> = Rc::new(CallbackList::default());
        let (n, r) = (num.clone(), reports.clone());
        core.handle(ids.num_channels_report, move |m| {
            if let Ok(rep) = codec::NumChannelsReport::decode(m.payload) {
                if (0..=CHANNEL_MAX as i32).contains(&rep.num_channels) {
                    n.set(rep.num_channels);
                    r.call(&rep.num_channels);
                }
            }
        });
        Ok(AnalogOutputRemote {
            core,
            ids,
            num,
            reports,
        })
    }

    /// The server's channel count (128 until it reports).
    pub fn num_channels(&self) -> i32 {
        self.num.get()
    }

    /// Calls `f` with each channel count the server reports.
    pub fn on_num_channels(&self, f: impl FnMut(&i32) + 'static) -> HandlerId {
        self.reports.add(f)
    }

    /// Removes a callback [`on_num_channels`](Self::on_num_channels) returned.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.reports.remove(id)
    }

    /// Asks the server to set one channel (RELIABLE).
    pub fn request_change_channel_value(&self, channel: i32, value: f64) -> Result<(), Error> {
        let mut buf = [0u8; codec::ChangeRequest::LEN];
        codec::ChangeRequest::new(channel, value).encode(&mut buf);
        self.send(self.ids.change_request, &buf)
    }

    /// Asks the server to set channels `0..values.len()` (at most 128, RELIABLE).
    pub fn request_change_channels(&self, values: &[f64]) -> Result<(), Error> {
        if values.len() > CHANNEL_MAX {
            return Err(Error::Unsupported("more than 128 analog output channels"));
        }
        let req = codec::ChangeChannelsRequest::from_slice(values);
        let mut buf = [0u8; 8 + 8 * CHANNEL_MAX];
        let len = req.encode(&mut buf);
        self.send(self.ids.change_channels_request, &buf[..len])
    }
}

struct ServerShared {
    values: RefCell<AnalogOutputValues>,
    callbacks: CallbackList<AnalogOutputValues>,
}

/// Server half: stores requested values and calls back after every request.
pub struct AnalogOutputServer {
    conn: Connection,
    ids: AnalogOutputIds,
    base: BaseIds,
    shared: Rc<ServerShared>,
}

impl AnalogOutputServer {
    /// This device's sender id on its connection.
    pub fn sender(&self) -> SenderId {
        self.base.sender
    }

    /// Keeps the values clients ask for, channels `0..slots`, for a driver to take when it
    /// next writes to its device (see [`OutputRequests`]); with `pings_of`, also notes that a
    /// client pinged that sender (a driver answers a ping of its Analog with a report).
    pub fn watch_requests(
        &self,
        slots: usize,
        pings_of: Option<SenderId>,
    ) -> Result<OutputRequests, Error> {
        let pending = Rc::new(RefCell::new(Pending::new(slots)));
        let only = SenderFilter::Only(self.base.sender);
        let p = pending.clone();
        self.conn
            .register_handler(self.ids.change_request, only, move |m| {
                if let Ok(r) = codec::ChangeRequest::decode(m.payload) {
                    if let Ok(c) = usize::try_from(r.channel) {
                        p.borrow_mut().store(c, r.value);
                    }
                }
            });
        let p = pending.clone();
        self.conn
            .register_handler(self.ids.change_channels_request, only, move |m| {
                if let Ok(r) = codec::ChangeChannelsRequest::decode(m.payload) {
                    let mut p = p.borrow_mut();
                    for (c, &v) in r.values[..r.count].iter().enumerate() {
                        p.store(c, v);
                    }
                }
            });
        if let Some(sender) = pings_of {
            let ping = self.conn.register_type(base::PING_MESSAGE)?;
            let p = pending.clone();
            self.conn
                .register_handler(ping, SenderFilter::Only(sender), move |_| {
                    p.borrow_mut().pinged = true;
                });
        }
        Ok(OutputRequests { pending })
    }

    /// Registers `device` with `channels` output channels (clamped to 128).
    pub fn new(
        device: &str,
        conn: &Connection,
        channels: usize,
    ) -> Result<AnalogOutputServer, Error> {
        let (base, ids) = base::register_server(conn, device, AnalogOutputIds::register)?;
        let sender = base.sender;
        let num = channels.min(CHANNEL_MAX) as i32;
        let shared = Rc::new(ServerShared {
            values: RefCell::new(AnalogOutputValues {
                time: TimeVal::ZERO,
                num_channel: num,
                channel: [0.0; CHANNEL_MAX],
            }),
            callbacks: CallbackList::default(),
        });
        let (weak, s) = (conn.downgrade(), shared.clone());
        conn.on_event(ConnectionEvent::GotConnection, move || {
            if let Some(c) = weak.upgrade() {
                let num = s.values.borrow().num_channel;
                let mut buf = [0u8; codec::NumChannelsReport::LEN];
                codec::NumChannelsReport { num_channels: num }.encode(&mut buf);
                let _ = c.pack_message(
                    c.now().wall,
                    ids.num_channels_report,
                    sender,
                    &buf,
                    class::RELIABLE,
                );
            }
        });
        let only = SenderFilter::Only(sender);
        let (weak, s) = (conn.downgrade(), shared.clone());
        conn.register_handler(ids.change_request, only, move |m| {
            let Ok(r) = codec::ChangeRequest::decode(m.payload) else {
                return;
            };
            let v = {
                let mut v = s.values.borrow_mut();
                v.time = m.time;
                if r.channel >= 0 && r.channel < v.num_channel {
                    v.channel[r.channel as usize] = r.value;
                } else if let Some(c) = weak.upgrade() {
                    let t = format!(
                        "Error:  (handle_request_message):  channel {} is not active.  Squelching.",
                        r.channel
                    );
                    let _ = base::send_text(&c, sender, TextSeverity::Error, 0, &t);
                }
                *v
            };
            s.callbacks.call(&v);
        });
        let (weak, s) = (conn.downgrade(), shared.clone());
        conn.register_handler(ids.change_channels_request, only, move |m| {
            let raw_n = if m.payload.len() >= 4 {
                i32::from_be_bytes([m.payload[0], m.payload[1], m.payload[2], m.payload[3]])
            } else {
                return;
            };
            let v = {
                let mut v = s.values.borrow_mut();
                v.time = m.time;
                let num = v.num_channel;
                if raw_n < 0 {
                    if let Some(c) = weak.upgrade() {
                        let t = format!(
                            "Error:  (handle_request_channels_message):  invalid channel {raw_n}.  Squelching."
                        );
                        let _ = base::send_text(&c, sender, TextSeverity::Error, 0, &t);
                    }
                } else {
                    if raw_n > num {
                        if let Some(c) = weak.upgrade() {
                            let t = format!(
                                "Error:  (handle_request_channels_message):  channels above {num} not active; bad request up to channel {raw_n}.  Squelching."
                            );
                            let _ = base::send_text(&c, sender, TextSeverity::Error, 0, &t);
                        }
                    }
                    if let Ok(r) = codec::ChangeChannelsRequest::decode(m.payload) {
                        let n = r.count.min(num as usize);
                        v.channel[..n].copy_from_slice(&r.values[..n]);
                    }
                }
                *v
            };
            s.callbacks.call(&v);
        });
        Ok(AnalogOutputServer {
            conn: conn.clone(),
            ids,
            base,
            shared,
        })
    }

    /// Calls `f` after every request (valid or not) with all current values.
    pub fn on_request(&self, f: impl FnMut(&AnalogOutputValues) + 'static) -> HandlerId {
        self.shared.callbacks.add(f)
    }

    /// Removes a callback [`on_request`](Self::on_request) returned.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.shared.callbacks.remove(id)
    }

    /// The current output values.
    pub fn values(&self) -> AnalogOutputValues {
        *self.shared.values.borrow()
    }

    /// Sets the number of active channels (clamped to 128), for a device that learns it when
    /// it starts (a chain of positioners). Later requests are checked against it, and new
    /// connections are told it; [`report_num_channels`](Self::report_num_channels) tells the
    /// current ones.
    pub fn set_num_channels(&self, n: usize) {
        self.shared.values.borrow_mut().num_channel = n.min(CHANNEL_MAX) as i32;
    }

    /// Sends the channel count now (as on a new connection).
    pub fn report_num_channels(&self) -> Result<(), Error> {
        let mut buf = [0u8; codec::NumChannelsReport::LEN];
        codec::NumChannelsReport {
            num_channels: self.shared.values.borrow().num_channel,
        }
        .encode(&mut buf);
        self.conn.pack_message(
            self.conn.now().wall,
            self.ids.num_channels_report,
            self.base.sender,
            &buf,
            class::RELIABLE,
        )
    }
}

/// What clients asked an [`AnalogOutputServer`] for that its driver has not written yet: the
/// last value asked for each channel (a device is moved or set to where it was last asked to
/// be; a value superseded before the driver's next pass is never written), and whether a
/// client pinged. Made by [`AnalogOutputServer::watch_requests`]; its slots are allocated
/// then, so keeping and taking requests allocates nothing.
///
/// It sees requests as they came: a value for a channel the server half refuses (beyond its
/// current channel count) is still kept when a slot holds it, for a driver that learns its
/// channel count later (a chain of positioners found by a reset).
pub struct OutputRequests {
    pending: Rc<RefCell<Pending>>,
}

impl OutputRequests {
    /// Whether a value or a ping waits (the driver should run its next pass at once).
    pub fn is_pending(&self) -> bool {
        let p = self.pending.borrow();
        p.lowest.is_some() || p.pinged
    }

    /// Whether a client pinged since the last call.
    pub fn take_pinged(&self) -> bool {
        std::mem::take(&mut self.pending.borrow_mut().pinged)
    }

    /// The waiting value of the lowest channel that has one, taken: calling it until `None`
    /// yields the requests in channel order.
    pub fn take_next(&self) -> Option<(usize, f64)> {
        self.pending.borrow_mut().take_next()
    }
}

/// The slots behind [`OutputRequests`].
struct Pending {
    value: Vec<Option<f64>>,
    /// No slot below it holds a value (`None`: no slot does).
    lowest: Option<usize>,
    pinged: bool,
}

impl Pending {
    fn new(slots: usize) -> Pending {
        Pending {
            value: vec![None; slots],
            lowest: None,
            pinged: false,
        }
    }

    /// Keeps `v` for channel `c` (ignored without a slot for it).
    fn store(&mut self, c: usize, v: f64) {
        if let Some(slot) = self.value.get_mut(c) {
            *slot = Some(v);
            self.lowest = Some(self.lowest.map_or(c, |l| l.min(c)));
        }
    }

    fn take_next(&mut self) -> Option<(usize, f64)> {
        let from = self.lowest?;
        for c in from..self.value.len() {
            if let Some(v) = self.value[c].take() {
                self.lowest = Some(c + 1).filter(|&n| n < self.value.len());
                return Some((c, v));
            }
        }
        self.lowest = None;
        None
    }
}

#[cfg(test)]
mod tests {
    use super::Pending;

    fn drain(p: &mut Pending) -> Vec<(usize, f64)> {
        std::iter::from_fn(|| p.take_next()).collect()
    }

    #[test]
    fn the_last_value_per_channel_is_taken_in_channel_order() {
        let mut p = Pending::new(4);
        p.store(2, 1.0);
        p.store(0, 2.0);
        p.store(2, 3.0);
        p.store(3, 4.0);
        assert_eq!(drain(&mut p), [(0, 2.0), (2, 3.0), (3, 4.0)]);
        assert!(p.lowest.is_none());
        assert_eq!(drain(&mut p), []);
    }

    #[test]
    fn a_channel_without_a_slot_is_ignored() {
        let mut p = Pending::new(1);
        p.store(1, 5.0);
        p.store(usize::MAX, 5.0);
        assert!(p.lowest.is_none());
        assert_eq!(drain(&mut p), []);
        p.store(0, 6.0);
        assert_eq!(drain(&mut p), [(0, 6.0)]);
    }

    #[test]
    fn a_value_stored_between_takes_below_the_cursor_is_found() {
        let mut p = Pending::new(3);
        p.store(1, 1.0);
        p.store(2, 2.0);
        assert_eq!(p.take_next(), Some((1, 1.0)));
        p.store(0, 3.0);
        assert_eq!(drain(&mut p), [(0, 3.0), (2, 2.0)]);
    }
}

//! The client half of an imager (C++ `vrpn_Imager_Remote`).

use std::cell::{Cell, RefCell};
use std::ops::Deref;
use std::rc::Rc;

use super::region::ImagerRegion;
use super::{Extent, ImagerIds};
use crate::connection::{Connection, ConnectionEvent};
use crate::devices::base::RemoteCore;
use crate::dispatch::{CallbackList, HandlerId, Message};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::payload::imager::{
    self as codec, ChannelDescription, DiscardedFrames, FrameExtent, Region, ThrottleFrames,
    MAX_CHANNELS,
};

/// The image's size and channel count, as last described by the server.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImagerDescription {
    /// The server's time stamp of the description.
    pub time: TimeVal,
    /// When it arrived here.
    pub arrival: TimeVal,
    /// Columns.
    pub cols: i32,
    /// Rows.
    pub rows: i32,
    /// Depth.
    pub depth: i32,
    /// Channels ([`ImagerRemote::channel`] gives each).
    pub channels: usize,
}

/// A begin-frame or end-frame message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameReport {
    /// The server's time stamp (translated to the local clock when clock synchronisation is
    /// in effect).
    pub time: TimeVal,
    /// The time stamp as the server wrote it.
    pub sender_time: TimeVal,
    /// When it arrived here.
    pub arrival: TimeVal,
    /// The frame's extent.
    pub extent: Extent,
    /// Counts the frames ended (for end-frame reports) or begun (for begin-frame reports)
    /// since the remote was made, 1 for the first.
    pub seq: u64,
}

/// A discarded-frames notice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DiscardedFramesReport {
    /// The server's time stamp.
    pub time: TimeVal,
    /// When it arrived here.
    pub arrival: TimeVal,
    /// Frames dropped (0: some, count unknown).
    pub count: u16,
}

type RegionCallback = Rc<RefCell<dyn for<'a> FnMut(&ImagerRegion<'a>)>>;

/// What the remote's handlers share with it.
struct State {
    /// The description's channels, decoded in place (no allocation per description).
    channels: RefCell<Box<[ChannelDescription; MAX_CHANNELS]>>,
    description: Cell<Option<ImagerDescription>>,
    begin: Cell<Option<FrameReport>>,
    end: Cell<Option<FrameReport>>,
    /// `end.seq` when the application last took the end of a frame.
    end_taken: Cell<u64>,
    discarded: Cell<u64>,
    regions: Cell<u64>,
    bad: Cell<u64>,
    on_description: CallbackList<ImagerDescription>,
    on_begin: CallbackList<FrameReport>,
    on_end: CallbackList<FrameReport>,
    on_discarded: CallbackList<DiscardedFramesReport>,
    on_region: RefCell<Vec<(HandlerId, RegionCallback)>>,
}

impl State {
    fn call_regions(&self, region: &ImagerRegion<'_>) {
        let mut i = 0;
        loop {
            let cb = match self.on_region.borrow().get(i) {
                Some((_, cb)) => cb.clone(),
                None => break,
            };
            if let Ok(mut f) = cb.try_borrow_mut() {
                f(region);
            }
            i += 1;
        }
    }

    fn described(&self) -> bool {
        self.description.get().is_some()
    }

    fn frame(&self, m: &Message<'_>, slot: &Cell<Option<FrameReport>>) -> Option<FrameReport> {
        let Ok(f) = FrameExtent::decode(m.payload) else {
            self.bad.set(self.bad.get() + 1);
            return None;
        };
        let seq = slot.get().map_or(0, |r| r.seq) + 1;
        let report = FrameReport {
            time: m.time,
            sender_time: m.sender_time,
            arrival: m.arrived(),
            extent: Extent::from_frame(&f),
            seq,
        };
        slot.set(Some(report));
        Some(report)
    }
}

/// Client half of an imager: the description, frames and regions a server sends.
///
/// As in C++, regions, frames and discarded-frame notices reach the callbacks only once a
/// description has arrived (and again after one arrives following a drop of the
/// connection): without it the channels are unknown. A frame loop can also poll:
/// [`description`](Self::description), [`last_begin_frame`](Self::last_begin_frame),
/// [`take_end_frame`](Self::take_end_frame) (the newest end of a frame, once).
pub struct ImagerRemote {
    core: RemoteCore,
    ids: ImagerIds,
    state: Rc<State>,
    dropped_handler: HandlerId,
}

impl Deref for ImagerRemote {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl Drop for ImagerRemote {
    fn drop(&mut self) {
        self.core.connection().remove_handler(self.dropped_handler);
    }
}

impl ImagerRemote {
    /// Opens `Device@location`.
    pub fn new(name: &str) -> Result<ImagerRemote, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// A remote for `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<ImagerRemote, Error> {
        let (mut core, ids) = RemoteCore::new(device, conn, ImagerIds::register)?;
        let state = Rc::new(State {
            channels: RefCell::new(Box::new([ChannelDescription::default(); MAX_CHANNELS])),
            description: Cell::new(None),
            begin: Cell::new(None),
            end: Cell::new(None),
            end_taken: Cell::new(0),
            discarded: Cell::new(0),
            regions: Cell::new(0),
            bad: Cell::new(0),
            on_description: CallbackList::default(),
            on_begin: CallbackList::default(),
            on_end: CallbackList::default(),
            on_discarded: CallbackList::default(),
            on_region: RefCell::new(Vec::new()),
        });
        let s = state.clone();
        core.handle(ids.description, move |m| {
            let decoded = {
                let mut chans = s.channels.borrow_mut();
                codec::decode_description(m.payload, &mut chans)
            };
            let Ok(h) = decoded else {
                s.bad.set(s.bad.get() + 1);
                return;
            };
            let d = ImagerDescription {
                time: m.time,
                arrival: m.arrived(),
                cols: h.cols,
                rows: h.rows,
                depth: h.depth,
                channels: h.channels as usize,
            };
            s.description.set(Some(d));
            s.on_description.call(&d);
        });
        for type_id in [
            ids.region_u8,
            ids.region_u16,
            ids.region_u12in16,
            ids.region_f32,
        ] {
            let s = state.clone();
            core.handle(type_id, move |m| {
                let Some(d) = s.description.get() else {
                    return;
                };
                let region = match Region::decode(m.payload) {
                    Ok(r) if (r.header.channel as usize) < d.channels && r.header.channel >= 0 => r,
                    _ => {
                        s.bad.set(s.bad.get() + 1);
                        return;
                    }
                };
                s.regions.set(s.regions.get() + 1);
                s.call_regions(&ImagerRegion::new(
                    &region,
                    m.time,
                    m.sender_time,
                    m.arrived(),
                ));
            });
        }
        let s = state.clone();
        core.handle(ids.begin_frame, move |m| {
            if s.described() {
                if let Some(r) = s.frame(m, &s.begin) {
                    s.on_begin.call(&r);
                }
            }
        });
        let s = state.clone();
        core.handle(ids.end_frame, move |m| {
            if s.described() {
                if let Some(r) = s.frame(m, &s.end) {
                    s.on_end.call(&r);
                }
            }
        });
        let s = state.clone();
        core.handle(ids.discarded_frames, move |m| {
            if !s.described() {
                return;
            }
            let Ok(d) = DiscardedFrames::decode(m.payload) else {
                s.bad.set(s.bad.get() + 1);
                return;
            };
            s.discarded
                .set(s.discarded.get() + u64::from(d.count.max(1)));
            s.on_discarded.call(&DiscardedFramesReport {
                time: m.time,
                arrival: m.arrived(),
                count: d.count,
            });
        });
        let s = state.clone();
        let dropped_handler = conn.on_event(ConnectionEvent::DroppedConnection, move || {
            s.description.set(None);
        });
        Ok(ImagerRemote {
            core,
            ids,
            state,
            dropped_handler,
        })
    }

    /// Calls `f` with every region of every channel (after a description arrived). The
    /// region borrows the received message: copy what you keep
    /// ([`ImagerRegion::read_into`] into your image).
    pub fn on_region(&self, f: impl for<'a> FnMut(&ImagerRegion<'a>) + 'static) -> HandlerId {
        let id = HandlerId::fresh();
        self.state
            .on_region
            .borrow_mut()
            .push((id, Rc::new(RefCell::new(f))));
        id
    }

    /// Calls `f` with each description (size or channels may have changed).
    pub fn on_description(&self, f: impl FnMut(&ImagerDescription) + 'static) -> HandlerId {
        self.state.on_description.add(f)
    }

    /// Calls `f` at the beginning of each frame.
    pub fn on_begin_frame(&self, f: impl FnMut(&FrameReport) + 'static) -> HandlerId {
        self.state.on_begin.add(f)
    }

    /// Calls `f` at the end of each frame.
    pub fn on_end_frame(&self, f: impl FnMut(&FrameReport) + 'static) -> HandlerId {
        self.state.on_end.add(f)
    }

    /// Calls `f` with each discarded-frames notice.
    pub fn on_discarded_frames(
        &self,
        f: impl FnMut(&DiscardedFramesReport) + 'static,
    ) -> HandlerId {
        self.state.on_discarded.add(f)
    }

    /// Removes a callback any `on_*` of this remote returned.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        let s = &self.state;
        let region = || {
            let mut r = s.on_region.borrow_mut();
            let before = r.len();
            r.retain(|(i, _)| *i != id);
            r.len() != before
        };
        region()
            || s.on_description.remove(id)
            || s.on_begin.remove(id)
            || s.on_end.remove(id)
            || s.on_discarded.remove(id)
    }

    /// Asks the server to send at most `frames` more frames (added to a limit already in
    /// force); a negative count lifts the limit (the default). RELIABLE.
    pub fn throttle_sender(&self, frames: i32) -> Result<(), Error> {
        let mut buf = [0u8; ThrottleFrames::LEN];
        ThrottleFrames { frames }.encode(&mut buf);
        self.core.send(self.ids.throttle_frames, &buf)
    }

    /// The latest description, or `None` before one arrived (or since the connection
    /// dropped).
    pub fn description(&self) -> Option<ImagerDescription> {
        self.state.description.get()
    }

    /// True once a description arrived (C++ `is_description_valid`).
    pub fn is_description_valid(&self) -> bool {
        self.state.described()
    }

    /// Channel `i` of the latest description.
    pub fn channel(&self, i: usize) -> Option<ChannelDescription> {
        let n = self.state.description.get()?.channels;
        (i < n).then(|| self.state.channels.borrow()[i])
    }

    /// The index of the channel named `name`.
    pub fn channel_index(&self, name: &str) -> Option<usize> {
        let n = self.state.description.get()?.channels;
        let chans = self.state.channels.borrow();
        chans[..n]
            .iter()
            .position(|c| c.name.as_bytes() == name.as_bytes())
    }

    /// The newest begin-frame.
    pub fn last_begin_frame(&self) -> Option<FrameReport> {
        self.state.begin.get()
    }

    /// The newest end-frame.
    pub fn last_end_frame(&self) -> Option<FrameReport> {
        self.state.end.get()
    }

    /// The newest end-frame if it arrived since the last call (`seq` tells how many frames
    /// ended meanwhile).
    pub fn take_end_frame(&self) -> Option<FrameReport> {
        let r = self.state.end.get()?;
        (r.seq != self.state.end_taken.replace(r.seq)).then_some(r)
    }

    /// Regions delivered to callbacks so far.
    pub fn regions_received(&self) -> u64 {
        self.state.regions.get()
    }

    /// Frames the server said it discarded (a notice without a count counts as one).
    pub fn frames_discarded(&self) -> u64 {
        self.state.discarded.get()
    }

    /// Messages that could not be decoded (or named a channel the description lacks) and
    /// were ignored.
    pub fn bad_messages(&self) -> u64 {
        self.state.bad.get()
    }
}

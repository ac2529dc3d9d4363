//! The server half of an imager (C++ `vrpn_Imager_Server`).

use std::cell::{Cell, RefCell};
use std::rc::Rc;

use super::layout::{gather, BufferLayout, Pixel};
use super::{Extent, ImagerIds};
use crate::connection::{Connection, ConnectionEvent};
use crate::devices::base::{self, BaseIds};
use crate::dispatch::{SenderFilter, SenderId};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::class;
use crate::wire::payload::fixed_text::FixedText;
use crate::wire::payload::imager::{
    self as codec, ChannelDescription, DiscardedFrames, RegionHeader, ThrottleFrames, MAX_CHANNELS,
    REGION_HEADER_LEN,
};
use crate::wire::MAX_PAYLOAD;

/// What the server's handlers share with it.
struct State {
    ids: ImagerIds,
    sender: SenderId,
    /// Columns, rows, depth.
    size: Cell<(i32, i32, i32)>,
    channels: RefCell<Vec<ChannelDescription>>,
    description_sent: Cell<bool>,
    /// Whether a connecting or pinging client is sent the description (a relay waits until
    /// it has the upstream's).
    announce: Cell<bool>,
    /// Frames still allowed by the clients' throttle requests; -1: unlimited.
    frames_to_send: Cell<i32>,
    /// Frames dropped because of the throttle since the last one sent.
    dropped: Cell<u16>,
    /// The message being built (one C++ TCP message at most), reused for every message.
    buf: RefCell<Vec<u8>>,
}

impl State {
    fn send_description(&self, conn: &Connection) -> Result<(), Error> {
        let (cols, rows, depth) = self.size.get();
        let mut buf = self.buf.borrow_mut();
        let n = codec::encode_description(depth, rows, cols, &self.channels.borrow(), &mut buf);
        conn.pack_message(
            conn.now().wall,
            self.ids.description,
            self.sender,
            &buf[..n],
            class::RELIABLE,
        )?;
        self.description_sent.set(true);
        Ok(())
    }

    fn throttle(&self, frames: i32) {
        if frames < 0 {
            self.frames_to_send.set(-1);
        } else if self.frames_to_send.get() == -1 {
            self.frames_to_send.set(frames);
        } else {
            self.frames_to_send
                .set(self.frames_to_send.get().saturating_add(frames));
        }
    }
}

/// Server half of an imager: describes the image and sends frames of regions.
///
/// The description goes out when a client connects, when a client's remote pings (so a
/// client hears it before any region), before the first region after a change, and on
/// [`send_description`](Self::send_description). A client may throttle the server to a
/// number of frames ([`ImagerRemote::throttle_sender`](super::ImagerRemote::throttle_sender)):
/// [`send_begin_frame`](Self::send_begin_frame) then returns `Ok(false)` for each frame
/// beyond the limit, the frame's regions and end are not sent either, and the next frame
/// sent is preceded by a discarded-frames notice with the count. When the last client
/// leaves, the throttle is lifted.
pub struct ImagerServer {
    conn: Connection,
    base: BaseIds,
    state: Rc<State>,
}

impl ImagerServer {
    /// Registers an imager `device` of `cols` × `rows` × `depth` pixels on `conn` (a server
    /// connection, or any connection an in-process remote shares). Channels are added with
    /// [`add_channel`](Self::add_channel).
    pub fn new(
        device: &str,
        conn: &Connection,
        cols: i32,
        rows: i32,
        depth: i32,
    ) -> Result<ImagerServer, Error> {
        let (base, ids) = base::register_server(conn, device, ImagerIds::register)?;
        let state = Rc::new(State {
            ids,
            sender: base.sender,
            size: Cell::new((cols, rows, depth)),
            channels: RefCell::new(Vec::with_capacity(MAX_CHANNELS)),
            description_sent: Cell::new(false),
            announce: Cell::new(true),
            frames_to_send: Cell::new(-1),
            dropped: Cell::new(0),
            buf: RefCell::new(vec![0; MAX_PAYLOAD]),
        });
        let s = state.clone();
        conn.register_handler(base.ping, SenderFilter::Only(base.sender), move |m| {
            if s.announce.get() {
                let _ = s.send_description(m.connection());
            }
        });
        let (s, weak) = (state.clone(), conn.downgrade());
        conn.on_event(ConnectionEvent::GotConnection, move || {
            if let (true, Some(c)) = (s.announce.get(), weak.upgrade()) {
                let _ = s.send_description(&c);
            }
        });
        let s = state.clone();
        conn.register_handler(
            ids.throttle_frames,
            SenderFilter::Only(base.sender),
            move |m| {
                if let Ok(t) = ThrottleFrames::decode(m.payload) {
                    s.throttle(t.frames);
                }
            },
        );
        let s = state.clone();
        conn.on_event(ConnectionEvent::DroppedLastConnection, move || {
            s.frames_to_send.set(-1);
            s.dropped.set(0);
        });
        Ok(ImagerServer {
            conn: conn.clone(),
            base,
            state,
        })
    }

    /// This device's sender id on its connection.
    pub fn sender(&self) -> SenderId {
        self.base.sender
    }

    /// The connection the server reports on.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// The imager type ids on its connection.
    pub fn ids(&self) -> ImagerIds {
        self.state.ids
    }

    /// The sender and base type ids (text, ping, pong).
    pub fn base_ids(&self) -> BaseIds {
        self.base
    }

    /// Whether clients that connect or ping are sent the description (on by default). A
    /// relay turns it off until it knows the image: a C++ client takes the first description
    /// it hears as the image's size for good.
    pub(crate) fn set_announce(&self, on: bool) {
        self.state.announce.set(on);
    }

    /// Replaces the image's size and every channel at once, and sends the description (a
    /// relay copying another imager's). At most 100 channels.
    pub fn set_description(
        &self,
        cols: i32,
        rows: i32,
        depth: i32,
        channels: &[ChannelDescription],
    ) -> Result<(), Error> {
        if channels.len() > MAX_CHANNELS {
            return Err(Error::InvalidArgument(format!(
                "an imager has at most {MAX_CHANNELS} channels"
            )));
        }
        self.state.size.set((cols, rows, depth));
        {
            let mut c = self.state.channels.borrow_mut();
            c.clear();
            c.extend_from_slice(channels);
        }
        self.send_description()
    }

    /// Columns, rows and depth of the image.
    pub fn size(&self) -> (i32, i32, i32) {
        self.state.size.get()
    }

    /// The channels described so far.
    pub fn channels(&self) -> Vec<ChannelDescription> {
        self.state.channels.borrow().clone()
    }

    /// Frames the clients' throttle still allows (-1: no limit).
    pub fn frames_to_send(&self) -> i32 {
        self.state.frames_to_send.get()
    }

    /// Adds a channel; returns its index. Physical values are raw × `scale` + `offset`; a
    /// zero scale becomes 1 (as in C++). Errors: more than 100 channels, a name or units of
    /// 100 bytes or more.
    pub fn add_channel(
        &self,
        name: &str,
        units: &str,
        min_val: f32,
        max_val: f32,
        scale: f32,
        offset: f32,
    ) -> Result<usize, Error> {
        let mut chans = self.state.channels.borrow_mut();
        if chans.len() >= MAX_CHANNELS {
            return Err(Error::InvalidArgument(format!(
                "an imager has at most {MAX_CHANNELS} channels"
            )));
        }
        let text = |what: &str, t: &str| {
            FixedText::new(t).map_err(|_| {
                Error::InvalidArgument(format!(
                    "channel {what} {t:?} must be shorter than {} bytes, without NUL",
                    codec::NAME_LEN
                ))
            })
        };
        chans.push(ChannelDescription {
            min_val,
            max_val,
            offset,
            scale: if scale == 0.0 { 1.0 } else { scale },
            compression: 0,
            name: text("name", name)?,
            units: text("units", units)?,
        });
        self.state.description_sent.set(false);
        Ok(chans.len() - 1)
    }

    /// Sends the description (size and channels) now.
    pub fn send_description(&self) -> Result<(), Error> {
        self.state.send_description(&self.conn)
    }

    /// Changes the image's size and sends the new description. Every size must be positive.
    pub fn set_resolution(&self, cols: i32, rows: i32, depth: i32) -> Result<(), Error> {
        if cols <= 0 || rows <= 0 || depth <= 0 {
            return Err(Error::InvalidArgument(format!(
                "image size {cols}×{rows}×{depth} must be positive"
            )));
        }
        self.state.size.set((cols, rows, depth));
        self.send_description()
    }

    fn check_extent(&self, extent: &Extent) -> Result<(), Error> {
        let (cols, rows, depth) = self.state.size.get();
        extent.check(cols, rows, depth)
    }

    fn send_frame_extent(
        &self,
        type_id: crate::dispatch::TypeId,
        extent: &Extent,
        time: Option<TimeVal>,
    ) -> Result<(), Error> {
        let mut buf = [0u8; codec::FrameExtent::LEN];
        extent.to_frame().encode(&mut buf);
        let time = time.unwrap_or_else(|| self.conn.now().wall);
        self.conn
            .pack_message(time, type_id, self.base.sender, &buf, class::RELIABLE)
    }

    /// Starts a frame covering `extent` (`None` time: now). Returns `Ok(false)` when the
    /// clients' throttle drops this frame: send none of its regions then (they would be
    /// refused too). Before the first frame sent after dropped ones, a discarded-frames
    /// notice with their count goes out.
    pub fn send_begin_frame(&self, extent: &Extent, time: Option<TimeVal>) -> Result<bool, Error> {
        let s = &self.state;
        if s.frames_to_send.get() == 0 {
            s.dropped.set(s.dropped.get().saturating_add(1));
            return Ok(false);
        }
        if s.dropped.get() > 0 {
            self.send_discarded_frames(s.dropped.get(), None)?;
            s.dropped.set(0);
        }
        if s.frames_to_send.get() > 0 {
            s.frames_to_send.set(s.frames_to_send.get() - 1);
        }
        self.check_extent(extent)?;
        self.send_frame_extent(s.ids.begin_frame, extent, time)?;
        Ok(true)
    }

    /// Ends a frame. `Ok(false)` while the throttle is dropping frames.
    pub fn send_end_frame(&self, extent: &Extent, time: Option<TimeVal>) -> Result<bool, Error> {
        if self.state.dropped.get() > 0 {
            return Ok(false);
        }
        self.check_extent(extent)?;
        self.send_frame_extent(self.state.ids.end_frame, extent, time)?;
        Ok(true)
    }

    /// Tells the clients that `count` frames were dropped (0: some, count unknown).
    pub fn send_discarded_frames(&self, count: u16, time: Option<TimeVal>) -> Result<(), Error> {
        let mut buf = [0u8; DiscardedFrames::LEN];
        DiscardedFrames { count }.encode(&mut buf);
        let time = time.unwrap_or_else(|| self.conn.now().wall);
        self.conn.pack_message(
            time,
            self.state.ids.discarded_frames,
            self.base.sender,
            &buf,
            class::RELIABLE,
        )
    }

    /// Sends the pixels of `extent` of channel `channel`, taken from `image`, the whole
    /// image as `layout` describes it (C++ `send_region_using_base_pointer`). Pixels go as
    /// `T` (u8, u16 or f32), RELIABLE; `None` time means now.
    ///
    /// `Ok(false)`: the frame is being dropped by the throttle. Errors: an unknown channel,
    /// an extent outside the image, more pixels than one region holds ([`MAX_REGION_U8`],
    /// [`MAX_REGION_U16`], [`MAX_REGION_F32`]), a buffer the layout does not fit.
    /// Allocation-free.
    ///
    /// [`MAX_REGION_U8`]: super::MAX_REGION_U8
    /// [`MAX_REGION_U16`]: super::MAX_REGION_U16
    /// [`MAX_REGION_F32`]: super::MAX_REGION_F32
    pub fn send_region<T: Pixel>(
        &self,
        channel: usize,
        extent: &Extent,
        image: &[T],
        layout: &BufferLayout,
        time: Option<TimeVal>,
    ) -> Result<bool, Error> {
        self.send_region_with(channel, extent, image, layout, extent, time)
    }

    /// Like [`send_region`](Self::send_region) with `data` holding just the region's pixels,
    /// packed (C++ `send_region_using_first_pointer` with unit strides).
    pub fn send_region_packed<T: Pixel>(
        &self,
        channel: usize,
        extent: &Extent,
        data: &[T],
        time: Option<TimeVal>,
    ) -> Result<bool, Error> {
        let layout = BufferLayout::packed(extent.cols(), extent.rows());
        let local = Extent {
            c_min: 0,
            c_max: extent.c_max.wrapping_sub(extent.c_min),
            r_min: 0,
            r_max: extent.r_max.wrapping_sub(extent.r_min),
            d_min: 0,
            d_max: extent.d_max.wrapping_sub(extent.d_min),
        };
        self.send_region_with(channel, extent, data, &layout, &local, time)
    }

    /// Sends `extent` of the image, its pixels found in `data` at the `local` extent in
    /// `layout` (the same extent for a whole-image buffer, one starting at 0 for a packed
    /// region).
    fn send_region_with<T: Pixel>(
        &self,
        channel: usize,
        extent: &Extent,
        data: &[T],
        layout: &BufferLayout,
        local: &Extent,
        time: Option<TimeVal>,
    ) -> Result<bool, Error> {
        let s = &self.state;
        if s.dropped.get() > 0 {
            return Ok(false);
        }
        let nchan = s.channels.borrow().len();
        if channel >= nchan {
            return Err(Error::InvalidArgument(format!(
                "channel {channel} does not exist (the imager has {nchan})"
            )));
        }
        self.check_extent(extent)?;
        let vt = T::VALUE_TYPE;
        if extent.len() > vt.max_region() {
            return Err(Error::InvalidArgument(format!(
                "a region of {} pixels exceeds the {} of type {vt:?} one message holds",
                extent.len(),
                vt.max_region()
            )));
        }
        layout.check(local, data.len(), 1)?;
        if !s.description_sent.get() {
            s.send_description(&self.conn)?;
        }
        let time = time.unwrap_or_else(|| self.conn.now().wall);
        let mut buf = s.buf.borrow_mut();
        RegionHeader {
            channel: channel as i16,
            d_min: extent.d_min,
            d_max: extent.d_max,
            r_min: extent.r_min,
            r_max: extent.r_max,
            c_min: extent.c_min,
            c_max: extent.c_max,
            val_type: vt.code(),
        }
        .encode(&mut buf);
        let n = gather(data, layout, local, &mut buf[REGION_HEADER_LEN..]);
        self.conn.pack_message(
            time,
            s.ids.region(vt),
            self.base.sender,
            &buf[..REGION_HEADER_LEN + n],
            class::RELIABLE,
        )?;
        Ok(true)
    }
}

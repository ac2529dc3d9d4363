//! The imager remote from C (C++ `vrpn_Imager_Remote`): the description, regions handed to a
//! callback without a copy, frame ends, the throttle, and the copy of a region into the
//! application's image.

use std::ffi::{c_char, c_void};

use super::client::{
    callback, connection_state, index, mainloop, open, out_arg, Callbacks, Remote,
};
use super::handle::{self, write_out, Header, Object};
use super::types::{CCallback, VrpnTimeVal};
use super::{status, Failure, VrpnStatus};
use crate::devices::base::RemoteCore;
use crate::devices::imager::{
    BufferLayout, Extent, ImagerRegion, ImagerRemote, Pixel, ValueType, NAME_LEN,
};
use crate::time::TimeVal;

/// Bytes of a channel's name and units, NUL included.
pub const VRPN_IMAGER_NAME_LEN: usize = 100;
const _: () = assert!(VRPN_IMAGER_NAME_LEN == NAME_LEN);

/// Pixel type of a region: 8-bit (`vrpn_IMAGER_VALTYPE_UINT8`).
pub const VRPN_IMAGER_U8: u16 = 1;
/// 16-bit.
pub const VRPN_IMAGER_U16: u16 = 4;
/// 12-bit values in 16-bit words.
pub const VRPN_IMAGER_U12IN16: u16 = 5;
/// 32-bit float.
pub const VRPN_IMAGER_F32: u16 = 6;

/// A region of one channel, valid during the callback only: `data` points into the received
/// message.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct VrpnImagerRegion {
    /// The server's time stamp.
    pub time: VrpnTimeVal,
    /// Channel index in the description.
    pub channel: i32,
    /// First column.
    pub c_min: u16,
    /// Last column.
    pub c_max: u16,
    /// First row.
    pub r_min: u16,
    /// Last row.
    pub r_max: u16,
    /// First depth.
    pub d_min: u16,
    /// Last depth.
    pub d_max: u16,
    /// `VRPN_IMAGER_U8`, `_U16`, `_U12IN16` or `_F32`.
    pub value_type: u16,
    /// The pixels, little-endian, columns fastest, then rows, then depths.
    pub data: *const u8,
    /// Bytes at `data`.
    pub data_len: usize,
}

impl VrpnImagerRegion {
    fn from_region(r: &ImagerRegion<'_>) -> VrpnImagerRegion {
        let e = &r.extent;
        VrpnImagerRegion {
            time: r.time.into(),
            channel: r.channel as i32,
            c_min: e.c_min,
            c_max: e.c_max,
            r_min: e.r_min,
            r_max: e.r_max,
            d_min: e.d_min,
            d_max: e.d_max,
            value_type: r.value_type.code(),
            data: r.data.as_ptr(),
            data_len: r.data.len(),
        }
    }
}

/// The image's size and channel count.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VrpnImagerDescription {
    /// The server's time stamp.
    pub time: VrpnTimeVal,
    /// Columns.
    pub cols: i32,
    /// Rows.
    pub rows: i32,
    /// Depth.
    pub depth: i32,
    /// Channels.
    pub channels: i32,
}

/// One channel of the description.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct VrpnImagerChannel {
    /// NUL-terminated name.
    pub name: [c_char; VRPN_IMAGER_NAME_LEN],
    /// NUL-terminated units.
    pub units: [c_char; VRPN_IMAGER_NAME_LEN],
    /// Smallest raw value.
    pub min_val: f32,
    /// Largest raw value.
    pub max_val: f32,
    /// Physical value = raw × scale + offset.
    pub scale: f32,
    /// Physical value = raw × scale + offset.
    pub offset: f32,
}

/// A begin-frame or end-frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VrpnImagerFrame {
    /// The server's time stamp.
    pub time: VrpnTimeVal,
    /// First column.
    pub c_min: u16,
    /// Last column.
    pub c_max: u16,
    /// First row.
    pub r_min: u16,
    /// Last row.
    pub r_max: u16,
    /// First depth.
    pub d_min: u16,
    /// Last depth.
    pub d_max: u16,
    /// Frames ended (or begun) so far, 1 for the first.
    pub seq: u64,
}

/// How the application's image is laid out, in elements of its type (see
/// `BufferLayout` in docs/IMAGER.md).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VrpnImagerLayout {
    /// Elements from one column to the next (1: packed).
    pub col_stride: usize,
    /// Elements from one row to the next.
    pub row_stride: usize,
    /// Elements from one depth to the next.
    pub depth_stride: usize,
    /// 0, or the rows of a buffer stored upside down.
    pub flip_rows: u16,
    /// Elements each value is written to (0 or 1: one).
    pub repeat: usize,
}

/// Receives regions; `region` and its data are valid during the call only.
pub type VrpnImagerRegionCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, region: *const VrpnImagerRegion)>;
/// Receives descriptions.
pub type VrpnImagerDescriptionCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, description: *const VrpnImagerDescription)>;
/// Receives frame ends.
pub type VrpnImagerFrameCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, frame: *const VrpnImagerFrame)>;

/// An imager remote.
pub struct VrpnImager {
    header: Header,
    remote: ImagerRemote,
    callbacks: Callbacks,
}

impl Object for VrpnImager {
    const TAG: u32 = 0x7672_0010;
    const NAME: &'static str = "VrpnImager";
    fn header(&self) -> &Header {
        &self.header
    }
}

impl Remote for VrpnImager {
    fn core(&self) -> &RemoteCore {
        &self.remote
    }
}

/// Opens the imager `name` (`Device@host[:port]`); NULL on failure.
#[no_mangle]
pub extern "C" fn vrpn_imager_open(name: *const c_char) -> *mut VrpnImager {
    open(name, |n| {
        Ok(VrpnImager {
            header: Header::new::<VrpnImager>(),
            remote: ImagerRemote::new(n)?,
            callbacks: Callbacks::default(),
        })
    })
}

/// Frees an imager remote (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_imager_free(imager: *mut VrpnImager) -> VrpnStatus {
    handle::free(imager)
}

/// Services the imager's connection without blocking; runs callbacks.
#[no_mangle]
pub extern "C" fn vrpn_imager_mainloop(imager: *mut VrpnImager) -> VrpnStatus {
    mainloop(imager)
}

/// The connection's state: a `VrpnConnectionState` (>= 0) or a negative `VrpnStatus`.
#[no_mangle]
pub extern "C" fn vrpn_imager_connection_state(imager: *const VrpnImager) -> i32 {
    connection_state(imager)
}

/// Calls `callback(userdata, region)` for every region (once a description arrived).
#[no_mangle]
pub extern "C" fn vrpn_imager_on_region(
    imager: *mut VrpnImager,
    callback: VrpnImagerRegionCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(imager, |i| {
        let cb: CCallback<VrpnImagerRegion> = self::callback(callback, userdata)?;
        let id = i
            .remote
            .on_region(move |r| cb.call(VrpnImagerRegion::from_region(r)));
        i.callbacks.add(id, id_out)
    }))
}

/// Calls `callback(userdata, description)` for every description.
#[no_mangle]
pub extern "C" fn vrpn_imager_on_description(
    imager: *mut VrpnImager,
    callback: VrpnImagerDescriptionCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(imager, |i| {
        let cb: CCallback<VrpnImagerDescription> = self::callback(callback, userdata)?;
        let id = i.remote.on_description(move |d| {
            cb.call(VrpnImagerDescription {
                time: d.time.into(),
                cols: d.cols,
                rows: d.rows,
                depth: d.depth,
                channels: d.channels as i32,
            })
        });
        i.callbacks.add(id, id_out)
    }))
}

/// Calls `callback(userdata, frame)` at the end of every frame.
#[no_mangle]
pub extern "C" fn vrpn_imager_on_end_frame(
    imager: *mut VrpnImager,
    callback: VrpnImagerFrameCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(imager, |i| {
        let cb: CCallback<VrpnImagerFrame> = self::callback(callback, userdata)?;
        let id = i.remote.on_end_frame(move |f| {
            let e = &f.extent;
            cb.call(VrpnImagerFrame {
                time: f.time.into(),
                c_min: e.c_min,
                c_max: e.c_max,
                r_min: e.r_min,
                r_max: e.r_max,
                d_min: e.d_min,
                d_max: e.d_max,
                seq: f.seq,
            })
        });
        i.callbacks.add(id, id_out)
    }))
}

/// Removes a callback by the id an `vrpn_imager_on_*` gave.
#[no_mangle]
pub extern "C" fn vrpn_imager_remove_callback(imager: *mut VrpnImager, id: u64) -> VrpnStatus {
    status(handle::with(imager, |i| {
        i.remote.remove_callback(i.callbacks.take(id)?);
        Ok(VrpnStatus::Ok)
    }))
}

/// Asks the server for at most `frames` more frames; negative lifts the limit.
#[no_mangle]
pub extern "C" fn vrpn_imager_throttle(imager: *mut VrpnImager, frames: i32) -> VrpnStatus {
    status(handle::with(imager, |i| {
        i.remote.throttle_sender(frames)?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Copies the latest description into `*out` (`VRPN_STATUS_NO_DATA` before one arrived).
#[no_mangle]
pub extern "C" fn vrpn_imager_description(
    imager: *const VrpnImager,
    out: *mut VrpnImagerDescription,
) -> VrpnStatus {
    status(handle::with(imager, |i| {
        out_arg(out, "description")?;
        let Some(d) = i.remote.description() else {
            return Ok(VrpnStatus::NoData);
        };
        let v = VrpnImagerDescription {
            time: d.time.into(),
            cols: d.cols,
            rows: d.rows,
            depth: d.depth,
            channels: d.channels as i32,
        };
        // SAFETY: `out` is a writable VrpnImagerDescription (checked non-NULL above).
        unsafe { write_out(out, v, "description")? };
        Ok(VrpnStatus::Ok)
    }))
}

/// Copies channel `index` of the latest description into `*out` (`VRPN_STATUS_NO_DATA` when
/// there is no such channel).
#[no_mangle]
pub extern "C" fn vrpn_imager_channel(
    imager: *const VrpnImager,
    index: i32,
    out: *mut VrpnImagerChannel,
) -> VrpnStatus {
    status(handle::with(imager, |i| {
        let n = self::index(index, "channel")?;
        out_arg(out, "channel")?;
        let Some(c) = i.remote.channel(n) else {
            return Ok(VrpnStatus::NoData);
        };
        let text = |t: &[u8]| {
            let mut a = [0 as c_char; VRPN_IMAGER_NAME_LEN];
            for (d, s) in a.iter_mut().zip(t.iter().take(VRPN_IMAGER_NAME_LEN - 1)) {
                *d = *s as c_char;
            }
            a
        };
        let v = VrpnImagerChannel {
            name: text(c.name.as_bytes()),
            units: text(c.units.as_bytes()),
            min_val: c.min_val,
            max_val: c.max_val,
            scale: c.scale,
            offset: c.offset,
        };
        // SAFETY: `out` is a writable VrpnImagerChannel (checked non-NULL above).
        unsafe { write_out(out, v, "channel")? };
        Ok(VrpnStatus::Ok)
    }))
}

/// The Rust view of a C region: its extent, type and bytes.
///
/// # Safety
/// `region` is NULL or a region a callback received, still inside that callback.
unsafe fn region_arg<'a>(region: *const VrpnImagerRegion) -> Result<ImagerRegion<'a>, Failure> {
    if region.is_null() {
        return Err(Failure::new(VrpnStatus::NullArgument, "region is NULL"));
    }
    // SAFETY: non-null and valid during the callback (caller's contract).
    let r = unsafe { *region };
    let value_type = ValueType::from_code(r.value_type)
        .ok_or_else(|| Failure::invalid(format!("value type {} is unknown", r.value_type)))?;
    let extent = Extent {
        c_min: r.c_min,
        c_max: r.c_max,
        r_min: r.r_min,
        r_max: r.r_max,
        d_min: r.d_min,
        d_max: r.d_max,
    };
    let needed = extent.len().checked_mul(value_type.size());
    if r.data.is_null() || needed.map_or(true, |n| n > r.data_len) {
        return Err(Failure::invalid(
            "the region's data does not hold its extent (use the region a callback received)",
        ));
    }
    // SAFETY: `data` points to `data_len` bytes of the message the callback is reading.
    let data = unsafe { std::slice::from_raw_parts(r.data, r.data_len) };
    let t: TimeVal = r.time.into();
    Ok(ImagerRegion {
        time: t,
        sender_time: t,
        arrival: t,
        channel: usize::try_from(r.channel).unwrap_or(0),
        extent,
        value_type,
        data,
    })
}

/// Copies a region into an image of `len` elements of `T` laid out as `layout` says.
///
/// # Safety
/// `region` as for [`region_arg`]; `image` points to `len` writable elements.
unsafe fn read<T: Pixel>(
    region: *const VrpnImagerRegion,
    image: *mut T,
    len: usize,
    layout: *const VrpnImagerLayout,
) -> VrpnStatus {
    status(handle::guard(|| {
        // SAFETY: forwarded from the caller.
        let r = unsafe { region_arg(region)? };
        if image.is_null() || layout.is_null() {
            return Err(Failure::new(
                VrpnStatus::NullArgument,
                "image or layout is NULL",
            ));
        }
        // SAFETY: non-null, a valid layout struct (caller's contract).
        let l = unsafe { *layout };
        let layout = BufferLayout {
            col_stride: l.col_stride,
            row_stride: l.row_stride,
            depth_stride: l.depth_stride,
            flip_rows: (l.flip_rows > 0).then_some(l.flip_rows),
            repeat: l.repeat.max(1),
        };
        // SAFETY: `image` points to `len` writable elements (caller's contract).
        let out = unsafe { std::slice::from_raw_parts_mut(image, len) };
        r.read_into(out, &layout)?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Copies `region` (inside its callback) into the 8-bit image `image` of `len` elements laid
/// out as `layout` says, converting the pixels. Every index is checked first: a region that
/// does not fit is `VRPN_STATUS_INVALID_ARGUMENT` and nothing is written.
///
/// # Safety
/// `region` is the pointer a region callback received, used inside that callback; `image`
/// points to `len` writable bytes; `layout` to a `VrpnImagerLayout`.
#[no_mangle]
pub unsafe extern "C" fn vrpn_imager_region_read_u8(
    region: *const VrpnImagerRegion,
    image: *mut u8,
    len: usize,
    layout: *const VrpnImagerLayout,
) -> VrpnStatus {
    // SAFETY: forwarded from the caller.
    unsafe { read(region, image, len, layout) }
}

/// As `vrpn_imager_region_read_u8` into a 16-bit image.
///
/// # Safety
/// As `vrpn_imager_region_read_u8`, with `len` writable `uint16_t`.
#[no_mangle]
pub unsafe extern "C" fn vrpn_imager_region_read_u16(
    region: *const VrpnImagerRegion,
    image: *mut u16,
    len: usize,
    layout: *const VrpnImagerLayout,
) -> VrpnStatus {
    // SAFETY: forwarded from the caller.
    unsafe { read(region, image, len, layout) }
}

/// As `vrpn_imager_region_read_u8` into a float image.
///
/// # Safety
/// As `vrpn_imager_region_read_u8`, with `len` writable `float`.
#[no_mangle]
pub unsafe extern "C" fn vrpn_imager_region_read_f32(
    region: *const VrpnImagerRegion,
    image: *mut f32,
    len: usize,
    layout: *const VrpnImagerLayout,
) -> VrpnStatus {
    // SAFETY: forwarded from the caller.
    unsafe { read(region, image, len, layout) }
}

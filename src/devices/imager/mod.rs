//! Imager (`vrpn_Imager`): a stream of images. The server describes the image (size and
//! channels), then sends each frame as begin-frame, regions of pixels, end-frame; a client
//! may throttle it to a number of frames. [`ImagerServer`] is the server half,
//! [`ImagerRemote`] the client half; [`ImagerPoseServer`] and [`ImagerPoseRemote`] carry
//! where the image lies in space (`vrpn_ImagerPose`).
//!
//! Regions travel as the pixels of one channel over an inclusive extent of columns, rows and
//! depths, packed columns fastest; a region holds at most 63960 bytes of pixels (one C++ TCP
//! message), so a large frame is sent as several regions. The remote hands each region to
//! its callbacks borrowed from the received message ([`ImagerRegion`]): nothing is copied or
//! allocated per region.

use crate::connection::Connection;
use crate::dispatch::TypeId;
use crate::error::Error;
use crate::wire::payload::imager as codec;

mod layout;
mod pose;
mod region;
mod relay;
mod remote;
mod server;

pub use codec::{
    ChannelDescription, FrameExtent, ValueType, MAX_CHANNELS, MAX_REGION_F32, MAX_REGION_U16,
    MAX_REGION_U8, NAME_LEN, TYPE_NAMES,
};
pub use layout::{BufferLayout, Pixel};
pub use pose::{ImagerPose, ImagerPoseRemote, ImagerPoseReport, ImagerPoseServer};
pub use region::ImagerRegion;
pub use relay::ImagerRelay;
pub use remote::{DiscardedFramesReport, FrameReport, ImagerDescription, ImagerRemote};
pub use server::ImagerServer;

/// Ids of the nine imager types on one connection.
#[derive(Clone, Copy, Debug)]
pub struct ImagerIds {
    /// Size and channels.
    pub description: TypeId,
    /// Start of a frame.
    pub begin_frame: TypeId,
    /// End of a frame.
    pub end_frame: TypeId,
    /// Frames dropped.
    pub discarded_frames: TypeId,
    /// Throttle request.
    pub throttle_frames: TypeId,
    /// 8-bit region.
    pub region_u8: TypeId,
    /// 16-bit region.
    pub region_u16: TypeId,
    /// 12-in-16-bit region.
    pub region_u12in16: TypeId,
    /// Float region.
    pub region_f32: TypeId,
}

impl ImagerIds {
    /// Registers the nine types in C++ order.
    pub fn register(conn: &Connection) -> Result<ImagerIds, Error> {
        let mut ids = [TypeId(0); 9];
        for (slot, name) in ids.iter_mut().zip(TYPE_NAMES) {
            *slot = conn.register_type(name)?;
        }
        Ok(ImagerIds {
            description: ids[0],
            begin_frame: ids[1],
            end_frame: ids[2],
            discarded_frames: ids[3],
            throttle_frames: ids[4],
            region_u8: ids[5],
            region_u16: ids[6],
            region_u12in16: ids[7],
            region_f32: ids[8],
        })
    }

    /// The region message type for pixels of `t`.
    pub fn region(&self, t: ValueType) -> TypeId {
        match t {
            ValueType::U8 => self.region_u8,
            ValueType::U16 => self.region_u16,
            ValueType::U12In16 => self.region_u12in16,
            ValueType::F32 => self.region_f32,
        }
    }
}

/// An inclusive extent of an image: columns, rows and depths.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Extent {
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
}

impl Extent {
    /// Columns `c_min..=c_max` and rows `r_min..=r_max` of depth 0.
    pub fn rect(c_min: u16, c_max: u16, r_min: u16, r_max: u16) -> Extent {
        Extent {
            c_min,
            c_max,
            r_min,
            r_max,
            d_min: 0,
            d_max: 0,
        }
    }

    /// The whole of a `cols` × `rows` × `depth` image (each at least 1).
    pub fn whole(cols: u16, rows: u16, depth: u16) -> Extent {
        Extent {
            c_min: 0,
            c_max: cols.saturating_sub(1),
            r_min: 0,
            r_max: rows.saturating_sub(1),
            d_min: 0,
            d_max: depth.saturating_sub(1),
        }
    }

    /// Number of columns.
    pub fn cols(&self) -> usize {
        span(self.c_min, self.c_max)
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        span(self.r_min, self.r_max)
    }

    /// Number of depths.
    pub fn depths(&self) -> usize {
        span(self.d_min, self.d_max)
    }

    /// Pixels in the extent.
    pub fn len(&self) -> usize {
        self.cols() * self.rows() * self.depths()
    }

    /// True when a range is reversed.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Checks the extent against an image of `cols` × `rows` × `depth`: every range in
    /// order and inside the image.
    pub(crate) fn check(&self, cols: i32, rows: i32, depth: i32) -> Result<(), Error> {
        let bad = |what: &str, lo: u16, hi: u16, n: i32| {
            Err(Error::InvalidArgument(format!(
                "{what} range {lo}..={hi} is not inside the image's 0..{n}"
            )))
        };
        if self.r_min > self.r_max || i32::from(self.r_max) >= rows {
            return bad("row", self.r_min, self.r_max, rows);
        }
        if self.c_min > self.c_max || i32::from(self.c_max) >= cols {
            return bad("column", self.c_min, self.c_max, cols);
        }
        if self.d_min > self.d_max || i32::from(self.d_max) >= depth {
            return bad("depth", self.d_min, self.d_max, depth);
        }
        Ok(())
    }

    pub(crate) fn to_frame(self) -> FrameExtent {
        FrameExtent {
            d_min: self.d_min,
            d_max: self.d_max,
            r_min: self.r_min,
            r_max: self.r_max,
            c_min: self.c_min,
            c_max: self.c_max,
        }
    }

    pub(crate) fn from_frame(f: &FrameExtent) -> Extent {
        Extent {
            c_min: f.c_min,
            c_max: f.c_max,
            r_min: f.r_min,
            r_max: f.r_max,
            d_min: f.d_min,
            d_max: f.d_max,
        }
    }
}

fn span(lo: u16, hi: u16) -> usize {
    if hi >= lo {
        usize::from(hi - lo) + 1
    } else {
        0
    }
}

//! A region as the remote's callbacks see it: the pixels borrowed from the received
//! message, read one at a time or copied into the application's image buffer.

use super::layout::{scatter, BufferLayout, Pixel};
use super::{Extent, ValueType};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::payload::imager::Region;

/// One region of one channel, valid during the callback (C++ `vrpn_Imager_Region`).
#[derive(Clone, Copy, Debug)]
pub struct ImagerRegion<'a> {
    /// The server's time stamp (translated to the local clock when clock synchronisation is
    /// in effect).
    pub time: TimeVal,
    /// The time stamp as the server wrote it.
    pub sender_time: TimeVal,
    /// When the message arrived here (the pass that read it).
    pub arrival: TimeVal,
    /// Channel index in the description.
    pub channel: usize,
    /// The columns, rows and depths the region covers.
    pub extent: Extent,
    /// The type of its pixels.
    pub value_type: ValueType,
    /// The pixels, little-endian, columns fastest, then rows, then depths.
    pub data: &'a [u8],
}

impl<'a> ImagerRegion<'a> {
    pub(crate) fn new(
        region: &Region<'a>,
        time: TimeVal,
        sender_time: TimeVal,
        arrival: TimeVal,
    ) -> ImagerRegion<'a> {
        let h = &region.header;
        ImagerRegion {
            time,
            sender_time,
            arrival,
            channel: h.channel as usize,
            extent: Extent {
                c_min: h.c_min,
                c_max: h.c_max,
                r_min: h.r_min,
                r_max: h.r_max,
                d_min: h.d_min,
                d_max: h.d_max,
            },
            value_type: region.val_type,
            data: region.data,
        }
    }

    /// Pixels in the region.
    pub fn len(&self) -> usize {
        self.extent.len()
    }

    /// True for a region without pixels (never sent by a server).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The wire bytes of pixel (`col`, `row`, `depth`), if the region holds it.
    fn pixel_bytes(&self, col: u16, row: u16, depth: u16) -> Option<&'a [u8]> {
        let e = &self.extent;
        if !(e.c_min..=e.c_max).contains(&col)
            || !(e.r_min..=e.r_max).contains(&row)
            || !(e.d_min..=e.d_max).contains(&depth)
        {
            return None;
        }
        let i = usize::from(col - e.c_min)
            + e.cols() * (usize::from(row - e.r_min) + e.rows() * usize::from(depth - e.d_min));
        let size = self.value_type.size();
        self.data.get(i * size..(i + 1) * size)
    }

    /// Pixel (`col`, `row`, `depth`) as `T` (converted if the region's type differs), or
    /// `None` outside the region. For whole regions [`read_into`](Self::read_into) is
    /// faster.
    pub fn get<T: Pixel>(&self, col: u16, row: u16, depth: u16) -> Option<T> {
        self.pixel_bytes(col, row, depth)
            .map(|b| T::read_wire(self.value_type, b))
    }

    /// Pixel (`col`, `row`) of depth 0 as `T`.
    pub fn get_2d<T: Pixel>(&self, col: u16, row: u16) -> Option<T> {
        self.get(col, row, 0)
    }

    /// Copies the region into `image`, an application's whole image laid out as `layout`
    /// says, converting the pixels to `T` (C++ `decode_unscaled_region_using_base_pointer`).
    /// Every index is checked first: a region that does not fit the buffer is an error and
    /// nothing is written. Allocation-free.
    pub fn read_into<T: Pixel>(&self, image: &mut [T], layout: &BufferLayout) -> Result<(), Error> {
        let repeat = layout.repeat.max(1);
        layout.check(&self.extent, image.len(), repeat)?;
        scatter(self.value_type, self.data, layout, &self.extent, image);
        Ok(())
    }
}

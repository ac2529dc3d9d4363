//! Where the pixels of an image sit in an application's buffer ([`BufferLayout`]), and the
//! pixel types a region carries ([`Pixel`]): the copies between a buffer and a region's
//! little-endian wire bytes, in both directions, bounds-checked before the first byte moves.

use super::{Extent, ValueType};
use crate::error::Error;

/// How an application's buffer holds an image, in elements of the buffer's type.
///
/// Pixel (column `c`, row `r`, depth `d`) is element
/// `d × depth_stride + r' × row_stride + c × col_stride`, where `r'` is `r`, or
/// `flip_rows − 1 − r` when [`flip_rows`](Self::flip_rows) is set (images stored bottom row
/// first, as OpenGL textures are). When reading a region into a buffer, each value is
/// written to `repeat` consecutive elements from there (one gray value into R, G and B).
///
/// C++ `send_region_using_base_pointer` / `decode_unscaled_region_using_base_pointer` take the
/// same strides; for regions that do not start at column 0 with a column stride other than 1,
/// C++ offsets the row by `c_min` elements instead of `c_min × col_stride` (a C++ defect not
/// reproduced here).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BufferLayout {
    /// Elements from one column to the next (1: packed; 3: one channel of RGB).
    pub col_stride: usize,
    /// Elements from one row to the next.
    pub row_stride: usize,
    /// Elements from one depth to the next.
    pub depth_stride: usize,
    /// `Some(rows)`: rows are stored upside down in a buffer of `rows` rows.
    pub flip_rows: Option<u16>,
    /// Reading only: elements each value is written to (at most `col_stride`).
    pub repeat: usize,
}

impl BufferLayout {
    /// A packed `cols` × `rows` (× any depth) image: columns fastest, then rows, then depths.
    pub fn packed(cols: usize, rows: usize) -> BufferLayout {
        BufferLayout {
            col_stride: 1,
            row_stride: cols,
            depth_stride: cols * rows,
            flip_rows: None,
            repeat: 1,
        }
    }

    /// One component of `components` interleaved per pixel (e.g. 3 for RGB); point the
    /// buffer slice at the component's first element.
    pub fn interleaved(cols: usize, rows: usize, components: usize) -> BufferLayout {
        BufferLayout {
            col_stride: components,
            row_stride: cols * components,
            depth_stride: cols * rows * components,
            flip_rows: None,
            repeat: 1,
        }
    }

    /// The same layout with rows stored upside down in a buffer of `rows` rows.
    pub fn flipped(self, rows: u16) -> BufferLayout {
        BufferLayout {
            flip_rows: Some(rows),
            ..self
        }
    }

    /// The same layout writing each value to `repeat` consecutive elements when reading.
    pub fn repeated(self, repeat: usize) -> BufferLayout {
        BufferLayout { repeat, ..self }
    }

    #[inline]
    fn row(&self, r: u16) -> usize {
        match self.flip_rows {
            Some(n) => usize::from(n) - 1 - usize::from(r),
            None => usize::from(r),
        }
    }

    /// Checks that every element the extent touches (with `repeat` copies) lies inside a
    /// buffer of `len` elements.
    pub(crate) fn check(&self, extent: &Extent, len: usize, repeat: usize) -> Result<(), Error> {
        if repeat == 0 || repeat > self.col_stride.max(1) {
            return Err(Error::InvalidArgument(format!(
                "repeat {repeat} must be between 1 and the column stride {}",
                self.col_stride
            )));
        }
        if let Some(n) = self.flip_rows {
            if extent.r_max >= n {
                return Err(Error::InvalidArgument(format!(
                    "row {} is outside the {n} rows of a flipped buffer",
                    extent.r_max
                )));
            }
        }
        // Every term grows with its coordinate, so the last element is at the largest ones.
        let last_row = match self.flip_rows {
            Some(_) => self.row(extent.r_min),
            None => usize::from(extent.r_max),
        };
        let last = usize::from(extent.d_max)
            .checked_mul(self.depth_stride)
            .and_then(|a| {
                last_row
                    .checked_mul(self.row_stride)
                    .and_then(|b| a.checked_add(b))
            })
            .and_then(|a| {
                usize::from(extent.c_max)
                    .checked_mul(self.col_stride)
                    .and_then(|b| a.checked_add(b))
            })
            .and_then(|a| a.checked_add(repeat - 1));
        match last {
            Some(i) if i < len => Ok(()),
            _ => Err(Error::InvalidArgument(format!(
                "the buffer of {len} elements does not hold columns {}..={}, rows {}..={}, \
                 depths {}..={} in this layout",
                extent.c_min, extent.c_max, extent.r_min, extent.r_max, extent.d_min, extent.d_max
            ))),
        }
    }

    /// Calls `f(index)` for every pixel of the extent in wire order (columns fastest, then
    /// rows, then depths). The caller has run [`check`](Self::check).
    #[inline]
    pub(crate) fn for_each(&self, extent: &Extent, mut f: impl FnMut(usize)) {
        for d in extent.d_min..=extent.d_max {
            for r in extent.r_min..=extent.r_max {
                let base = usize::from(d) * self.depth_stride + self.row(r) * self.row_stride;
                for c in extent.c_min..=extent.c_max {
                    f(base + usize::from(c) * self.col_stride);
                }
            }
        }
    }

    /// The start of each row of the extent in wire order (for packed copies).
    #[inline]
    pub(crate) fn for_each_row(&self, extent: &Extent, mut f: impl FnMut(usize)) {
        for d in extent.d_min..=extent.d_max {
            for r in extent.r_min..=extent.r_max {
                f(usize::from(d) * self.depth_stride
                    + self.row(r) * self.row_stride
                    + usize::from(extent.c_min) * self.col_stride);
            }
        }
    }
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for u8 {}
    impl Sealed for u16 {}
    impl Sealed for f32 {}
}

/// A pixel type a region can carry and a buffer can hold: `u8`, `u16` or `f32`.
///
/// Reading a region of another type converts each value as C++ does where C++ converts
/// (16-bit to 8-bit keeps the high byte, 8-bit to 16-bit shifts left by 8, float to
/// integer truncates) and, where C++ refuses, the obvious way (12-bit to 8-bit keeps the
/// high 8 of the 12 bits; integers to float are exact; float to integer saturates).
pub trait Pixel: Copy + Default + sealed::Sealed + 'static {
    /// The type a region of these pixels is sent as.
    const VALUE_TYPE: ValueType;
    /// Writes the value little-endian at the start of `out`.
    fn write_le(self, out: &mut [u8]);
    /// Reads a value of wire type `t` (little-endian, `t.size()` bytes) as this type.
    fn read_wire(t: ValueType, bytes: &[u8]) -> Self;
}

#[inline]
fn le_u16(b: &[u8]) -> u16 {
    u16::from_le_bytes([b[0], b[1]])
}

#[inline]
fn le_f32(b: &[u8]) -> f32 {
    f32::from_le_bytes([b[0], b[1], b[2], b[3]])
}

impl Pixel for u8 {
    const VALUE_TYPE: ValueType = ValueType::U8;
    #[inline]
    fn write_le(self, out: &mut [u8]) {
        out[0] = self;
    }
    #[inline]
    fn read_wire(t: ValueType, b: &[u8]) -> u8 {
        match t {
            ValueType::U8 => b[0],
            ValueType::U16 => (le_u16(b) >> 8) as u8,
            ValueType::U12In16 => (le_u16(b) >> 4) as u8,
            ValueType::F32 => le_f32(b) as u8,
        }
    }
}

impl Pixel for u16 {
    const VALUE_TYPE: ValueType = ValueType::U16;
    #[inline]
    fn write_le(self, out: &mut [u8]) {
        out[..2].copy_from_slice(&self.to_le_bytes());
    }
    #[inline]
    fn read_wire(t: ValueType, b: &[u8]) -> u16 {
        match t {
            ValueType::U8 => u16::from(b[0]) << 8,
            ValueType::U16 | ValueType::U12In16 => le_u16(b),
            ValueType::F32 => le_f32(b) as u16,
        }
    }
}

impl Pixel for f32 {
    const VALUE_TYPE: ValueType = ValueType::F32;
    #[inline]
    fn write_le(self, out: &mut [u8]) {
        out[..4].copy_from_slice(&self.to_le_bytes());
    }
    #[inline]
    fn read_wire(t: ValueType, b: &[u8]) -> f32 {
        match t {
            ValueType::U8 => f32::from(b[0]),
            ValueType::U16 | ValueType::U12In16 => f32::from(le_u16(b)),
            ValueType::F32 => le_f32(b),
        }
    }
}

/// Copies the pixels of `extent` from `image` into `out` as little-endian wire bytes;
/// returns the bytes written. The caller has checked the layout and `out`'s size.
pub(crate) fn gather<T: Pixel>(
    image: &[T],
    layout: &BufferLayout,
    extent: &Extent,
    out: &mut [u8],
) -> usize {
    let size = T::VALUE_TYPE.size();
    let mut off = 0;
    if layout.col_stride == 1 {
        let cols = extent.cols();
        layout.for_each_row(extent, |start| {
            for (v, o) in image[start..start + cols]
                .iter()
                .zip(out[off..off + cols * size].chunks_exact_mut(size))
            {
                v.write_le(o);
            }
            off += cols * size;
        });
    } else {
        layout.for_each(extent, |i| {
            image[i].write_le(&mut out[off..off + size]);
            off += size;
        });
    }
    off
}

/// Copies wire pixels of type `t` covering `extent` into `image`, converting to `T`. The
/// caller has checked the layout (with `layout.repeat`) and that `data` holds the extent.
pub(crate) fn scatter<T: Pixel>(
    t: ValueType,
    data: &[u8],
    layout: &BufferLayout,
    extent: &Extent,
    image: &mut [T],
) {
    let size = t.size();
    let repeat = layout.repeat.max(1);
    let mut values = data.chunks_exact(size);
    if layout.col_stride == 1 && repeat == 1 {
        let cols = extent.cols();
        layout.for_each_row(extent, |start| {
            for (slot, b) in image[start..start + cols].iter_mut().zip(values.by_ref()) {
                *slot = T::read_wire(t, b);
            }
        });
    } else {
        layout.for_each(extent, |i| {
            if let Some(b) = values.next() {
                let v = T::read_wire(t, b);
                image[i..i + repeat].fill(v);
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gather_and_scatter_agree_in_every_layout() {
        let (cols, rows) = (5usize, 4usize);
        let image: Vec<u16> = (0..(cols * rows) as u16).map(|v| v * 300).collect();
        let extent = Extent::rect(1, 3, 1, 2);
        for layout in [
            BufferLayout::packed(cols, rows),
            BufferLayout::packed(cols, rows).flipped(rows as u16),
        ] {
            layout.check(&extent, image.len(), 1).unwrap();
            let mut wire = [0u8; 64];
            let n = gather(&image, &layout, &extent, &mut wire);
            assert_eq!(n, 6 * 2);
            let mut back = vec![0u16; image.len()];
            scatter(ValueType::U16, &wire[..n], &layout, &extent, &mut back);
            for r in 1..=2u16 {
                for c in 1..=3u16 {
                    let i = layout.row(r) * cols + usize::from(c);
                    assert_eq!(back[i], image[i]);
                }
            }
        }
        // Flipped: the first wire row is buffer row rows-1-r_min.
        let flipped = BufferLayout::packed(cols, rows).flipped(rows as u16);
        let mut wire = [0u8; 64];
        gather(&image, &flipped, &extent, &mut wire);
        assert_eq!(le_u16(&wire[0..2]), image[(rows - 2) * cols + 1]);
    }

    #[test]
    fn interleaved_with_repeat_and_conversion() {
        // A gray 8-bit region into the R, G and B of an RGB buffer, as the C++ test client
        // does; 16-bit wire values keep their high byte.
        let extent = Extent::rect(0, 1, 0, 0);
        let wire = [0x34u8, 0x12, 0x78, 0x56];
        let layout = BufferLayout::interleaved(2, 1, 3).repeated(3);
        layout.check(&extent, 6, 3).unwrap();
        let mut rgb = [0u8; 6];
        scatter(ValueType::U16, &wire, &layout, &extent, &mut rgb);
        assert_eq!(rgb, [0x12, 0x12, 0x12, 0x56, 0x56, 0x56]);
        assert_eq!(u16::read_wire(ValueType::U8, &[0x80]), 0x8000);
        assert_eq!(u8::read_wire(ValueType::F32, &300.0f32.to_le_bytes()), 255);
        assert_eq!(
            u8::read_wire(ValueType::U12In16, &0x0fffu16.to_le_bytes()),
            0xff
        );
    }

    #[test]
    fn checks_refuse_what_does_not_fit() {
        let extent = Extent::rect(0, 4, 0, 3);
        let l = BufferLayout::packed(5, 4);
        assert!(l.check(&extent, 20, 1).is_ok());
        assert!(l.check(&extent, 19, 1).is_err());
        assert!(l.flipped(3).check(&extent, 20, 1).is_err());
        assert!(l.check(&extent, 20, 2).is_err()); // repeat beyond the column stride
        let huge = BufferLayout {
            row_stride: usize::MAX / 2,
            ..l
        };
        assert!(huge.check(&extent, 20, 1).is_err());
    }
}

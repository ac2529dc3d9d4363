//! Imager messages (`vrpn_Imager`, `vrpn_ImagerPose`): an image's size and channel
//! descriptions, frame brackets, discarded-frame notices, throttle requests, and regions of
//! pixels in 8-bit, 16-bit and 32-bit float.
//!
//! Everything is big-endian except the pixels of a region, which C++ copies from memory as
//! they are: **little-endian** (a C++ server on a big-endian host refuses to send them).

use byteorder::{BigEndian, ByteOrder};

use super::super::{need, Result, WireError};
use super::fixed_text::FixedText;

/// Size and channels of the image, server->client ([`DescriptionHeader`] then one
/// [`ChannelDescription`] per channel).
pub const DESCRIPTION: &str = "vrpn_Imager Description";
/// Start of a frame, server->client, 12 bytes ([`FrameExtent`]).
pub const BEGIN_FRAME: &str = "vrpn_Imager Begin_Frame";
/// End of a frame, server->client, 12 bytes ([`FrameExtent`]).
pub const END_FRAME: &str = "vrpn_Imager End_Frame";
/// Frames the server dropped, server->client, 2 bytes ([`DiscardedFrames`]).
pub const DISCARDED_FRAMES: &str = "vrpn_Imager Discarded_Frames";
/// Send at most N more frames, client->server, 4 bytes ([`ThrottleFrames`]).
pub const THROTTLE_FRAMES: &str = "vrpn_Imager Throttle_Frames";
/// A region of 8-bit pixels, server->client ([`Region`]).
pub const REGION_U8: &str = "vrpn_Imager Regionu8";
/// A region of 16-bit pixels, server->client ([`Region`]).
pub const REGION_U16: &str = "vrpn_Imager Regionu16";
/// A region of 12-bit pixels in 16-bit words (registered by C++, never sent by its server).
pub const REGION_U12IN16: &str = "vrpn_Imager Regionu12in16";
/// A region of 32-bit float pixels, server->client ([`Region`]).
pub const REGION_F32: &str = "vrpn_Imager Regionf32";
/// The imager's place in space, server->client, 96 bytes ([`PoseDescription`]).
pub const POSE_DESCRIPTION: &str = "vrpn_ImagerPose Description";

/// The imager type names in C++ registration order.
pub const TYPE_NAMES: &[&str] = &[
    DESCRIPTION,
    BEGIN_FRAME,
    END_FRAME,
    DISCARDED_FRAMES,
    THROTTLE_FRAMES,
    REGION_U8,
    REGION_U16,
    REGION_U12IN16,
    REGION_F32,
];

/// Most channels an imager describes (`vrpn_IMAGER_MAX_CHANNELS`).
pub const MAX_CHANNELS: usize = 100;
/// Bytes of a channel's name and units fields (`vrpn_CNAME`).
pub const NAME_LEN: usize = 100;
/// Bytes of a region message's header.
pub const REGION_HEADER_LEN: usize = 16;
/// Most 8-bit pixels in one region: what fits a C++ peer's 64000-byte TCP message with the
/// 24-byte message header and the region header (`vrpn_IMAGER_MAX_REGIONu8`).
pub const MAX_REGION_U8: usize = 64_000 - REGION_HEADER_LEN - 24;
/// Most 16-bit pixels in one region (`vrpn_IMAGER_MAX_REGIONu16`).
pub const MAX_REGION_U16: usize = MAX_REGION_U8 / 2;
/// Most float pixels in one region (`vrpn_IMAGER_MAX_REGIONf32`).
pub const MAX_REGION_F32: usize = MAX_REGION_U8 / 4;

/// The type of the pixels in a region (the region header's last field).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ValueType {
    /// `vrpn_IMAGER_VALTYPE_UINT8` (1).
    U8,
    /// `vrpn_IMAGER_VALTYPE_UINT16` (4).
    U16,
    /// `vrpn_IMAGER_VALTYPE_UINT12IN16` (5): 12-bit values in 16-bit words.
    U12In16,
    /// `vrpn_IMAGER_VALTYPE_FLOAT32` (6).
    F32,
}

impl ValueType {
    /// The wire code.
    pub fn code(self) -> u16 {
        match self {
            ValueType::U8 => 1,
            ValueType::U16 => 4,
            ValueType::U12In16 => 5,
            ValueType::F32 => 6,
        }
    }

    /// From the wire code; `None` for codes C++ does not define (0 is "unknown").
    pub fn from_code(code: u16) -> Option<ValueType> {
        match code {
            1 => Some(ValueType::U8),
            4 => Some(ValueType::U16),
            5 => Some(ValueType::U12In16),
            6 => Some(ValueType::F32),
            _ => None,
        }
    }

    /// Bytes per pixel.
    pub fn size(self) -> usize {
        match self {
            ValueType::U8 => 1,
            ValueType::U16 | ValueType::U12In16 => 2,
            ValueType::F32 => 4,
        }
    }

    /// Most pixels of this type in one region.
    pub fn max_region(self) -> usize {
        MAX_REGION_U8 / self.size()
    }

    /// The message type name a C++ server sends regions of this type as.
    pub fn message_type(self) -> &'static str {
        match self {
            ValueType::U8 => REGION_U8,
            ValueType::U16 => REGION_U16,
            ValueType::U12In16 => REGION_U12IN16,
            ValueType::F32 => REGION_F32,
        }
    }
}

fixed_payload! {
    /// First 16 bytes of `vrpn_Imager Description`: the image's size and how many
    /// [`ChannelDescription`]s follow. Note the order: depth, rows, columns.
    pub struct DescriptionHeader: at_least {
        /// Depth (stacks) of the image.
        pub depth: i32,
        /// Rows.
        pub rows: i32,
        /// Columns.
        pub cols: i32,
        /// Channel descriptions that follow (C++ sends 0..=100).
        pub channels: i32,
    }
}

/// One channel of a description, 220 bytes: f32 min, max, offset, scale, u32 compression
/// (0: none), then the 100-byte name and the 100-byte units, each NUL-terminated text in
/// its fixed field.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ChannelDescription {
    /// Smallest value a pixel can hold.
    pub min_val: f32,
    /// Largest value a pixel can hold.
    pub max_val: f32,
    /// Physical value = raw × scale + offset.
    pub offset: f32,
    /// Physical value = raw × scale + offset.
    pub scale: f32,
    /// Compression of the channel's regions: C++ defines only 0 (none).
    pub compression: u32,
    /// The channel's name.
    pub name: FixedText<NAME_LEN>,
    /// Its units.
    pub units: FixedText<NAME_LEN>,
}

impl ChannelDescription {
    /// Bytes on the wire.
    pub const LEN: usize = 20 + 2 * NAME_LEN;

    /// Decodes one channel from the start of `buf` (at least 220 bytes).
    pub fn decode(buf: &[u8]) -> Result<ChannelDescription> {
        need(buf, Self::LEN)?;
        Ok(ChannelDescription {
            min_val: BigEndian::read_f32(&buf[0..4]),
            max_val: BigEndian::read_f32(&buf[4..8]),
            offset: BigEndian::read_f32(&buf[8..12]),
            scale: BigEndian::read_f32(&buf[12..16]),
            compression: BigEndian::read_u32(&buf[16..20]),
            name: FixedText::decode(&buf[20..])?,
            units: FixedText::decode(&buf[20 + NAME_LEN..])?,
        })
    }

    /// Writes the 220 bytes at the start of `out`; returns 220.
    pub fn encode(&self, out: &mut [u8]) -> usize {
        BigEndian::write_f32(&mut out[0..4], self.min_val);
        BigEndian::write_f32(&mut out[4..8], self.max_val);
        BigEndian::write_f32(&mut out[8..12], self.offset);
        BigEndian::write_f32(&mut out[12..16], self.scale);
        BigEndian::write_u32(&mut out[16..20], self.compression);
        self.name.encode(&mut out[20..]);
        self.units.encode(&mut out[20 + NAME_LEN..]);
        Self::LEN
    }
}

/// Length of a description of `channels` channels.
pub fn description_len(channels: usize) -> usize {
    DescriptionHeader::LEN + channels * ChannelDescription::LEN
}

/// Decodes `vrpn_Imager Description` into `channels` (which holds [`MAX_CHANNELS`]), without
/// allocating. A channel count outside 0..=100 or a payload too short for the channels it
/// announces is an error (C++ would read past its array).
pub fn decode_description(
    buf: &[u8],
    channels: &mut [ChannelDescription; MAX_CHANNELS],
) -> Result<DescriptionHeader> {
    let h = DescriptionHeader::decode(buf)?;
    if !(0..=MAX_CHANNELS as i32).contains(&h.channels) {
        return Err(WireError::BadValue("imager channel count"));
    }
    let n = h.channels as usize;
    need(buf, description_len(n))?;
    for (i, c) in channels.iter_mut().take(n).enumerate() {
        *c = ChannelDescription::decode(
            &buf[DescriptionHeader::LEN + i * ChannelDescription::LEN..],
        )?;
    }
    Ok(h)
}

/// Encodes a description of `channels` (at most [`MAX_CHANNELS`]) into `out`, which must
/// hold [`description_len`] bytes; returns the length.
pub fn encode_description(
    depth: i32,
    rows: i32,
    cols: i32,
    channels: &[ChannelDescription],
    out: &mut [u8],
) -> usize {
    let channels = &channels[..channels.len().min(MAX_CHANNELS)];
    let h = DescriptionHeader {
        depth,
        rows,
        cols,
        channels: channels.len() as i32,
    };
    let mut off = h.encode(out);
    for c in channels {
        off += c.encode(&mut out[off..]);
    }
    off
}

fixed_payload! {
    /// `vrpn_Imager Begin_Frame` and `End_Frame`: the frame's extent, inclusive, in the wire
    /// order depth, rows, columns. At least 12 bytes.
    pub struct FrameExtent: at_least {
        /// First depth index.
        pub d_min: u16,
        /// Last depth index.
        pub d_max: u16,
        /// First row.
        pub r_min: u16,
        /// Last row.
        pub r_max: u16,
        /// First column.
        pub c_min: u16,
        /// Last column.
        pub c_max: u16,
    }
}

fixed_payload! {
    /// `vrpn_Imager Discarded_Frames`: frames dropped (0: "some, count unknown"). At least
    /// 2 bytes.
    pub struct DiscardedFrames: at_least {
        /// How many.
        pub count: u16,
    }
}

fixed_payload! {
    /// `vrpn_Imager Throttle_Frames`: send at most this many more frames (added to a limit
    /// already in force); negative: no limit. At least 4 bytes.
    pub struct ThrottleFrames: at_least {
        /// Frames, or negative for unlimited.
        pub frames: i32,
    }
}

fixed_payload! {
    /// The 16-byte header of a region message: channel, the inclusive extent in the order
    /// depth, rows, columns, and the pixel type code ([`ValueType`]).
    pub struct RegionHeader: at_least {
        /// Channel index in the description.
        pub channel: i16,
        /// First depth index.
        pub d_min: u16,
        /// Last depth index.
        pub d_max: u16,
        /// First row.
        pub r_min: u16,
        /// Last row.
        pub r_max: u16,
        /// First column.
        pub c_min: u16,
        /// Last column.
        pub c_max: u16,
        /// [`ValueType::code`].
        pub val_type: u16,
    }
}

impl RegionHeader {
    /// Pixels in the extent (columns × rows × depths); 0 if a range is reversed.
    pub fn count(&self) -> u64 {
        let span = |lo: u16, hi: u16| if hi >= lo { u64::from(hi - lo) + 1 } else { 0 };
        span(self.c_min, self.c_max) * span(self.r_min, self.r_max) * span(self.d_min, self.d_max)
    }
}

/// A decoded region message: its header and its pixels, borrowed from the payload.
///
/// Pixels are packed columns fastest, then rows, then depths, each value little-endian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region<'a> {
    /// Channel, extent and pixel type.
    pub header: RegionHeader,
    /// The pixel type.
    pub val_type: ValueType,
    /// Exactly `count × size` bytes of pixels.
    pub data: &'a [u8],
}

impl<'a> Region<'a> {
    /// Decodes a region payload. Errors: fewer than 16 bytes, an unknown pixel type, a
    /// reversed range, or fewer pixel bytes than the extent needs (C++ reads past the
    /// message then). Bytes beyond the extent's pixels are ignored.
    pub fn decode(buf: &'a [u8]) -> Result<Region<'a>> {
        let header = RegionHeader::decode(buf)?;
        let val_type = ValueType::from_code(header.val_type)
            .ok_or(WireError::BadValue("imager region value type"))?;
        if header.c_min > header.c_max || header.r_min > header.r_max || header.d_min > header.d_max
        {
            return Err(WireError::BadValue("imager region extent"));
        }
        let bytes = header.count() * val_type.size() as u64;
        let end = REGION_HEADER_LEN as u64 + bytes;
        if (buf.len() as u64) < end {
            return Err(WireError::Truncated {
                needed: end.min(usize::MAX as u64) as usize,
                available: buf.len(),
            });
        }
        Ok(Region {
            header,
            val_type,
            data: &buf[REGION_HEADER_LEN..end as usize],
        })
    }
}

fixed_payload! {
    /// `vrpn_ImagerPose Description`: where the image lies in space, in meters, as 12 f64 in
    /// the wire order origin, depth span, row span, column span (96 bytes). The origin is the
    /// outer corner of pixel (0,0,0); each span goes from the origin to one pixel past the
    /// image's end along that axis.
    pub struct PoseDescription: at_least {
        /// Corner of pixel (0,0,0).
        pub origin: [f64; 3],
        /// Total span of the image in depth.
        pub d_depth: [f64; 3],
        /// Total span in rows.
        pub d_row: [f64; 3],
        /// Total span in columns.
        pub d_col: [f64; 3],
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{hex, round_trip};
    use super::*;

    fn channel(name: &str, units: &str) -> ChannelDescription {
        ChannelDescription {
            min_val: 0.0,
            max_val: 255.0,
            offset: 0.5,
            scale: 2.0,
            compression: 0,
            name: FixedText::new(name).unwrap(),
            units: FixedText::new(units).unwrap(),
        }
    }

    #[test]
    fn fixed_layouts() {
        let b = round_trip!(
            FrameExtent,
            FrameExtent {
                d_min: 0,
                d_max: 1,
                r_min: 2,
                r_max: 3,
                c_min: 4,
                c_max: 0xff05
            }
        );
        assert_eq!(b, hex("0000 0001 0002 0003 0004 ff05"));
        let b = round_trip!(DiscardedFrames, DiscardedFrames { count: 7 });
        assert_eq!(b, hex("0007"));
        let b = round_trip!(ThrottleFrames, ThrottleFrames { frames: -1 });
        assert_eq!(b, hex("ffffffff"));
        let b = round_trip!(
            PoseDescription,
            PoseDescription {
                origin: [1.0, 0.0, 0.0],
                d_depth: [0.0; 3],
                d_row: [0.0, 2.0, 0.0],
                d_col: [0.0, 0.0, -2.0]
            }
        );
        assert_eq!(b.len(), 96);
        assert_eq!(&b[..8], &hex("3ff0000000000000")[..]);
        assert_eq!(&b[56..64], &hex("4000000000000000")[..]);
        assert_eq!(&b[88..96], &hex("c000000000000000")[..]);
    }

    #[test]
    fn description_layout() {
        let chans = [channel("Slope", "unsigned8bit"), channel("b", "")];
        let mut out = vec![0u8; description_len(2)];
        let n = encode_description(1, 256, 128, &chans, &mut out);
        assert_eq!(n, 16 + 440);
        assert_eq!(&out[..16], &hex("00000001 00000100 00000080 00000002")[..]);
        // min 0, max 255, offset 0.5, scale 2, compression 0, then "Slope\0..."
        assert_eq!(
            &out[16..36],
            &hex("00000000 437f0000 3f000000 40000000 00000000")[..]
        );
        assert_eq!(&out[36..42], b"Slope\0");
        assert_eq!(&out[136..149], b"unsigned8bit\0");
        let mut back = [ChannelDescription::default(); MAX_CHANNELS];
        let h = decode_description(&out, &mut back).unwrap();
        assert_eq!((h.depth, h.rows, h.cols, h.channels), (1, 256, 128, 2));
        assert_eq!(&back[..2], &chans);
        assert_eq!(back[0].name.as_str(), Some("Slope"));
        // Too short for the announced channels, too many channels, negative count.
        assert!(decode_description(&out[..n - 1], &mut back).is_err());
        let mut bad = out.clone();
        bad[15] = 101;
        assert!(decode_description(&bad, &mut back).is_err());
        bad[12] = 0xff;
        assert!(decode_description(&bad, &mut back).is_err());
        for cut in 0..n {
            assert!(decode_description(&out[..cut], &mut back).is_err());
        }
    }

    #[test]
    fn region_layout_and_checks() {
        // Channel 0, depth 0..0, rows 1..2, columns 3..5, u16: 6 pixels little-endian.
        let mut p = hex("0000 0000 0000 0001 0002 0003 0005 0004");
        for v in 0u16..6 {
            p.extend_from_slice(&(0x1000 + v).to_le_bytes());
        }
        let r = Region::decode(&p).unwrap();
        assert_eq!(r.val_type, ValueType::U16);
        assert_eq!(r.header.count(), 6);
        assert_eq!(r.data.len(), 12);
        assert_eq!(&r.data[..2], &[0x00, 0x10]);
        let mut again = [0u8; 16];
        r.header.encode(&mut again);
        assert_eq!(&again[..], &p[..16]);
        // Extra bytes are ignored; missing ones are an error.
        let mut longer = p.clone();
        longer.extend_from_slice(&[9, 9]);
        assert_eq!(Region::decode(&longer).unwrap().data.len(), 12);
        for cut in 0..p.len() {
            assert!(Region::decode(&p[..cut]).is_err());
        }
        // Unknown type, reversed range.
        let mut bad = p.clone();
        bad[15] = 2;
        assert!(Region::decode(&bad).is_err());
        let mut bad = p.clone();
        bad[7] = 9; // r_min 9 > r_max 2
        assert!(Region::decode(&bad).is_err());
        // A huge extent with a short payload is an error, not an overflow.
        let huge = hex("0000 0000 ffff 0000 ffff 0000 ffff 0006");
        assert!(Region::decode(&huge).is_err());
    }

    #[test]
    fn limits_match_cpp() {
        assert_eq!(MAX_REGION_U8, 63_960);
        assert_eq!(MAX_REGION_U16, 31_980);
        assert_eq!(MAX_REGION_F32, 15_990);
        assert_eq!(REGION_HEADER_LEN + MAX_REGION_U8, crate::wire::MAX_PAYLOAD);
        assert_eq!(ChannelDescription::LEN, 220);
        for t in [
            ValueType::U8,
            ValueType::U16,
            ValueType::U12In16,
            ValueType::F32,
        ] {
            assert_eq!(ValueType::from_code(t.code()), Some(t));
        }
        assert_eq!(ValueType::from_code(0), None);
    }
}

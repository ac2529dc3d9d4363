//! HID report descriptors (USB HID 1.11, section 6.2.2): the input fields a device reports,
//! where each sits in its report, and what it means. Pure: bytes in, a list of fields out.
//!
//! Items are a prefix byte (size in bits 0-1: 0, 1, 2 or 4 bytes; type in bits 2-3: main,
//! global, local; tag in bits 4-7) and their data, little-endian. Long items (`0xFE`) are
//! skipped. Global items (usage page, logical range, report size, count and id) persist and
//! can be pushed and popped; local items (usages, usage ranges) apply to the next main item
//! only. Every `Input` main item yields `count` fields of `size` bits, laid out one after the
//! other in the report of the current report id (which, when the device uses ids, is the
//! first byte of each report).
//!
//! A usage given in fewer than four bytes takes the usage page current when its main item is
//! read (as the Linux kernel does); a four-byte usage carries its own page.

/// Usage pages this crate looks at.
pub mod page {
    /// Generic Desktop (axes, hat switch, system controls).
    pub const GENERIC_DESKTOP: u16 = 0x01;
    /// Simulation Controls (throttle, rudder, brake…).
    pub const SIMULATION: u16 = 0x02;
    /// Buttons.
    pub const BUTTON: u16 = 0x09;
    /// Consumer controls.
    pub const CONSUMER: u16 = 0x0c;
}

/// Generic Desktop usages.
pub mod usage {
    /// X axis (`X` … `Wheel` are 0x30 … 0x38).
    pub const X: u16 = 0x30;
    /// The wheel, last of the axis usages.
    pub const WHEEL: u16 = 0x38;
    /// Hat switch.
    pub const HAT_SWITCH: u16 = 0x39;
}

/// One input field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    /// Report id (0 when the device has none).
    pub report_id: u8,
    /// Bit offset in the report, after the report id byte.
    pub bit_offset: u32,
    /// Bits.
    pub bit_size: u32,
    /// Usage page.
    pub page: u16,
    /// Usage.
    pub usage: u16,
    /// Logical minimum.
    pub logical_min: i32,
    /// Logical maximum.
    pub logical_max: i32,
    /// A relative value (motion since the last report), not a position.
    pub relative: bool,
    /// Values outside the logical range mean "no value" (a centred hat).
    pub null_state: bool,
}

impl Field {
    /// The field's value in `data` (the report after its id byte), sign-extended when the
    /// logical range is signed; `None` if the report is too short.
    pub fn extract(&self, data: &[u8]) -> Option<i32> {
        let (off, size) = (self.bit_offset as usize, self.bit_size as usize);
        if size == 0 || size > 32 || off + size > data.len() * 8 {
            return None;
        }
        let mut v: u64 = 0;
        for i in 0..size {
            let bit = off + i;
            if data[bit / 8] & (1 << (bit % 8)) != 0 {
                v |= 1 << i;
            }
        }
        Some(if self.logical_min < 0 && size < 32 {
            let shift = 64 - size;
            (((v << shift) as i64) >> shift) as i32
        } else {
            v as u32 as i32
        })
    }
}

/// A parsed descriptor: every variable, non-constant input field, in descriptor order.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Descriptor {
    /// The fields.
    pub fields: Vec<Field>,
    /// Whether the device numbers its reports (each report then starts with its id).
    pub uses_report_ids: bool,
    /// Bits each input report has (by report id), for checking report lengths.
    pub report_bits: Vec<(u8, u32)>,
    /// Application collections' usages (page, usage): a joystick, a game pad, a
    /// multi-axis controller…
    pub applications: Vec<(u16, u16)>,
}

/// Why a descriptor could not be read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DescriptorError {
    /// An item runs past the end.
    Truncated {
        /// Where the item starts.
        at: usize,
    },
    /// `Pop` with nothing pushed, or more than 16 pushes.
    Stack {
        /// Where.
        at: usize,
    },
}

impl std::fmt::Display for DescriptorError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DescriptorError::Truncated { at } => {
                write!(f, "report descriptor item at byte {at} runs past the end")
            }
            DescriptorError::Stack { at } => {
                write!(f, "report descriptor push/pop out of balance at byte {at}")
            }
        }
    }
}

impl std::error::Error for DescriptorError {}

#[derive(Clone, Copy, Debug, Default)]
struct Globals {
    page: u16,
    logical_min: i32,
    logical_max: i32,
    report_size: u32,
    report_count: u32,
    report_id: u8,
}

#[derive(Clone, Debug, Default)]
struct Locals {
    /// (page if given with the usage, usage).
    usages: Vec<(Option<u16>, u16)>,
    min: Option<(Option<u16>, u16)>,
    max: Option<(Option<u16>, u16)>,
}

fn unsigned(d: &[u8]) -> u32 {
    d.iter()
        .rev()
        .fold(0u32, |acc, b| (acc << 8) | u32::from(*b))
}

fn signed(d: &[u8]) -> i32 {
    match d.len() {
        0 => 0,
        1 => i32::from(d[0] as i8),
        2 => i32::from(i16::from_le_bytes([d[0], d[1]])),
        _ => unsigned(d) as i32,
    }
}

fn split_usage(d: &[u8]) -> (Option<u16>, u16) {
    let v = unsigned(d);
    if d.len() == 4 {
        (Some((v >> 16) as u16), v as u16)
    } else {
        (None, v as u16)
    }
}

/// Parses a report descriptor.
pub fn parse(bytes: &[u8]) -> Result<Descriptor, DescriptorError> {
    let mut d = Descriptor::default();
    let mut g = Globals::default();
    let mut stack: Vec<Globals> = Vec::new();
    let mut l = Locals::default();
    let mut bits_by_id: Vec<(u8, u32)> = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let at = i;
        let prefix = bytes[i];
        if prefix == 0xfe {
            // Long item: size, tag, data.
            let size = usize::from(*bytes.get(i + 1).ok_or(DescriptorError::Truncated { at })?);
            i += 3 + size;
            if i > bytes.len() {
                return Err(DescriptorError::Truncated { at });
            }
            continue;
        }
        let size = [0, 1, 2, 4][usize::from(prefix & 3)];
        let data = bytes
            .get(i + 1..i + 1 + size)
            .ok_or(DescriptorError::Truncated { at })?;
        i += 1 + size;
        let (kind, tag) = ((prefix >> 2) & 3, prefix >> 4);
        match (kind, tag) {
            // Main: Input.
            (0, 0x8) => {
                let flags = unsigned(data);
                let constant = flags & 1 != 0;
                let variable = flags & 2 != 0;
                let slot = match bits_by_id.iter().position(|(id, _)| *id == g.report_id) {
                    Some(s) => s,
                    None => {
                        bits_by_id.push((g.report_id, 0));
                        bits_by_id.len() - 1
                    }
                };
                let start = bits_by_id[slot].1;
                if !constant && variable {
                    for k in 0..g.report_count {
                        let (p, u) = if let (Some(lo), Some(hi)) = (l.min, l.max) {
                            let u = lo.1.saturating_add(k.min(u32::from(u16::MAX)) as u16);
                            (lo.0, u.min(hi.1))
                        } else if let Some(last) = l.usages.last() {
                            *l.usages.get(k as usize).unwrap_or(last)
                        } else {
                            (None, 0)
                        };
                        d.fields.push(Field {
                            report_id: g.report_id,
                            bit_offset: start + k * g.report_size,
                            bit_size: g.report_size,
                            page: p.unwrap_or(g.page),
                            usage: u,
                            logical_min: g.logical_min,
                            logical_max: g.logical_max,
                            relative: flags & 4 != 0,
                            null_state: flags & 0x40 != 0,
                        });
                    }
                }
                bits_by_id[slot].1 = start + g.report_count * g.report_size;
                l = Locals::default();
            }
            // Main: Collection.
            (0, 0xa) => {
                if unsigned(data) == 1 {
                    let (p, u) = l.usages.first().copied().unwrap_or((None, 0));
                    d.applications.push((p.unwrap_or(g.page), u));
                }
                l = Locals::default();
            }
            // Main: Output, Feature, End Collection.
            (0, _) => l = Locals::default(),
            // Global.
            (1, 0x0) => g.page = unsigned(data) as u16,
            (1, 0x1) => g.logical_min = signed(data),
            (1, 0x2) => {
                // A maximum written in fewer bytes than needed to keep its sign positive
                // (`26 ff 00` is 255) is unsigned when the minimum is not negative.
                g.logical_max = if g.logical_min >= 0 {
                    unsigned(data) as i32
                } else {
                    signed(data)
                }
            }
            (1, 0x7) => g.report_size = unsigned(data),
            (1, 0x8) => {
                g.report_id = unsigned(data) as u8;
                d.uses_report_ids = true;
            }
            (1, 0x9) => g.report_count = unsigned(data),
            (1, 0xa) => {
                if stack.len() >= 16 {
                    return Err(DescriptorError::Stack { at });
                }
                stack.push(g);
            }
            (1, 0xb) => g = stack.pop().ok_or(DescriptorError::Stack { at })?,
            (1, _) => {}
            // Local.
            (2, 0x0) => l.usages.push(split_usage(data)),
            (2, 0x1) => l.min = Some(split_usage(data)),
            (2, 0x2) => l.max = Some(split_usage(data)),
            _ => {}
        }
    }
    d.report_bits = bits_by_id;
    Ok(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mouse_descriptor() {
        // Buttons 1-3, 5 bits padding, X and Y relative −127…127.
        let rd = [
            0x05, 0x01, 0x09, 0x02, 0xa1, 0x01, 0x09, 0x01, 0xa1, 0x00, 0x05, 0x09, 0x19, 0x01,
            0x29, 0x03, 0x15, 0x00, 0x25, 0x01, 0x95, 0x03, 0x75, 0x01, 0x81, 0x02, 0x95, 0x01,
            0x75, 0x05, 0x81, 0x03, 0x05, 0x01, 0x09, 0x30, 0x09, 0x31, 0x15, 0x81, 0x25, 0x7f,
            0x75, 0x08, 0x95, 0x02, 0x81, 0x06, 0xc0, 0xc0,
        ];
        let d = parse(&rd).unwrap();
        assert!(!d.uses_report_ids);
        assert_eq!(d.applications, vec![(1, 2)]);
        assert_eq!(d.report_bits, vec![(0, 24)]);
        assert_eq!(d.fields.len(), 5);
        assert_eq!((d.fields[2].page, d.fields[2].usage), (page::BUTTON, 3));
        let x = d.fields[3];
        assert_eq!((x.page, x.usage, x.bit_offset, x.bit_size), (1, 0x30, 8, 8));
        assert!(x.relative);
        assert_eq!((x.logical_min, x.logical_max), (-127, 127));
        let report = [0b101, 0xfe, 0x05];
        assert_eq!(d.fields[0].extract(&report), Some(1));
        assert_eq!(d.fields[1].extract(&report), Some(0));
        assert_eq!(x.extract(&report), Some(-2));
        assert_eq!(d.fields[4].extract(&report), Some(5));
        assert_eq!(d.fields[4].extract(&report[..2]), None);
    }

    #[test]
    fn push_pop_long_items_and_errors() {
        let rd = [
            0x05, 0x01, 0xa4, 0x05, 0x09, 0xb4, 0x09, 0x30, 0x15, 0x00, 0x26, 0xff, 0x00, 0x75,
            0x08, 0x95, 0x01, 0xfe, 0x02, 0x10, 0xaa, 0xbb, 0x81, 0x02,
        ];
        let d = parse(&rd).unwrap();
        assert_eq!(d.fields[0].page, 1, "the pushed page came back");
        assert_eq!(d.fields[0].logical_max, 255);
        assert_eq!(
            parse(&[0x26, 0xff]),
            Err(DescriptorError::Truncated { at: 0 })
        );
        assert_eq!(parse(&[0xb4]), Err(DescriptorError::Stack { at: 0 }));
        assert_eq!(
            parse(&[0xfe, 0x05, 0x00]),
            Err(DescriptorError::Truncated { at: 0 })
        );
    }
}

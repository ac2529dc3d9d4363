//! The board's two-byte commands, pure: how a register and a value are put on the line, and
//! how an answer is recognised.
//!
//! Every command starts with an **address byte** (bit 7 set) and may carry a **value byte**
//! (bit 7 clear):
//!
//! ```text
//! address byte = (register + 64) << 1 | bit 7 of the value     (registers 0..=63)
//! value byte   = the value's low 7 bits
//! ```
//!
//! A **read** is the lone address byte (its low bit 0); the board answers with the address
//! byte (its low bit now bit 7 of the register's value) and the value byte. A **write** is
//! both bytes; the board echoes them. An answer is found by skipping every byte until the
//! awaited address byte (either low bit for a read, the exact byte for a write): whatever
//! else the board sends is not an answer.

/// The highest register the board has.
pub const MAX_REGISTER: usize = 63;

/// A channel's mode, from its configuration line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Read and written (`RW`).
    ReadWrite,
    /// Read only (`RO`).
    ReadOnly,
    /// Written only (`WO`).
    WriteOnly,
    /// Not used (`NA`, and every channel without a line).
    Unused,
}

impl Mode {
    /// The mode a configuration word names (C++ reads at most two characters of it).
    pub fn from_word(word: &str) -> Option<Mode> {
        match word.get(..2.min(word.len()))? {
            "RW" => Some(Mode::ReadWrite),
            "RO" => Some(Mode::ReadOnly),
            "WO" => Some(Mode::WriteOnly),
            "NA" => Some(Mode::Unused),
            _ => None,
        }
    }

    /// Whether the channel's register is read.
    pub fn readable(self) -> bool {
        matches!(self, Mode::ReadWrite | Mode::ReadOnly)
    }

    /// Whether a client may write the channel.
    pub fn writable(self) -> bool {
        matches!(self, Mode::ReadWrite | Mode::WriteOnly)
    }
}

/// The values C++ reports in a channel instead of a register's value.
pub mod reported {
    /// The channel is not in use (not readable, or its first read failed, or not written yet).
    pub const NOT_VALID: f64 = -1.0;
    /// A read was not answered.
    pub const READ_FAILED: f64 = -21.0;
    /// A write was not confirmed.
    pub const WRITE_FAILED: f64 = -22.0;
    /// A client asked for a value outside 0..=255.
    pub const OUT_OF_RANGE: f64 = -23.0;
    /// A client asked to write a channel that is not `RW` or `WO`.
    pub const NOT_WRITABLE: f64 = -24.0;
}

/// The address byte of `register` (low bit 0), or `None` past [`MAX_REGISTER`].
pub fn address(register: usize) -> Option<u8> {
    (register <= MAX_REGISTER).then(|| ((register as u8) + 64) << 1)
}

/// The register an address byte names, or `None` for a byte without bit 7.
pub fn register_of(byte: u8) -> Option<usize> {
    (byte & 0x80 != 0).then(|| usize::from(byte >> 1) - 64)
}

/// The two bytes that write `value` to `register`, or `None` past [`MAX_REGISTER`].
pub fn write_command(register: usize, value: u8) -> Option<[u8; 2]> {
    Some([address(register)? | value >> 7, value & 0x7F])
}

/// A register's value from the answer's two bytes (C++ accepts a value byte up to 128).
pub fn value_of(address: u8, value: u8) -> Option<u16> {
    (value <= 128).then(|| u16::from(value) + if address & 1 != 0 { 128 } else { 0 })
}

/// What an exchange waits for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Awaited {
    /// The answer to a read of the register at this address byte.
    Read(u8),
    /// The echo of a write.
    Echo([u8; 2]),
}

/// One step of [`Matcher::push`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// Not the answer (yet).
    Skip,
    /// The answer's address byte: its value byte comes next.
    Started,
    /// A read's answer: the register's value.
    Value(u16),
    /// A write's echo.
    Confirmed,
    /// The byte after the address byte is not a value (a read) or not the value written (a
    /// write): the exchange failed, as in C++.
    Failed,
}

/// Finds an exchange's answer among the bytes the board sends.
#[derive(Clone, Copy, Debug)]
pub struct Matcher {
    awaited: Awaited,
    address: Option<u8>,
}

impl Matcher {
    /// Waits for `awaited`.
    pub fn new(awaited: Awaited) -> Matcher {
        Matcher {
            awaited,
            address: None,
        }
    }

    /// What was awaited.
    pub fn awaited(&self) -> Awaited {
        self.awaited
    }

    /// The next byte from the board.
    pub fn push(&mut self, b: u8) -> Step {
        match (self.awaited, self.address) {
            (Awaited::Read(a), None) if b | 1 == a | 1 => {
                self.address = Some(b);
                Step::Started
            }
            (Awaited::Echo([a, _]), None) if b == a => {
                self.address = Some(b);
                Step::Started
            }
            (_, None) => Step::Skip,
            (Awaited::Read(_), Some(a)) => value_of(a, b).map_or(Step::Failed, Step::Value),
            (Awaited::Echo([_, v]), Some(_)) => {
                if b == v {
                    Step::Confirmed
                } else {
                    Step::Failed
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_are_cpps() {
        assert_eq!(address(0), Some(0x80));
        assert_eq!(address(63), Some(0xFE));
        assert_eq!(address(64), None);
        assert_eq!(register_of(0x85), Some(2));
        assert_eq!(register_of(0x05), None);
        assert_eq!(write_command(2, 200), Some([0x85, 200 - 128]));
        assert_eq!(write_command(2, 100), Some([0x84, 100]));
        assert_eq!(value_of(0x85, 72), Some(200));
        assert_eq!(value_of(0x84, 128), Some(128));
        assert_eq!(value_of(0x84, 129), None);
        assert_eq!(Mode::from_word("RWX"), Some(Mode::ReadWrite));
        assert_eq!(Mode::from_word("R"), None);
        assert_eq!(Mode::from_word("rw"), None);
    }

    #[test]
    fn answers_are_found_among_other_bytes() {
        let mut m = Matcher::new(Awaited::Read(0x84));
        let steps: Vec<Step> = [0x00, 0x86, 0x85, 72].iter().map(|&b| m.push(b)).collect();
        // 0x86 is register 3's address: skipped; its value byte would be too.
        assert_eq!(
            steps,
            [Step::Skip, Step::Skip, Step::Started, Step::Value(200)]
        );
        let mut m = Matcher::new(Awaited::Read(0x84));
        assert_eq!(
            [0x84, 0x90].map(|b| m.push(b)),
            [Step::Started, Step::Failed]
        );
        let mut m = Matcher::new(Awaited::Echo([0x85, 72]));
        assert_eq!(
            [0x84, 0x85, 72].map(|b| m.push(b)),
            [Step::Skip, Step::Started, Step::Confirmed]
        );
        let mut m = Matcher::new(Awaited::Echo([0x85, 72]));
        assert_eq!([0x85, 71].map(|b| m.push(b)), [Step::Started, Step::Failed]);
    }
}

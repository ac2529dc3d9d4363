//! The Pinch Glove's messages and how they are found in the byte stream (pure code).
//!
//! Every message starts with a byte from 0x80 to 0x8E and ends with 0x8F; the bytes between
//! have bit 7 clear. A touch message (0x80) holds pairs of bytes, one pair per group of
//! fingers touching each other: the left hand's fingers, then the right hand's, each a
//! five-bit mask (0x10 thumb … 0x01 little finger). `0x80 0x8F` says nothing touches. 0x81
//! starts a touch message with time stamps (the glove was left in that mode); 0x82 a text,
//! such as the answer to a command (`0x82 '0' 0x8F` answers `T0`, "time stamps off").

use crate::time::Now;

/// Start of a touch message.
pub const TOUCH: u8 = 0x80;
/// Start of a touch message with time stamps.
pub const TOUCH_TIMED: u8 = 0x81;
/// Start of a text message (command answers).
pub const TEXT: u8 = 0x82;
/// End of every message.
pub const END: u8 = 0x8F;
/// Buttons: 0-4 the right hand's fingers, 5-9 the left hand's, thumb first.
pub const BUTTONS: usize = 10;

/// The buttons a touch message's pairs press: finger *j* (thumb 0) of the right hand is
/// button *j*, of the left hand button 5 + *j*.
pub fn pressed(left: u8, right: u8) -> [bool; BUTTONS] {
    let mut b = [false; BUTTONS];
    for j in 0..5 {
        let mask = 0x10 >> j;
        b[j] = right & mask != 0;
        b[j + 5] = left & mask != 0;
    }
    b
}

/// What the framer found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Found {
    /// A complete touch message: the OR of its left-hand and right-hand bytes.
    Touch {
        /// Left-hand fingers touching anything.
        left: u8,
        /// Right-hand fingers touching anything.
        right: u8,
        /// When the read holding its start byte arrived.
        first_byte: Now,
        /// Bytes skipped since the previous message.
        skipped: u32,
    },
    /// A touch message with time stamps began (the glove must be told `T0`).
    Timed,
    /// A text message ended; `zero_answer` when it was `'0'` (the answer to `T0`).
    Text {
        /// It was the answer to a `T0`.
        zero_answer: bool,
    },
    /// A message with an unknown start byte was skipped.
    Unknown(u8),
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum State {
    Between,
    Touch {
        first: Now,
        left: u8,
        right: u8,
        half: Option<u8>,
        /// Bytes so far, the start byte included.
        len: usize,
    },
    /// Inside a message that is skipped to its end: its start byte, its length so far, its
    /// last data byte.
    Skip {
        start: u8,
        len: usize,
        last: u8,
    },
}

/// Finds messages byte by byte. A touch message with a byte out of place (a data byte above
/// 0x1F, an odd number of data bytes, another start byte) is dropped and counted as skipped;
/// bytes between messages are skipped. A new start byte always starts a new message, so a
/// damaged message costs nothing after it.
#[derive(Clone, Debug)]
pub struct Framer {
    state: State,
    skipped: u32,
    total_skipped: u64,
}

impl Default for Framer {
    fn default() -> Framer {
        Framer::new()
    }
}

impl Framer {
    /// An empty framer.
    pub fn new() -> Framer {
        Framer {
            state: State::Between,
            skipped: 0,
            total_skipped: 0,
        }
    }

    /// Forgets a partial message.
    pub fn clear(&mut self) {
        self.state = State::Between;
        self.skipped = 0;
    }

    /// Bytes skipped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    fn skip(&mut self, n: usize) {
        self.skipped = self.skipped.saturating_add(n as u32);
        self.total_skipped += n as u64;
    }

    /// Bytes of the message being read, dropped.
    fn drop_current(&mut self) {
        let n = match self.state {
            State::Between => 0,
            State::Touch { len, .. } => len,
            State::Skip { .. } => 0,
        };
        self.skip(n);
        self.state = State::Between;
    }

    fn start(&mut self, b: u8, arrived: Now) -> Option<Found> {
        self.state = match b {
            TOUCH => State::Touch {
                first: arrived,
                left: 0,
                right: 0,
                half: None,
                len: 1,
            },
            _ => State::Skip {
                start: b,
                len: 1,
                last: 0,
            },
        };
        if b == TOUCH_TIMED {
            return Some(Found::Timed);
        }
        if b != TOUCH && b != TEXT {
            return Some(Found::Unknown(b));
        }
        None
    }

    /// Takes one byte that arrived at `arrived`.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Found> {
        match self.state {
            State::Between => {
                if (TOUCH..END).contains(&b) {
                    self.start(b, arrived)
                } else {
                    self.skip(1);
                    None
                }
            }
            State::Touch {
                first,
                left,
                right,
                half,
                len,
            } => match (b, half) {
                (END, None) => {
                    self.state = State::Between;
                    let skipped = std::mem::take(&mut self.skipped);
                    Some(Found::Touch {
                        left,
                        right,
                        first_byte: first,
                        skipped,
                    })
                }
                (0..=0x1F, None) => {
                    self.state = State::Touch {
                        first,
                        left,
                        right,
                        half: Some(b),
                        len: len + 1,
                    };
                    None
                }
                (0..=0x1F, Some(l)) => {
                    self.state = State::Touch {
                        first,
                        left: left | l,
                        right: right | b,
                        half: None,
                        len: len + 1,
                    };
                    None
                }
                _ => {
                    // Damaged: the pairs read so far go with it.
                    self.drop_current();
                    if (TOUCH..END).contains(&b) {
                        self.start(b, arrived)
                    } else {
                        self.skip(1);
                        None
                    }
                }
            },
            State::Skip { start, len, last } => {
                if b == END {
                    self.state = State::Between;
                    return (start == TEXT).then_some(Found::Text {
                        zero_answer: len == 2 && last == b'0',
                    });
                }
                if (TOUCH..END).contains(&b) {
                    // A message that never ended: the next one starts.
                    return self.start(b, arrived);
                }
                self.state = State::Skip {
                    start,
                    len: len + 1,
                    last: b,
                };
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::TimeVal;
    use std::time::{Duration, Instant};

    fn at(ms: u64, base: Instant) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(100, 0).plus(Duration::from_millis(ms)),
        }
    }

    fn feed(f: &mut Framer, bytes: &[u8], t: Now) -> Vec<Found> {
        bytes.iter().filter_map(|&b| f.push(b, t)).collect()
    }

    #[test]
    fn fingers_map_to_buttons_thumb_first() {
        let b = pressed(0x10, 0x01);
        assert_eq!(
            b,
            [false, false, false, false, true, true, false, false, false, false]
        );
        assert_eq!(pressed(0x1F, 0x1F), [true; BUTTONS]);
    }

    #[test]
    fn touches_texts_and_damage() {
        let base = Instant::now();
        let mut f = Framer::new();
        // Garbage, then two pairs (thumb-index of both hands; left ring to right little).
        let got = feed(
            &mut f,
            &[0x33, 0x8F, TOUCH, 0x18, 0x18, 0x02, 0x01, END],
            at(1, base),
        );
        assert_eq!(
            got,
            vec![Found::Touch {
                left: 0x1A,
                right: 0x19,
                first_byte: at(1, base),
                skipped: 2
            }]
        );
        assert_eq!(
            feed(&mut f, &[TEXT, b'0', END], at(2, base)),
            vec![Found::Text { zero_answer: true }]
        );
        assert_eq!(
            feed(&mut f, &[TEXT, b'1', b'0', END], at(3, base)),
            vec![Found::Text { zero_answer: false }]
        );
        assert_eq!(
            feed(
                &mut f,
                &[TOUCH_TIMED, 0x10, 0x10, 0x05, 0x06, END],
                at(4, base)
            ),
            vec![Found::Timed]
        );
        assert_eq!(
            feed(&mut f, &[0x8A, END], at(5, base)),
            vec![Found::Unknown(0x8A)]
        );
        // An odd pair count, a byte out of range, a lost end byte: each costs its message.
        let before = f.total_skipped();
        assert_eq!(feed(&mut f, &[TOUCH, 0x10, END], at(6, base)), vec![]);
        assert_eq!(feed(&mut f, &[TOUCH, 0x10, 0x40], at(7, base)), vec![]);
        let got = feed(&mut f, &[TOUCH, 0x10, 0x01, TOUCH, END], at(8, base));
        assert_eq!(f.total_skipped() - before, 3 + 3 + 3);
        assert_eq!(
            got,
            vec![Found::Touch {
                left: 0,
                right: 0,
                first_byte: at(8, base),
                skipped: 9
            }]
        );
    }
}

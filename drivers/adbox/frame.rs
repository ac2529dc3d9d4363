//! The AD-Box's answer to `U`, pure: its layout (told by its length), its decoding, and C++'s
//! filter against a converter flickering between two neighbouring values.
//!
//! An answer is `D` digital bytes (bit `b` of byte `i` is button `8i + b`, **clear while
//! pressed**) and then two bytes per analog channel, high byte first, a 10-bit value
//! (0..=1023, reported as value / 1023):
//!
//! | Answer length | Digital bytes | Buttons | Analog channels |
//! |---------------|---------------|---------|-----------------|
//! | 14            | 2             | 16      | 6               |
//! | 18            | 2             | 16      | 8               |
//! | 19            | 3             | 24      | 8               |

/// The request for one answer.
pub const REQUEST: u8 = b'U';
/// The longest answer.
pub const MAX_ANSWER: usize = 19;
/// Most analog channels.
pub const MAX_CHANNELS: usize = 8;
/// Most buttons.
pub const MAX_BUTTONS: usize = 24;
/// Frames of history C++'s filter looks back over.
pub const HISTORY: usize = 30;

/// The layout of a box's answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Bytes in an answer.
    pub len: usize,
    /// Digital bytes at its start.
    pub digital: usize,
}

impl Layout {
    /// The layout of an answer `len` bytes long; `None` for a length no box answers with.
    pub fn of_len(len: usize) -> Option<Layout> {
        match len {
            14 | 18 => Some(Layout { len, digital: 2 }),
            19 => Some(Layout { len, digital: 3 }),
            _ => None,
        }
    }

    /// Buttons.
    pub fn buttons(&self) -> usize {
        self.digital * 8
    }

    /// Analog channels.
    pub fn channels(&self) -> usize {
        (self.len - self.digital) / 2
    }

    /// Whether `answer` can be one: every analog value has 10 bits (a high byte above 3 means
    /// the answer is out of step with the requests).
    pub fn plausible(&self, answer: &[u8]) -> bool {
        answer.len() == self.len && answer[self.digital..].chunks(2).all(|p| p[0] <= 3)
    }

    /// Whether button `i` is pressed in `answer`.
    pub fn pressed(&self, answer: &[u8], i: usize) -> bool {
        answer[i / 8] & (1 << (i % 8)) == 0
    }

    /// Analog channel `c`'s raw value in `answer`.
    pub fn raw(&self, answer: &[u8], c: usize) -> u16 {
        let at = self.digital + 2 * c;
        u16::from(answer[at]) << 8 | u16::from(answer[at + 1])
    }
}

/// C++'s flicker filter: each channel's last [`HISTORY`] raw values. A value one step from
/// the last different value, which itself came after this value, is a converter flickering
/// between two neighbours: the midpoint is reported.
#[derive(Clone, Debug)]
pub struct Filter {
    history: [[u16; HISTORY]; MAX_CHANNELS],
    pos: usize,
}

impl Default for Filter {
    fn default() -> Filter {
        Filter::new()
    }
}

impl Filter {
    /// A filter with a history of zeros (as C++ starts).
    pub fn new() -> Filter {
        Filter {
            history: [[0; HISTORY]; MAX_CHANNELS],
            pos: 0,
        }
    }

    /// Channel `c`'s value for this frame's raw `v` (0..=1 for 0..=1023).
    pub fn value(&mut self, c: usize, v: u16) -> f64 {
        let h = &mut self.history[c];
        let now = self.pos;
        h[now] = v;
        let back = |p: usize| (p + HISTORY - 1) % HISTORY;
        // The last value before this one that differs from it...
        let mut p = back(now);
        while p != now && h[p] == v {
            p = back(p);
        }
        if p != now && h[p].abs_diff(v) == 1 {
            let last = h[p];
            // ...and, before that one, the last value that differs from it.
            while p != now && h[p] == last {
                p = back(p);
            }
            if p != now && h[p] == v {
                return f64::from(v + last) / 2046.0;
            }
        }
        f64::from(v) / 1023.0
    }

    /// Ends a frame (every channel's value taken).
    pub fn next_frame(&mut self) {
        self.pos = (self.pos + 1) % HISTORY;
    }
}

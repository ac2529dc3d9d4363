//! The latest-state store behind the remotes' polling API.
//!
//! A frame loop reads state once per frame and needs to know whether it changed since the
//! last frame. Each index (sensor, button, dial) keeps its newest value, how many values
//! arrived (`seq`, which the report carries too) and how many of them the application had
//! when it last *took* the value: `take` returns a value only once per arrival, `get` always.

use std::cell::RefCell;

use crate::time::TimeVal;

/// Highest index + 1 a remote keeps latest state for (sensors, buttons, dials). Reports with
/// a larger index still reach callbacks; the bound keeps a peer's index from sizing memory.
pub const MAX_LATEST_INDEX: usize = 4096;

/// When a report arrived and which one it is: the fields every report of a remote carries
/// beside the sender's time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Stamp {
    pub sender_time: TimeVal,
    pub arrival: TimeVal,
}

impl Stamp {
    #[inline]
    pub(crate) fn of(m: &crate::dispatch::Message<'_>) -> Stamp {
        Stamp {
            sender_time: m.sender_time,
            arrival: m.arrived(),
        }
    }
}

#[derive(Clone, Copy)]
struct Slot<T> {
    value: Option<T>,
    seq: u64,
    taken: u64,
}

/// Newest value per index, with arrival counts.
pub(crate) struct Latest<T> {
    slots: RefCell<Vec<Slot<T>>>,
}

impl<T: Copy> Latest<T> {
    /// A store with room for `n` indices before it grows.
    pub(crate) fn with_capacity(n: usize) -> Latest<T> {
        Latest {
            slots: RefCell::new(Vec::with_capacity(n)),
        }
    }

    /// Stores the value `make(seq)` builds for index `i`, where `seq` counts the values that
    /// arrived for `i` (1 for the first). Returns the value; an index at or beyond
    /// [`MAX_LATEST_INDEX`] is not stored and gets `seq` 0.
    ///
    /// `make` runs twice, once into the slot and once for the returned copy: copying a report
    /// that was just written field by field reads it back in wider loads the CPU cannot
    /// forward from its store buffer, and that stall cost more than the whole store (about
    /// 3 ns of a 26 ns in-process report; see docs/PERFORMANCE.md).
    #[inline]
    pub(crate) fn store(&self, i: usize, make: impl Fn(u64) -> T) -> T {
        if i >= MAX_LATEST_INDEX {
            return make(0);
        }
        let mut s = self.slots.borrow_mut();
        if s.len() <= i {
            grow(&mut s, i + 1);
        }
        let slot = &mut s[i];
        slot.seq += 1;
        let seq = slot.seq;
        slot.value = Some(make(seq));
        make(seq)
    }

    /// The newest value of `i`, if any arrived.
    pub(crate) fn get(&self, i: usize) -> Option<T> {
        self.slots.borrow().get(i).and_then(|s| s.value)
    }

    /// The newest value of `i` if it arrived after the last `take` of `i`.
    pub(crate) fn take(&self, i: usize) -> Option<T> {
        let mut s = self.slots.borrow_mut();
        let slot = s.get_mut(i)?;
        if slot.seq == slot.taken {
            return None;
        }
        slot.taken = slot.seq;
        slot.value
    }

    /// Changes the value stored for `i` in place, as no new arrival.
    pub(crate) fn store_quiet(&self, i: usize, f: impl FnOnce(&mut T)) {
        if let Some(v) = self
            .slots
            .borrow_mut()
            .get_mut(i)
            .and_then(|s| s.value.as_mut())
        {
            f(v);
        }
    }

    /// Values that arrived for `i` so far.
    pub(crate) fn seq(&self, i: usize) -> u64 {
        self.slots.borrow().get(i).map_or(0, |s| s.seq)
    }

    /// Highest index seen + 1.
    pub(crate) fn len(&self) -> usize {
        self.slots.borrow().len()
    }
}

/// Grows a store to `len` indices: once per new index, never per report.
#[cold]
#[inline(never)]
fn grow<T: Copy>(slots: &mut Vec<Slot<T>>, len: usize) {
    slots.resize(
        len,
        Slot {
            value: None,
            seq: 0,
            taken: 0,
        },
    );
}

/// An index given by the caller: `usize`, or any other integer type (C++ ports pass `int`).
/// A negative or too large value is refused with a clear error by the method taking it.
pub trait Index: Copy {
    /// The index as `usize`, `None` when it is negative.
    fn to_index(self) -> Option<usize>;
}

macro_rules! index_from {
    ($($t:ty),*) => {$(
        impl Index for $t {
            fn to_index(self) -> Option<usize> {
                usize::try_from(self).ok()
            }
        }
    )*};
}
index_from!(usize, u8, u16, u32, u64, i8, i16, i32, i64, isize);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn take_returns_each_arrival_once_and_get_always() {
        let l: Latest<(u64, i32)> = Latest::with_capacity(2);
        assert_eq!(l.take(0), None);
        assert_eq!(l.store(1, |s| (s, 10)), (1, 10));
        assert_eq!(l.len(), 2);
        assert_eq!(l.get(0), None);
        assert_eq!(l.take(1), Some((1, 10)));
        assert_eq!(l.take(1), None);
        assert_eq!(l.get(1), Some((1, 10)));
        l.store(1, |s| (s, 11));
        l.store(1, |s| (s, 12));
        assert_eq!(l.seq(1), 3);
        assert_eq!(l.take(1), Some((3, 12)));
        assert_eq!(l.take(1), None);
        assert_eq!(l.store(MAX_LATEST_INDEX, |s| (s, 0)), (0, 0));
        assert_eq!(l.len(), 2);
    }

    #[test]
    fn indices_of_any_integer_type() {
        assert_eq!(3i32.to_index(), Some(3));
        assert_eq!((-1i32).to_index(), None);
        assert_eq!(7usize.to_index(), Some(7));
    }
}

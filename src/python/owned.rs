//! Objects that belong to the thread that made them.
//!
//! A connection and its devices are single-threaded (`Rc`, `RefCell`); Python lets any thread
//! call a method. pyo3's `unsendable` classes refuse other threads with a Rust panic (a
//! `BaseException` Python code rarely catches); [`Owned`] refuses them with
//! `vrpn.WrongThreadError` instead, as the C ABI returns `WRONG_THREAD`, and never touches the
//! value from another thread: not to read it, not to drop it (a value the garbage collector
//! frees on another thread is leaked rather than dropped there, since its `Rc`s are shared
//! with the owning thread).

// The one place of the Python module that needs `unsafe`: promising pyo3 that the classes may
// be shared between threads, which the thread check below makes true.
#![allow(unsafe_code)]

use std::mem::ManuallyDrop;
use std::thread::{self, ThreadId};

use pyo3::PyResult;

use super::errors::wrong_thread;

thread_local! {
    /// This thread's id, read once (`thread::current()` clones a handle on every call; the
    /// check runs on every method call).
    static THIS_THREAD: ThreadId = thread::current().id();
}

/// The calling thread's id (its own handle's while the thread is being torn down).
fn this_thread() -> ThreadId {
    THIS_THREAD
        .try_with(|id| *id)
        .unwrap_or_else(|_| thread::current().id())
}

/// A value that only the thread which created it can reach.
pub(crate) struct Owned<T> {
    owner: ThreadId,
    value: ManuallyDrop<T>,
}

// SAFETY: the value is reached only through `get`/`mine`, which check that the caller is the
// owning thread, and dropped only on that thread (elsewhere it is leaked); the `owner` field
// itself is immutable. So no two threads ever touch `T`, whatever `T` is.
unsafe impl<T> Send for Owned<T> {}
// SAFETY: as above: a shared `&Owned<T>` gives another thread nothing but the owner's id.
unsafe impl<T> Sync for Owned<T> {}

impl<T> Owned<T> {
    pub(crate) fn new(value: T) -> Owned<T> {
        Owned {
            owner: this_thread(),
            value: ManuallyDrop::new(value),
        }
    }

    fn is_mine(&self) -> bool {
        this_thread() == self.owner
    }

    /// The value, or `vrpn.WrongThreadError` naming `class` on any other thread.
    pub(crate) fn get(&self, class: &str) -> PyResult<&T> {
        if self.is_mine() {
            Ok(&self.value)
        } else {
            Err(wrong_thread(class))
        }
    }

    /// The value on its own thread; `None` elsewhere (garbage collection from another
    /// thread, which must neither fail nor touch the value).
    pub(crate) fn mine(&self) -> Option<&T> {
        self.is_mine().then_some(&*self.value)
    }
}

impl<T> Drop for Owned<T> {
    fn drop(&mut self) {
        if self.is_mine() {
            // SAFETY: dropped once, here, on the owning thread; never used afterwards.
            unsafe { ManuallyDrop::drop(&mut self.value) }
        }
        // On another thread the value is leaked: dropping its `Rc`s there could race with
        // the owning thread's use of the same counts.
    }
}

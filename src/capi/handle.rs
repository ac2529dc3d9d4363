//! Opaque handles: how a pointer from C becomes a checked `&T`, and how it is freed.
//!
//! Every handle starts with a [`Header`]: a per-kind tag (a freed handle or a handle of
//! another kind is refused, as far as its memory can still be read), the thread that made it
//! (connections use `Rc` and `RefCell`, so another thread must not touch them), and a count
//! of calls into it that are running. A callback may free the handle whose `mainloop` called
//! it: the free is then deferred until that outer call returns, so no `&T` ever outlives
//! the memory it points to.

use std::cell::Cell;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::thread::{self, ThreadId};

use super::{record, Failure, VrpnStatus};

/// The common start of every handle.
pub(crate) struct Header {
    tag: Cell<u32>,
    owner: ThreadId,
    /// Calls into this handle now running on the stack.
    depth: Cell<u32>,
    /// Freed while a call was running: dropped when the outermost call returns.
    doomed: Cell<bool>,
}

impl Header {
    pub(crate) fn new<T: Object>() -> Header {
        Header {
            tag: Cell::new(T::TAG),
            owner: thread::current().id(),
            depth: Cell::new(0),
            doomed: Cell::new(false),
        }
    }
}

/// A kind of handle.
pub(crate) trait Object: Sized {
    /// The kind's tag (distinct per kind, never 0).
    const TAG: u32;
    /// The C type name, for error texts.
    const NAME: &'static str;
    fn header(&self) -> &Header;
}

/// Converts a panic payload into the text of a [`VrpnStatus::Internal`] failure.
fn panic_failure(payload: Box<dyn std::any::Any + Send>) -> Failure {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    Failure::new(
        VrpnStatus::Internal,
        format!("internal error in the vrpn library (please report it): {what}"),
    )
}

/// Runs `f`, turning a panic into a failure.
pub(crate) fn guard<R>(f: impl FnOnce() -> Result<R, Failure>) -> Result<R, Failure> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|p| Err(panic_failure(p)))
}

/// Checks the tag and the thread of `ptr`.
///
/// # Safety
/// `ptr` is NULL or points to memory at least as large as `T` that can be read.
unsafe fn check<'a, T: Object>(ptr: *const T) -> Result<&'a T, Failure> {
    if ptr.is_null() {
        return Err(Failure::new(
            VrpnStatus::NullArgument,
            format!("{} handle is NULL", T::NAME),
        ));
    }
    // SAFETY: non-null; the caller guarantees it came from this library's `Box<T>` and was not
    // freed (a freed or foreign handle fails the tag check below as long as its memory is
    // still readable, which is the best a C boundary can do).
    let obj = unsafe { &*ptr };
    let h = obj.header();
    if h.tag.get() != T::TAG || h.doomed.get() {
        return Err(Failure::new(
            VrpnStatus::InvalidHandle,
            format!(
                "not a live {} handle (freed already, or another kind)",
                T::NAME
            ),
        ));
    }
    if h.owner != thread::current().id() {
        return Err(Failure::new(
            VrpnStatus::WrongThread,
            format!(
                "{} handle used from a thread other than the one that created it",
                T::NAME
            ),
        ));
    }
    Ok(obj)
}

/// Calls `f` on the handle behind `ptr`: NULL, freed, foreign-thread handles and panics
/// become failures.
pub(crate) fn with<T: Object, R>(
    ptr: *const T,
    f: impl FnOnce(&T) -> Result<R, Failure>,
) -> Result<R, Failure> {
    // SAFETY: `ptr` is what C passed as a handle of kind T (see `check`).
    let obj = unsafe { check(ptr)? };
    let h = obj.header();
    h.depth.set(h.depth.get() + 1);
    let r = guard(|| f(obj));
    h.depth.set(h.depth.get() - 1);
    if h.depth.get() == 0 && h.doomed.get() {
        // A callback freed this handle during `f`; `obj` is not used after this point.
        // SAFETY: the handle came from `Box::into_raw` in `into_handle`, no call into it is
        // running any more, and its tag was cleared so no later call will touch it.
        drop(guard(|| {
            drop(unsafe { Box::from_raw(ptr as *mut T) });
            Ok(())
        }));
    }
    r
}

/// Boxes a new handle for C; NULL (with the failure recorded) when `make` failed.
pub(crate) fn into_handle<T: Object>(make: impl FnOnce() -> Result<T, Failure>) -> *mut T {
    match guard(make) {
        Ok(t) => Box::into_raw(Box::new(t)),
        Err(f) => {
            record(f);
            std::ptr::null_mut()
        }
    }
}

/// Frees a handle (NULL is ignored). A handle freed from inside one of its own callbacks is
/// released when the call that ran the callback returns.
pub(crate) fn free<T: Object>(ptr: *mut T) -> VrpnStatus {
    if ptr.is_null() {
        return VrpnStatus::Ok;
    }
    // SAFETY: as for `with`.
    let obj = match unsafe { check(ptr) } {
        Ok(o) => o,
        Err(f) => return record(f),
    };
    let h = obj.header();
    h.tag.set(0);
    if h.depth.get() > 0 {
        h.doomed.set(true);
        return VrpnStatus::Ok;
    }
    // SAFETY: the handle came from `Box::into_raw` in `into_handle`, no call into it is
    // running (depth 0), and its tag is cleared so a double free is refused while the memory
    // is still readable.
    match guard(|| {
        drop(unsafe { Box::from_raw(ptr) });
        Ok(())
    }) {
        Ok(()) => VrpnStatus::Ok,
        Err(f) => record(f),
    }
}

/// Writes `value` through an output pointer argument.
///
/// # Safety
/// `out` is NULL or points to writable memory for a `T`.
pub(crate) unsafe fn write_out<T>(out: *mut T, value: T, what: &str) -> Result<(), Failure> {
    if out.is_null() {
        return Err(Failure::new(
            VrpnStatus::NullArgument,
            format!("{what} is NULL"),
        ));
    }
    // SAFETY: non-null; the caller guarantees it is writable and aligned for T.
    unsafe { out.write(value) };
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::cell::Cell;
    use std::rc::Rc;

    use super::*;

    /// A handle kind that counts its drops.
    struct Probe {
        header: Header,
        drops: Rc<Cell<u32>>,
    }

    impl Object for Probe {
        const TAG: u32 = 0x7672_ff01;
        const NAME: &'static str = "Probe";
        fn header(&self) -> &Header {
            &self.header
        }
    }

    impl Drop for Probe {
        fn drop(&mut self) {
            self.drops.set(self.drops.get() + 1);
        }
    }

    fn probe() -> (*mut Probe, Rc<Cell<u32>>) {
        let drops = Rc::new(Cell::new(0));
        let d = drops.clone();
        let p = into_handle(|| {
            Ok(Probe {
                header: Header::new::<Probe>(),
                drops: d,
            })
        });
        assert!(!p.is_null());
        (p, drops)
    }

    #[test]
    fn a_panic_becomes_an_internal_error_with_its_text() {
        let (p, drops) = probe();
        let r: Result<(), Failure> = with(p, |_| panic!("deliberate test panic"));
        let f = r.unwrap_err();
        assert_eq!(f.status, VrpnStatus::Internal);
        assert!(f.text.contains("deliberate test panic"), "{}", f.text);
        // The handle is still usable after the panic, then freed once.
        assert!(with(p, |_| Ok(())).is_ok());
        assert_eq!(free(p), VrpnStatus::Ok);
        assert_eq!(drops.get(), 1);
    }

    #[test]
    fn a_handle_freed_inside_a_call_is_dropped_when_the_call_returns() {
        let (p, drops) = probe();
        let r = with(p, |_| {
            assert_eq!(free(p), VrpnStatus::Ok);
            // Still alive: the outer call holds a reference.
            assert_eq!(drops.get(), 0);
            // Calls into a handle being freed are refused.
            let again = with(p, |_| Ok(()));
            assert_eq!(again.unwrap_err().status, VrpnStatus::InvalidHandle);
            Ok(7)
        });
        assert_eq!(r.unwrap(), 7);
        assert_eq!(drops.get(), 1);
    }

    #[test]
    fn null_and_foreign_thread_handles_are_refused() {
        let r = with(std::ptr::null::<Probe>(), |_| Ok(()));
        assert_eq!(r.unwrap_err().status, VrpnStatus::NullArgument);
        let (p, drops) = probe();
        let addr = p as usize;
        let (status, freed) = std::thread::spawn(move || {
            let p = addr as *mut Probe;
            let s = with(p, |_| Ok(())).unwrap_err().status;
            (s, free(p))
        })
        .join()
        .unwrap();
        assert_eq!(status, VrpnStatus::WrongThread);
        assert_eq!(freed, VrpnStatus::WrongThread);
        assert_eq!(drops.get(), 0);
        assert_eq!(free(p), VrpnStatus::Ok);
        assert_eq!(drops.get(), 1);
    }
}

//! Catching a panic of a library without its message on stderr, on the
//! calling thread only. The USD reader is young: should it panic on a
//! hostile file, the import reports the file's error instead
//! (docs/design.md §6.8, "Hostile files"). Swapping the process-wide panic
//! hook around each import would silence panics on every other thread
//! meanwhile and race with a concurrent import restoring its own; instead
//! one hook, installed once over the one before it, stays silent only on
//! a thread inside [`catch_quietly`].

use std::cell::Cell;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;

thread_local! {
    /// How many `catch_quietly` calls this thread is inside.
    static QUIET: Cell<u32> = const { Cell::new(0) };
}

/// Whether a panic on this thread now would be caught quietly.
#[must_use]
pub fn is_quiet() -> bool {
    QUIET.with(Cell::get) > 0
}

/// `f()`, or the payload of the panic that ended it, which no panic hook
/// reports; a panic on any other thread meanwhile is reported as before.
pub fn catch_quietly<R>(f: impl FnOnce() -> R) -> std::thread::Result<R> {
    static INSTALL: Once = Once::new();
    INSTALL.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !is_quiet() {
                previous(info);
            }
        }));
    });
    QUIET.with(|q| q.set(q.get() + 1));
    let result = catch_unwind(AssertUnwindSafe(f));
    QUIET.with(|q| q.set(q.get() - 1));
    result
}

/// A panic's message (a `String` or `&str` payload), else empty.
#[must_use]
pub fn message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| payload.downcast_ref::<&str>().map(|s| (*s).to_string()))
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_inside_is_caught_on_this_thread_and_no_other_is_silenced() {
        assert!(!is_quiet());
        let (inside, other) = (std::sync::Barrier::new(2), std::sync::Barrier::new(2));
        std::thread::scope(|scope| {
            let elsewhere = scope.spawn(|| {
                inside.wait();
                // The caller is inside catch_quietly now; this thread is not.
                let quiet = is_quiet();
                other.wait();
                quiet
            });
            let caught = catch_quietly(|| {
                assert!(is_quiet());
                inside.wait();
                other.wait();
                let nested = catch_quietly(|| -> u32 { panic!("inner {}", 7) });
                assert_eq!(message(&*nested.unwrap_err()), "inner 7");
                assert!(is_quiet(), "still inside the outer call");
                panic!("hostile file");
            });
            assert_eq!(message(&*caught.unwrap_err()), "hostile file");
            assert!(!elsewhere.join().unwrap(), "another thread was silenced");
        });
        assert!(!is_quiet());
        assert_eq!(catch_quietly(|| 5).unwrap(), 5);
    }
}

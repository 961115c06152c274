//! Named inputs: values a run holds and its user sets between steps (a controller's command, a
//! co-simulated force), read by [`TimeFunction::Input`](crate::TimeFunction::Input).
//!
//! A model is immutable and may be shared by many runs; an input's value belongs to the run, as a
//! state does (MuJoCo's `mjData.ctrl` beside `mjModel`). The seam evaluates a model at `(t, q, v)`
//! only, so a run makes its input values visible to the evaluations it drives with
//! [`with_inputs`]: for the duration of the closure, on the calling thread, input `k` reads
//! `values[k]`. Outside any such scope (a run without inputs set, a check, another thread) every
//! input reads 0, the value an input has before its first set. Scopes nest: the inner one's values
//! are seen inside it, the outer one's again after it.

use std::cell::Cell;
use std::marker::PhantomData;

thread_local! {
    /// The values of the innermost [`with_inputs`] scope on this thread: start and length of a
    /// slice that outlives the scope (null and 0 outside every scope).
    static HELD: Cell<(*const f64, usize)> = const { Cell::new((std::ptr::null(), 0)) };
}

/// Restores the enclosing scope's values when a scope ends, also when it ends by a panic.
struct Scope<'a> {
    previous: (*const f64, usize),
    _values: PhantomData<&'a [f64]>,
}

impl Drop for Scope<'_> {
    fn drop(&mut self) {
        HELD.with(|h| h.set(self.previous));
    }
}

/// Runs `f` with input `k` reading `values[k]` on this thread (inputs beyond `values` read 0).
/// The values cannot change while `f` runs (they are borrowed for its duration).
pub fn with_inputs<R>(values: &[f64], f: impl FnOnce() -> R) -> R {
    let previous = HELD.with(|h| h.replace((values.as_ptr(), values.len())));
    let _scope = Scope {
        previous,
        _values: PhantomData::<&[f64]>,
    };
    f()
}

/// The value of input `k` in the innermost [`with_inputs`] scope of this thread; 0 outside every
/// scope or beyond its values.
#[inline]
pub fn input_value(k: usize) -> f64 {
    HELD.with(|h| {
        let (start, len) = h.get();
        if k < len {
            // SAFETY: `(start, len)` was set by `with_inputs` from a slice borrowed for the whole
            // scope, and is replaced by the enclosing scope's (or null, 0) when the scope ends,
            // also on unwinding (`Scope::drop`); the scope cannot be leaked, as it is private to
            // `with_inputs`. So while `k < len` the slice is alive and unchanged, and `k` is in it.
            unsafe { *start.add(k) }
        } else {
            0.0
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values are seen inside their scope only; an inner scope shadows and then restores the
    /// outer one; a panic inside a scope restores it too.
    #[test]
    fn scopes_nest_and_restore() {
        assert_eq!(input_value(0), 0.0);
        let outer = [1.5, -2.0];
        with_inputs(&outer, || {
            assert_eq!((input_value(0), input_value(1), input_value(2)), (1.5, -2.0, 0.0));
            with_inputs(&[7.0], || assert_eq!((input_value(0), input_value(1)), (7.0, 0.0)));
            assert_eq!(input_value(1), -2.0);
            let caught = std::panic::catch_unwind(|| with_inputs(&[9.0], || panic!("inside")));
            assert!(caught.is_err());
            assert_eq!(input_value(0), 1.5, "the panic left the outer scope's values");
        });
        assert_eq!(input_value(0), 0.0);
        // Another thread sees none of this thread's values.
        with_inputs(&outer, || {
            assert_eq!(std::thread::spawn(|| input_value(0)).join().unwrap(), 0.0);
        });
    }
}

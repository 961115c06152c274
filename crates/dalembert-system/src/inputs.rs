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
//!
//! Forces computed by the caller's code (a Rust closure, a Python function) reach the model the
//! same way: a model's code-force element `k` asks [`code_force`] for its wrench, which calls the
//! function lent by the innermost [`with_code_forces`] scope (a zero wrench outside every scope).

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

/// The motion of one body at a stage, global components: what a code force is computed from. A
/// planar body moves in the x–y plane (`position[2] = 0`, rotation about z by its angle,
/// `angular_velocity = [0, 0, ω]`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyMotion {
    /// Centre of mass.
    pub position: [f64; 3],
    /// Rotation matrix, body frame to global frame (rows).
    pub rotation: [[f64; 3]; 3],
    /// Velocity of the centre of mass.
    pub velocity: [f64; 3],
    /// Angular velocity.
    pub angular_velocity: [f64; 3],
}

/// A force at a body's centre of mass and a torque, global components (a planar body takes
/// `force[0]`, `force[1]` and `torque[2]`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Wrench {
    /// Force (N).
    pub force: [f64; 3],
    /// Torque (N m).
    pub torque: [f64; 3],
}

/// The function a run lends its code forces through: element index, time, the body's motion.
pub type CodeForceFn<'a> = dyn Fn(usize, f64, &BodyMotion) -> Wrench + 'a;

thread_local! {
    /// The code forces of the innermost [`with_code_forces`] scope on this thread.
    static CODE: Cell<Option<*const CodeForceFn<'static>>> = const { Cell::new(None) };
}

/// Restores the enclosing scope's code forces when a scope ends, also by a panic.
struct CodeScope<'a> {
    previous: Option<*const CodeForceFn<'static>>,
    _forces: PhantomData<&'a CodeForceFn<'a>>,
}

impl Drop for CodeScope<'_> {
    fn drop(&mut self) {
        CODE.with(|c| c.set(self.previous));
    }
}

/// Runs `f` with code-force element `k` computed by `forces(k, t, motion)` on this thread.
pub fn with_code_forces<R>(forces: &CodeForceFn<'_>, f: impl FnOnce() -> R) -> R {
    let ptr: *const CodeForceFn<'_> = forces;
    // SAFETY: only the lifetime bound of the trait object is erased; the pointer is read only
    // while this scope lives (`code_force` runs inside `f`, and `CodeScope` puts the enclosing
    // scope's pointer back when `f` returns or unwinds), during which `forces` is borrowed.
    let ptr: *const CodeForceFn<'static> = unsafe { std::mem::transmute(ptr) };
    let previous = CODE.with(|c| c.replace(Some(ptr)));
    let _scope = CodeScope {
        previous,
        _forces: PhantomData,
    };
    f()
}

/// The wrench of code-force element `k` at time `t` for a body moving as `motion`: the innermost
/// [`with_code_forces`] scope's function, or zero outside every scope.
pub fn code_force(k: usize, t: f64, motion: &BodyMotion) -> Wrench {
    match CODE.with(|c| c.get()) {
        // SAFETY: set by `with_code_forces` from a reference borrowed for the whole scope and
        // replaced when the scope ends (see there), so the function is alive here.
        Some(ptr) => unsafe { (*ptr)(k, t, motion) },
        None => Wrench::default(),
    }
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
        // Code forces: seen inside their scope only.
        let motion = BodyMotion::default();
        assert_eq!(code_force(0, 0.0, &motion), Wrench::default());
        let push = |k: usize, t: f64, _: &BodyMotion| Wrench {
            force: [k as f64 + t, 0.0, 0.0],
            torque: [0.0; 3],
        };
        with_code_forces(&push, || assert_eq!(code_force(2, 0.5, &motion).force[0], 2.5));
        assert_eq!(code_force(2, 0.5, &motion), Wrench::default());
        // Another thread sees none of this thread's values.
        with_inputs(&outer, || {
            assert_eq!(std::thread::spawn(|| input_value(0)).join().unwrap(), 0.0);
        });
    }
}

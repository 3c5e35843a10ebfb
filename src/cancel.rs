//! A cancel handle the caller owns: raised from anywhere (a Ctrl-C handler, another thread),
//! read by the evaluation, the prepare stage and the render, which stop at their next check.
//! The render also writes its progress into it ([`Cancel::progress`]), so one handle both
//! stops the work and tells how far it got.
//!
//! A leaf: every stage may read it, and it knows nothing of them.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// A shared flag that asks the work holding it to stop, and the render's progress. Clones share
/// both; the default is a fresh flag that nobody else holds (so it is never raised).
#[derive(Clone, Default)]
pub struct Cancel(Arc<AtomicBool>, Arc<[AtomicU32; 2]>);

impl Cancel {
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks the work to stop (it stops at its next check; raising twice is the same as once).
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`Cancel::cancel`] was called on this handle or a clone of it. One relaxed load:
    /// cheap enough for every step of an evaluation.
    #[inline]
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// The flag itself, for the functions that take `&AtomicBool` (the render's passes).
    pub fn flag(&self) -> &AtomicBool {
        &self.0
    }

    /// Whether `self` and `other` are clones of one handle.
    pub fn same(&self, other: &AtomicBool) -> bool {
        std::ptr::eq(&*self.0, other)
    }

    /// The iterations finished and the iterations asked for, as the render last reported them
    /// (`(0, 0)` before it started; the total may be a bound when a time limit ends it first).
    pub fn progress(&self) -> (u32, u32) {
        (
            self.1[0].load(Ordering::Relaxed),
            self.1[1].load(Ordering::Relaxed),
        )
    }

    /// Records the render's progress (see [`Cancel::progress`]).
    pub fn set_progress(&self, done: u32, total: u32) {
        self.1[1].store(total, Ordering::Relaxed);
        self.1[0].store(done, Ordering::Relaxed);
    }
}

impl From<Arc<AtomicBool>> for Cancel {
    /// A handle on a flag the caller already shares (as a Ctrl-C handler does).
    fn from(flag: Arc<AtomicBool>) -> Self {
        Self(flag, Arc::default())
    }
}

impl std::fmt::Debug for Cancel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("Cancel").field(&self.is_cancelled()).finish()
    }
}

/// Two handles are equal when they share one flag (options compare equal only when they would
/// be cancelled together).
impl PartialEq for Cancel {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clones_share_the_flag_and_fresh_handles_do_not() {
        let a = Cancel::new();
        let b = a.clone();
        let other = Cancel::new();
        assert!(!a.is_cancelled());
        b.cancel();
        assert!(a.is_cancelled() && b.is_cancelled());
        assert!(!other.is_cancelled());
        assert_eq!(a, b);
        assert_ne!(a, other);
        assert!(a.same(b.flag()) && !a.same(other.flag()));
        let shared = Arc::new(AtomicBool::new(false));
        let c = Cancel::from(shared.clone());
        shared.store(true, Ordering::Relaxed);
        assert!(c.is_cancelled());
    }
}

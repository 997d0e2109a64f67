//! Runtime dispatch of the vector kernels: each kernel is written once, in plain Rust
//! shaped for the compiler's vectoriser (slices of one length, no bounds checks, no
//! branches in the inner loop), and compiled twice: for the baseline of the target (SSE2
//! on x86_64; NEON on aarch64, where it is the baseline) and, through [`pulp`]'s runtime
//! dispatch, for the best instruction set the CPU reports (x86-64-v3: AVX2, POPCNT, BMI,
//! FMA). The arithmetic is the same code in both, integer or IEEE (Rust contracts no
//! multiply-add on its own), so both give the same results bit for bit; the tests compare
//! them on every kernel.

use std::cell::Cell;

thread_local! {
    /// Set inside [`baseline`]: kernels run their baseline compilation on this thread.
    static BASELINE: Cell<bool> = const { Cell::new(false) };
}

/// Runs `op` compiled for the best instruction set of this CPU, or for the target's
/// baseline inside [`baseline`]. `op` and what it calls must be inlined (`#[inline]` or
/// `#[inline(always)]`) to be compiled for the dispatched instruction set.
#[inline(always)]
pub fn dispatch<R>(op: impl FnOnce() -> R) -> R {
    if BASELINE.with(Cell::get) {
        op()
    } else {
        pulp::Arch::new().dispatch(op)
    }
}

/// Runs `op` with every kernel it calls on this thread compiled for the target's
/// baseline only (no runtime dispatch): the scalar path the tests compare with.
pub fn baseline<R>(op: impl FnOnce() -> R) -> R {
    /// Restores the previous setting, even when `op` panics.
    struct Restore(bool);
    impl Drop for Restore {
        fn drop(&mut self) {
            BASELINE.with(|b| b.set(self.0));
        }
    }
    let _restore = Restore(BASELINE.with(|b| b.replace(true)));
    op()
}

#[cfg(test)]
mod tests;

//! Runtime dispatch of the hot loops (issue 34), for every crate of the workspace: each
//! kernel is written once, in plain Rust shaped for the compiler's vectoriser (slices of one
//! length, no bounds checks, no branches in the inner loop), and compiled twice: for the
//! baseline of the target (SSE2 on x86_64; NEON on aarch64, where it is the baseline) and,
//! through [`pulp`]'s runtime dispatch, for the best instruction set the CPU reports
//! (x86-64-v3: AVX2, POPCNT, BMI, FMA). The arithmetic is the same code in both, integer or
//! IEEE (Rust contracts no multiply-add on its own; library calls such as `ln` are the same
//! calls), so both give the same results bit for bit; the tests compare them. One switch,
//! [`baseline`], turns the dispatch off on a thread for the kernels of every crate.

use std::cell::Cell;

thread_local! {
    /// Set inside [`baseline`]: kernels run their baseline compilation on this thread.
    static BASELINE: Cell<bool> = const { Cell::new(false) };
}

/// A kernel call: its arguments, and [`Kernel::run`] calling the kernel. Every
/// implementation marks `run` `#[inline(always)]`, and the functions it calls too: that is
/// what compiles them into each instruction set's copy (a closure would be compiled once,
/// for the baseline, and called from every copy).
pub trait Kernel {
    /// What the kernel returns.
    type Output;
    /// Calls the kernel.
    fn run(self) -> Self::Output;
}

/// A [`Kernel`] as pulp's unit of dispatch.
struct Dispatched<K>(K);

impl<K: Kernel> pulp::WithSimd for Dispatched<K> {
    type Output = K::Output;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> K::Output {
        self.0.run()
    }
}

/// Runs `kernel` compiled for the best instruction set of this CPU, or for the target's
/// baseline inside [`baseline`].
#[inline(always)]
pub fn dispatch<K: Kernel>(kernel: K) -> K::Output {
    if BASELINE.with(Cell::get) {
        kernel.run()
    } else {
        pulp::Arch::new().dispatch(Dispatched(kernel))
    }
}

/// Runs `op` with every kernel it calls on this thread compiled for the target's
/// baseline only (no runtime dispatch): the path the tests compare with.
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
mod tests {
    use super::{BASELINE, baseline};

    /// [`baseline`] is scoped: the dispatch comes back after it, also after a panic.
    #[test]
    fn baseline_is_scoped() {
        let inside = baseline(|| BASELINE.with(std::cell::Cell::get));
        assert!(inside);
        assert!(!BASELINE.with(std::cell::Cell::get));
        let panicked = std::panic::catch_unwind(|| baseline(|| panic!("inside")));
        assert!(panicked.is_err());
        assert!(!BASELINE.with(std::cell::Cell::get));
    }
}

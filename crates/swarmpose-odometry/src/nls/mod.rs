//! The nonlinear least-squares base of both solvers: the two-frame refinement
//! ([`crate::refine`]) and the sliding window's bundle adjustment ([`crate::window`]).
//!
//! | part | module |
//! |---|---|
//! | pose parameterisation and its update `T ← E(ξ) T` | [`pose`] |
//! | robust loss (Huber) | [`robust`] |
//! | the Levenberg-Marquardt damping loop, driven by a small trait | [`lm`] |
//! | points eliminated by their Schur complements, back-substitution | [`schur`] |
//! | small products of the normal equations, nalgebra's arithmetic with fewer operations | [`products`] |
//!
//! Each solver keeps its own residuals, normal equations and stopping test (the
//! refinement's reduced system is one 6x6 pose block per fold; the window's is dense over
//! its keyframes' poses) and implements [`lm::LeastSquares`] over them.
//!
//! Why in-house rather than a solver crate: `tools/solver_compare` ported the window's
//! problem (a KITTI-sized window, 10 keyframes, 7 724 measurements) to `apex-solver`
//! (which has a Schur complement) and `tiny-solver` (which has none); all three reached
//! the same solution in the same iterations, and this code was 7 times faster per
//! iteration than `apex-solver` and 85 times faster than `tiny-solver` on one thread
//! (`tools/solver_compare/README.md`, `docs/window.md`). The crates also bring their own
//! nalgebra versions and a sparse-algebra stack, where the problem, once the points are
//! eliminated, is small and dense.

pub(crate) mod lm;
pub(crate) mod pose;
pub(crate) mod products;
pub(crate) mod robust;
pub(crate) mod schur;

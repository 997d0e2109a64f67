//! Runtime dispatch of the front end's vector kernels: [`swarmpose_core::simd`], the one
//! dispatch of the workspace (its [`baseline`] switch turns it off for the kernels of every
//! crate on a thread). The tests here compare the two compilations of the front end's kernels.

pub use swarmpose_core::simd::{Kernel, baseline, dispatch};

#[cfg(test)]
mod tests;

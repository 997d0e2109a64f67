//! A generic particle swarm optimizer, eq. (4)-(5) of the paper (Kennedy & Eberhart 1995).
//!
//! Each particle `i` has a position `x_i` in a box of `R^D` and a velocity `v_i`:
//!
//! ```text
//! v_i(k) = α φ0 v_i(k-1) + c φ1 (p_i - x_i(k-1)) + c φ2 (p_g - x_i(k-1))     (5)
//! x_i(k) = x_i(k-1) + v_i(k)                                                 (4)
//! ```
//!
//! with `φ0, φ1, φ2 ~ U[0, 1]` drawn per particle and dimension, `p_i` the particle's best
//! position, `p_g` the swarm's best. Velocities are clamped per dimension to a fraction of
//! the box width and positions to the box.
//!
//! Scores are generic (`S: PartialOrd + Copy`, lower is better), so a fitness can be a
//! plain `f64` or a lexicographic pair such as `(fewer-misses, cost)`.

mod swarm;

pub use swarm::{MAX_ITERATIONS, MAX_SWARM_SIZE, ParticleSwarm, PsoConfig, PsoOutcome};

//! The normal equations of the Mahalanobis Gauss-Newton steps, summed point by point with
//! the arithmetic of four points at a time in the lanes of vector registers (issue 34).

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector3, Vector6};

use super::add_point_full;
use crate::geometry::Correspondences;

/// Points whose updates are computed together, one a lane.
const LANES: usize = 4;

/// Entries of `(h, g)`: h's 36 by columns, then g's 6.
const ENTRIES: usize = 42;

/// One value of each of [`LANES`] points.
type Lanes = [f64; LANES];

/// The normal equations `(h, g)` of a Gauss-Newton step (6 × 6 and 6), summed point by
/// point ([`Normal::add_point`]). The points' updates are computed [`LANES`] at a time,
/// each point's arithmetic in its own lane (the same operations as one at a time), then
/// added to `(h, g)` point after point: the same sums in the same order, so the same bits.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Normal {
    /// `h` by columns, then `g`.
    sums: [f64; ENTRIES],
    /// The points waiting for their updates: `q = pose·src` (3), `r = dst − q` (3), and
    /// the information `w` by columns (9), one point a lane.
    pending: [Lanes; 15],
    /// How many lanes of `pending` hold points.
    count: usize,
}

impl Normal {
    /// `h = 0`, `g = 0` (every entry `+0`).
    pub(crate) fn zeros() -> Self {
        Self {
            sums: [0.0; ENTRIES],
            pending: [[0.0; LANES]; 15],
            count: 0,
        }
    }

    /// `(h, g)` with every point added.
    #[inline(always)]
    pub(crate) fn parts(mut self) -> (Matrix6<f64>, Vector6<f64>) {
        self.flush();
        self.matrices()
    }

    /// `(h, g)` of the points already added to `sums`.
    #[inline(always)]
    fn matrices(&self) -> (Matrix6<f64>, Vector6<f64>) {
        let h = Matrix6::from_column_slice(&self.sums[..36]);
        (h, Vector6::from_column_slice(&self.sums[36..]))
    }

    /// Adds correspondence `i` of `data`, weighted by the 3 × 3 information `w` (1/m²), to
    /// the normal equations of a Gauss-Newton step on `pose` (the motion `dst = R src + t`)
    /// perturbed on the left by `(ω, ν)` (radians, metres, in the destination frame):
    /// residual `r = dst − pose·src`, Jacobian `[[q]×, −I]` with `q = pose·src`.
    ///
    /// The same bits as `h += Jᵀ w J`, `g += Jᵀ w r` through nalgebra (issue 34), with the
    /// Jacobian's zeros left out: nalgebra sums `P = Jᵀ w` and `P J` term by term in order,
    /// and a term `0 · x` (`x` finite) is a zero, which leaves a sum unchanged unless the
    /// sum is itself zero, when only its sign can differ; `h` and `g` start at `+0` and
    /// never hold `-0` (`+0 + -0 = +0`), so such a zero adds nothing either way. When `w`
    /// or `P` is not finite (`0 · ∞` is NaN) the full products are taken. Inlined into the
    /// [`crate::simd::Kernel`]s that call it.
    #[inline(always)]
    pub(crate) fn add_point(
        &mut self,
        pose: &Isometry3<f64>,
        data: &Correspondences,
        i: usize,
        w: &Matrix3<f64>,
    ) {
        let q = (pose * data.src()[i]).coords;
        let r = data.dst()[i].coords - q;
        let lane = self.count;
        for k in 0..3 {
            self.pending[k][lane] = q[k];
            self.pending[3 + k][lane] = r[k];
        }
        for (b, column) in w.data.0.iter().enumerate() {
            for (k, v) in column.iter().enumerate() {
                self.pending[6 + 3 * b + k][lane] = *v;
            }
        }
        self.count += 1;
        if self.count == LANES {
            self.flush();
        }
    }

    /// Adds the pending points' updates to `sums`, in the order the points came.
    #[inline(always)]
    fn flush(&mut self) {
        let count = std::mem::replace(&mut self.count, 0);
        if count == 0 {
            return;
        }
        let (deltas, finite) = updates(&self.pending);
        if count == LANES && finite == [true; LANES] {
            for (s, d) in self.sums.iter_mut().zip(&deltas) {
                *s = (((*s + d[0]) + d[1]) + d[2]) + d[3];
            }
            return;
        }
        for lane in 0..count {
            if finite[lane] {
                for (s, d) in self.sums.iter_mut().zip(&deltas) {
                    *s += d[lane];
                }
            } else {
                let at = |k: usize| self.pending[k][lane];
                let q = Vector3::new(at(0), at(1), at(2));
                let r = Vector3::new(at(3), at(4), at(5));
                let w = Matrix3::from_fn(|row, col| at(6 + 3 * col + row));
                let (mut h, mut g) = self.matrices();
                add_point_full(&mut h, &mut g, &q, &r, &w);
                self.sums[..36].copy_from_slice(h.as_slice());
                self.sums[36..].copy_from_slice(g.as_slice());
            }
        }
    }
}

/// `f` lane by lane.
#[inline(always)]
fn map(f: impl Fn(usize) -> f64) -> Lanes {
    // Written out: `std::array::from_fn` left a call per element in the kernels.
    [f(0), f(1), f(2), f(3)]
}

/// `P = Jᵀ w` (6 × 3, by columns `[b][a]`) of each lane's pending point (see
/// [`Normal::add_point`]): rows 0-2 from the columns of `[q]×`, whose zero is left out;
/// rows 3-5 are −w (−1 · x, the same bits as −x for finite x; the −0 terms left out).
#[inline(always)]
fn jacobian_products(pending: &[Lanes; 15]) -> [[Lanes; 6]; 3] {
    let [q0, q1, q2, ..] = pending;
    let col = |b: usize, k: usize| &pending[6 + 3 * b + k]; // w_kb
    let columns = |b: usize| {
        let (c0, c1, c2) = (col(b, 0), col(b, 1), col(b, 2));
        [
            map(|l| q2[l] * c1[l] + (-q1[l]) * c2[l]),
            map(|l| (-q2[l]) * c0[l] + q0[l] * c2[l]),
            map(|l| q1[l] * c0[l] + (-q0[l]) * c1[l]),
            map(|l| -c0[l]),
            map(|l| -c1[l]),
            map(|l| -c2[l]),
        ]
    };
    [columns(0), columns(1), columns(2)]
}

/// Whether each lane's `P` is finite (else its updates are not used: the full products
/// are taken). P's rows 3-5 are −w, so P holds every entry of w. A sum with an infinite
/// or NaN term is ±∞ or NaN in any order, so these sums are finite only when every entry
/// of P (and w) is; a sum that overflows merely takes the full products (the same bits
/// for finite w and P).
#[inline(always)]
fn finite_lanes(p: &[[Lanes; 6]; 3]) -> [bool; LANES] {
    let row_sum = |a: usize| map(|l| p[0][a][l] + p[1][a][l] + p[2][a][l]);
    let sums = [
        row_sum(0),
        row_sum(1),
        row_sum(2),
        row_sum(3),
        row_sum(4),
        row_sum(5),
    ];
    let lane = |l: usize| {
        let s = |a: usize| sums[a][l];
        ((s(0) + s(1)) + (s(2) + s(3)) + (s(4) + s(5))).is_finite()
    };
    [lane(0), lane(1), lane(2), lane(3)]
}

/// Each lane's update of the entries of `(h, g)` (h by columns, then g) from its pending
/// point: `(P J)[a][c]`, J's columns 0-2 those of `[q]×`, 3-5 those of −I, then
/// `(P r)[a]`; and whether that point's `P` is finite (else its updates are not used:
/// the full products are taken).
#[inline(always)]
fn updates(pending: &[Lanes; 15]) -> ([Lanes; ENTRIES], [bool; LANES]) {
    let [q0, q1, q2, r0, r1, r2, ..] = pending;
    let p = jacobian_products(pending);
    let finite = finite_lanes(&p);
    let [p0, p1, p2] = &p;
    let mut deltas = [[0.0; LANES]; ENTRIES];
    for a in 0..6 {
        deltas[a] = map(|l| p1[a][l] * q2[l] + p2[a][l] * (-q1[l]));
        deltas[6 + a] = map(|l| p0[a][l] * (-q2[l]) + p2[a][l] * q0[l]);
        deltas[12 + a] = map(|l| p0[a][l] * q1[l] + p1[a][l] * (-q0[l]));
        for (k, pk) in p.iter().enumerate() {
            deltas[6 * (3 + k) + a] = map(|l| -pk[a][l]);
        }
        deltas[36 + a] = map(|l| p0[a][l] * r0[l] + p1[a][l] * r1[l] + p2[a][l] * r2[l]);
    }
    (deltas, finite)
}

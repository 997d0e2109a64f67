//! The Levenberg-Marquardt driver: the damping loop of both solvers, driven through the
//! small [`LeastSquares`] trait (linearise, solve the damped system, evaluate the step,
//! take it). The problem owns its state and its normal equations; the driver owns the
//! damping `λ` and the order of the steps.
//!
//! Each iteration linearises the problem at its state, then tries damped steps: `λ`
//! grows tenfold while the damped system is not positive definite or its step does not
//! lower the cost; the first step that lowers the cost is taken and `λ` shrinks tenfold
//! (not below 10⁻⁹). The iterations stop at the problem's convergence test, when `λ`
//! passes its ceiling without a step that lowers the cost, or after the most iterations.

/// A nonlinear least-squares problem as the driver sees it.
pub(crate) trait LeastSquares {
    /// Why the problem cannot go on (a linearisation that fails).
    type Error;

    /// Linearises the problem at its state (the normal equations that
    /// [`LeastSquares::solve_damped`] damps) and returns the cost there.
    ///
    /// # Errors
    /// When the problem cannot be linearised; the driver stops and passes it on.
    fn linearise(&mut self) -> Result<f64, Self::Error>;

    /// Solves the normal equations damped by `lambda` for a step; false when the damped
    /// system is not positive definite.
    fn solve_damped(&mut self, lambda: f64) -> bool;

    /// The cost at the state moved by the last step solved.
    fn trial_cost(&mut self) -> f64;

    /// Whether a step that lowers the cost from `current` to `trial` ends the iterations
    /// (asked before [`LeastSquares::accept`]).
    fn converged(&self, current: f64, trial: f64) -> bool;

    /// Takes the last step evaluated by [`LeastSquares::trial_cost`].
    fn accept(&mut self);
}

/// How the damping of the Levenberg-Marquardt loop starts and ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Damping {
    /// The first `λ`.
    pub(crate) start: f64,
    /// The ceiling: the iterations stall once `λ` passes it.
    pub(crate) ceiling: f64,
    /// Whether `λ` equal to the ceiling still tries a step. The two solvers differ here
    /// and keep their own rule (it decides whether a step is tried at `λ = 10⁸`, a value
    /// that `λ` reaches exactly in floating point from `10⁻⁴`).
    pub(crate) ceiling_tried: bool,
}

/// What one iteration did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Step {
    /// It took a step that lowered the cost: the next iteration may go on.
    Taken,
    /// It took a step that lowered the cost and the problem's test says converged.
    Converged,
    /// The damping passed its ceiling without a step that lowers the cost.
    Stalled,
}

impl Damping {
    /// The smallest `λ` after a step taken.
    const FLOOR: f64 = 1e-9;

    /// Whether `lambda` is past the ceiling.
    #[inline(always)]
    fn stalled(&self, lambda: f64) -> bool {
        if self.ceiling_tried {
            lambda > self.ceiling
        } else {
            lambda >= self.ceiling
        }
    }

    /// One iteration's damped steps on `problem`, linearised at cost `current`: `lambda`
    /// grows tenfold until a step lowers the cost, and that step is taken (`lambda` then
    /// shrinks tenfold).
    #[inline(always)]
    pub(crate) fn steps<P: LeastSquares + ?Sized>(
        &self,
        problem: &mut P,
        lambda: &mut f64,
        current: f64,
    ) -> Step {
        loop {
            if self.stalled(*lambda) {
                return Step::Stalled;
            }
            if !problem.solve_damped(*lambda) {
                *lambda *= 10.0;
                continue;
            }
            let c = problem.trial_cost();
            if c < current {
                let done = problem.converged(current, c);
                problem.accept();
                *lambda = (*lambda * 0.1).max(Self::FLOOR);
                return if done { Step::Converged } else { Step::Taken };
            }
            *lambda *= 10.0;
        }
    }

    /// At most `max_iterations` Levenberg-Marquardt iterations on `problem`; returns the
    /// iterations done (the one that converged or stalled counted).
    ///
    /// # Errors
    /// The problem's, when it cannot be linearised (its state as the last step left it).
    #[inline(always)]
    pub(crate) fn minimise<P: LeastSquares + ?Sized>(
        &self,
        problem: &mut P,
        max_iterations: usize,
    ) -> Result<usize, P::Error> {
        let mut lambda = self.start;
        for it in 0..max_iterations {
            let current = problem.linearise()?;
            if self.steps(problem, &mut lambda, current) != Step::Taken {
                return Ok(it + 1);
            }
        }
        Ok(max_iterations)
    }
}

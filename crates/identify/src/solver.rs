//! Solvers of the fitting problem and observers of their progress (argmin's split: the problem
//! says what a parameter vector costs, a solver searches, an observer watches).

use serde::{Deserialize, Serialize};

use crate::{FitProblem, IdentifyError};

/// What a solver reports after each of its iterations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// The iteration just finished, from 1.
    pub iteration: usize,
    /// The number of iterations the solver will run (at most).
    pub iterations: usize,
    /// The RMS error of the best parameter vector so far (normalised output units).
    pub best_cost: f64,
    /// Its total constraint violation (0 when feasible).
    pub best_violation: f64,
}

/// Watches a solver: a progress bar, a log, a convergence plot. Solvers never print.
///
/// Any `FnMut(&Progress)` closure is an observer:
///
/// ```
/// use hystcomp_identify::{Observer, Progress};
///
/// let mut costs = Vec::new();
/// let mut observer = |p: &Progress| costs.push(p.best_cost);
/// observer.observe(&Progress { iteration: 1, iterations: 2, best_cost: 0.5, best_violation: 0.0 });
/// observer.observe(&Progress { iteration: 2, iterations: 2, best_cost: 0.25, best_violation: 0.0 });
/// assert_eq!(costs, [0.5, 0.25]);
/// ```
pub trait Observer {
    /// Called after each iteration.
    fn observe(&mut self, progress: &Progress);

    /// Called when a new identification starts, when one observer watches several (as in
    /// [`crate::crossval()`]: `plant model`, then `inverse model`). Does nothing by default.
    fn begin(&mut self, _label: &str) {}
}

impl<F: FnMut(&Progress)> Observer for F {
    fn observe(&mut self, progress: &Progress) {
        self(progress)
    }
}

/// An observer that ignores everything.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoObserver;

impl Observer for NoObserver {
    fn observe(&mut self, _progress: &Progress) {}
}

/// What a solver found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Solution {
    /// The parameter vector (see [`FitProblem`] for its layout).
    pub theta: Vec<f64>,
    /// Its RMS error over the fitting span ([`FitProblem::cost`]), normalised output units.
    pub cost: f64,
    /// Its total constraint violation (0 when every constraint is met).
    pub violation: f64,
    /// How the solution was reached, for people (e.g. `unconstrained optimum`).
    pub detail: String,
}

/// A solver of the fitting problem: searches for the parameter vector of smallest
/// [`FitProblem::cost`] that meets every constraint.
///
/// ```
/// use hystcomp_identify::{FitProblem, LeastSquares, NoObserver, ProblemData, Solver};
/// use hystcomp_io::model_file::Direction;
///
/// // A pure cubic y = 0.2 x^3 + 0.8 x sampled on a triangle wave, one operator at r = 0.
/// let x: Vec<f64> = (0..200).map(|k| ((k % 50) as f64 / 49.0)).collect();
/// let y: Vec<f64> = x.iter().map(|x| 0.2 * x * x * x + 0.8 * x).collect();
/// let data = ProblemData { input: &x, output: &y, fit: 0..200 };
/// let problem = FitProblem::new(data, &[0.0], Direction::Plant, false, 1e-3)?;
/// let solution = LeastSquares::default().solve(&problem, &mut NoObserver)?;
/// assert!(solution.cost < 1e-12);
/// assert!((solution.theta[0] - 0.2).abs() < 1e-9);
/// # Ok::<(), hystcomp_identify::IdentifyError>(())
/// ```
pub trait Solver {
    /// A short name: `ls` or `pso`.
    fn name(&self) -> &'static str;

    /// Searches, telling `observer` about each iteration.
    fn solve(
        &self,
        problem: &FitProblem,
        observer: &mut dyn Observer,
    ) -> Result<Solution, IdentifyError>;
}

//! Constrained linear least squares: the global optimum of the fitting problem for the given
//! thresholds.
//!
//! 1. The unconstrained optimum `z = R^-1 d` (the QR of the column-scaled regressors, see
//!    [`crate::problem`]). When it meets every constraint, it is the answer.
//! 2. Otherwise the convex quadratic programme `min 1/2 ||R z - d||^2 / N` subject to
//!    `A S z >= margin` is solved with the interior-point solver Clarabel (Goulart & Chen,
//!    "Clarabel: an interior-point solver for conic programs with quadratic objectives",
//!    arXiv:2405.12762, 2024).
//! 3. The interior-point answer is exact only to the solver's tolerances, so the constraints it
//!    leaves active are taken as equalities and the equality-constrained least-squares problem
//!    is solved directly (its KKT system), adding violated or dropping wrongly signed
//!    constraints until the KKT conditions hold (a primal-dual active-set polish). The result
//!    is the optimum to rounding error; if the polish fails, the interior-point answer stands.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT,
};
use nalgebra::{DMatrix, DVector};

use crate::problem::{ACTIVE_TOLERANCE, dot};
use crate::{FitProblem, IdentifyError, Observer, Progress, Solution, Solver};

/// A solution may violate constraints by this fraction of the margin (rounding of the
/// active-set solve): its slopes are then still at least `(1 - 1e-9) margin > 0`.
pub(crate) const FEASIBILITY_TOLERANCE: f64 = 1e-9;

/// Most additions or removals of the active-set polish.
const ACTIVE_SET_ITERATIONS: usize = 200;

/// Constrained linear least squares (see the [module documentation](self)).
#[derive(Debug, Clone, Copy, Default)]
pub struct LeastSquares;

impl Solver for LeastSquares {
    fn name(&self) -> &'static str {
        "ls"
    }

    fn solve(
        &self,
        problem: &FitProblem,
        observer: &mut dyn Observer,
    ) -> Result<Solution, IdentifyError> {
        let (r, d, scale) = problem.scaled_system();
        let z = r
            .solve_upper_triangular(d)
            .ok_or(IdentifyError::IllConditioned {
                condition: f64::INFINITY,
                limit: f64::INFINITY,
            })?;
        let theta: Vec<f64> = z.iter().zip(scale.iter()).map(|(z, s)| z * s).collect();
        let solution = if problem.smallest_slack(&theta) >= 0.0 {
            finish(
                problem,
                theta,
                "unconstrained optimum (meets every constraint)".to_owned(),
            )
        } else {
            constrained(problem)?
        };
        observer.observe(&Progress {
            iteration: 1,
            iterations: 1,
            best_cost: solution.cost,
            best_violation: solution.violation,
        });
        Ok(solution)
    }
}

/// The solution record of a parameter vector.
pub(crate) fn finish(problem: &FitProblem, theta: Vec<f64>, detail: String) -> Solution {
    Solution {
        cost: problem.cost(&theta),
        violation: problem.violation(&theta),
        detail,
        theta,
    }
}

/// Step 2 and 3 of the module documentation.
fn constrained(problem: &FitProblem) -> Result<Solution, IdentifyError> {
    let qp = QuadraticProgram::new(problem);
    let (z_ip, initial_active) = qp.interior_point()?;
    let theta_ip = qp.to_theta(&z_ip);
    let ip = finish(problem, theta_ip, "interior-point QP (Clarabel)".to_owned());
    if let Some((z, active)) = qp.active_set(initial_active) {
        let theta = qp.to_theta(&z);
        let polished = finish(
            problem,
            theta,
            format!(
                "constrained optimum: interior-point QP (Clarabel), then exact on {} active \
                 constraint(s)",
                active.len()
            ),
        );
        if polished.violation <= ip.violation.max(FEASIBILITY_TOLERANCE * problem.margin())
            && polished.cost <= ip.cost + 1e-12
        {
            return Ok(polished);
        }
    }
    Ok(ip)
}

/// Solves the equality-constrained problem on `active`, then adds violated and drops wrongly
/// signed constraints until the KKT conditions hold. `None` when it does not settle.
pub(crate) fn polish_from(problem: &FitProblem, theta: &[f64]) -> Option<Solution> {
    let qp = QuadraticProgram::new(problem);
    let z: Vec<f64> = theta
        .iter()
        .zip(qp.scale.iter())
        .map(|(t, s)| if *s > 0.0 { t / s } else { 0.0 })
        .collect();
    // Start from the constraints the point violates or that are active there.
    let active: Vec<usize> = (0..qp.rows.len())
        .filter(|&j| dot(&qp.rows[j], &z) - qp.bounds[j] <= ACTIVE_TOLERANCE)
        .collect();
    let (z, active) = qp.active_set(active)?;
    Some(finish(
        problem,
        qp.to_theta(&z),
        format!(
            "least-squares polish on {} active constraint(s)",
            active.len()
        ),
    ))
}

/// `min 1/2 z' H z - g' z` subject to `rows z >= bounds` (`margin - shift` of each
/// constraint), in the scaled coordinates
/// `theta = S z`.
struct QuadraticProgram {
    /// `R' R / N`.
    h: DMatrix<f64>,
    /// `R' d / N`.
    g: DVector<f64>,
    /// Constraint rows in `z` (`a_j` times `S`).
    rows: Vec<Vec<f64>>,
    /// `margin - shift` of each row.
    bounds: Vec<f64>,
    margin: f64,
    scale: DVector<f64>,
}

impl QuadraticProgram {
    fn new(problem: &FitProblem) -> Self {
        let (r, d, scale) = problem.scaled_system();
        let n = problem.samples() as f64;
        let h = (r.transpose() * r) / n;
        let g = (r.transpose() * d) / n;
        let rows = problem
            .constraints()
            .iter()
            .map(|c| {
                c.coefficients
                    .iter()
                    .zip(scale.iter())
                    .map(|(a, s)| a * s)
                    .collect()
            })
            .collect();
        QuadraticProgram {
            h,
            g,
            rows,
            bounds: problem
                .constraints()
                .iter()
                .map(|c| problem.margin() - c.shift)
                .collect(),
            margin: problem.margin(),
            scale: scale.clone(),
        }
    }

    fn to_theta(&self, z: &[f64]) -> Vec<f64> {
        z.iter()
            .zip(self.scale.iter())
            .map(|(z, s)| z * s)
            .collect()
    }

    /// Clarabel on the whole programme: `z` and the constraints it leaves active (dual larger
    /// than slack).
    fn interior_point(&self) -> Result<(Vec<f64>, Vec<usize>), IdentifyError> {
        let p = self.h.nrows();
        let m = self.rows.len();
        // P: upper triangle, by columns.
        let mut colptr = vec![0];
        let mut rowval = Vec::new();
        let mut nzval = Vec::new();
        for j in 0..p {
            for i in 0..=j {
                rowval.push(i);
                nzval.push(self.h[(i, j)]);
            }
            colptr.push(rowval.len());
        }
        let big_p = CscMatrix::new(p, p, colptr, rowval, nzval);
        let q: Vec<f64> = self.g.iter().map(|g| -g).collect();
        // A z + s = b, s >= 0, with A = -rows and b = -margin: rows z - margin = s >= 0.
        let mut colptr = vec![0];
        let mut rowval = Vec::new();
        let mut nzval = Vec::new();
        for j in 0..p {
            for (i, row) in self.rows.iter().enumerate() {
                if row[j] != 0.0 {
                    rowval.push(i);
                    nzval.push(-row[j]);
                }
            }
            colptr.push(rowval.len());
        }
        let big_a = CscMatrix::new(m, p, colptr, rowval, nzval);
        let b: Vec<f64> = self.bounds.iter().map(|b| -b).collect();
        let cones: [SupportedConeT<f64>; 1] = [NonnegativeConeT(m)];
        let settings = DefaultSettings {
            verbose: false,
            max_iter: 500,
            tol_gap_abs: 1e-12,
            tol_gap_rel: 1e-12,
            tol_feas: 1e-12,
            ..DefaultSettings::default()
        };
        let mut solver =
            DefaultSolver::new(&big_p, &q, &big_a, &b, &cones, settings).map_err(|e| {
                IdentifyError::Solver {
                    reason: e.to_string(),
                }
            })?;
        solver.solve();
        let solution = &solver.solution;
        match solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => {}
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
                return Err(IdentifyError::Infeasible {
                    reason: "Clarabel found the constraints primal infeasible".to_owned(),
                });
            }
            other => {
                return Err(IdentifyError::Solver {
                    reason: format!("Clarabel stopped with status {other:?}"),
                });
            }
        }
        let active = (0..m).filter(|&j| solution.z[j] > solution.s[j]).collect();
        Ok((solution.x.clone(), active))
    }

    /// The minimiser with the constraints in `active` as equalities, and their multipliers
    /// (`>= 0` at the constrained optimum). `None` when the KKT matrix is singular.
    fn equality_constrained(&self, active: &[usize]) -> Option<(Vec<f64>, Vec<f64>)> {
        let p = self.h.nrows();
        let a = active.len();
        let mut kkt = DMatrix::<f64>::zeros(p + a, p + a);
        kkt.view_mut((0, 0), (p, p)).copy_from(&self.h);
        let mut rhs = DVector::<f64>::zeros(p + a);
        rhs.rows_mut(0, p).copy_from(&self.g);
        for (k, &j) in active.iter().enumerate() {
            for i in 0..p {
                kkt[(i, p + k)] = -self.rows[j][i];
                kkt[(p + k, i)] = self.rows[j][i];
            }
            rhs[p + k] = self.bounds[j];
        }
        let lu = kkt.full_piv_lu();
        let x = lu.solve(&rhs)?;
        if x.iter().any(|v| !v.is_finite()) {
            return None;
        }
        // Refuse a nearly singular system: its solution must reproduce the right-hand side.
        let residual = (lu_matrix_times(&self.h, &self.rows, active, &x) - &rhs).amax();
        if residual > 1e-9 * (1.0 + rhs.amax()) {
            return None;
        }
        Some((
            x.rows(0, p).iter().copied().collect(),
            x.rows(p, a).iter().copied().collect(),
        ))
    }

    /// The primal-dual active-set iteration from `active`.
    fn active_set(&self, mut active: Vec<usize>) -> Option<(Vec<f64>, Vec<usize>)> {
        let multiplier_tolerance = 1e-12 * (1.0 + self.g.amax());
        for _ in 0..ACTIVE_SET_ITERATIONS {
            let (z, multipliers) = self.equality_constrained(&active)?;
            if let Some((k, &mu)) = multipliers
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.total_cmp(b.1))
                && mu < -multiplier_tolerance
            {
                active.remove(k);
                continue;
            }
            let worst = (0..self.rows.len())
                .filter(|j| !active.contains(j))
                .map(|j| (j, dot(&self.rows[j], &z) - self.bounds[j]))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            match worst {
                Some((j, slack)) if slack < -1e-12 * self.margin => {
                    active.push(j);
                    active.sort_unstable();
                }
                _ => return Some((z, active)),
            }
        }
        None
    }
}

/// The KKT matrix of `active` times `x`, without forming it again.
fn lu_matrix_times(
    h: &DMatrix<f64>,
    rows: &[Vec<f64>],
    active: &[usize],
    x: &DVector<f64>,
) -> DVector<f64> {
    let p = h.nrows();
    let a = active.len();
    let z = x.rows(0, p);
    let mu = x.rows(p, a);
    let mut out = DVector::<f64>::zeros(p + a);
    let hz = h * z;
    for i in 0..p {
        let mut v = hz[i];
        for (k, &j) in active.iter().enumerate() {
            v -= rows[j][i] * mu[k];
        }
        out[i] = v;
    }
    for (k, &j) in active.iter().enumerate() {
        out[p + k] = rows[j].iter().zip(z.iter()).map(|(r, z)| r * z).sum();
    }
    out
}

//! The fitting problem: minimise the RMS model error of eq. (4) over the fitting span, under
//! linear constraints that make the identified model invertible.
//!
//! # Linear in the parameters
//! With the thresholds fixed, the MPIM output of eq. (4) (plus an optional constant `c`, the
//! output offset) is linear in its parameters:
//!
//! `y(t) = a1 x^3(t) + a2 x(t) + sum_i b_i F_{r_i}[x](t) + c = phi(t) . theta`.
//!
//! The regressors `phi(t)` are computed once with the core's play operators (eqs. (1)-(2)),
//! from zero memory at the first sample of the record. The columns are scaled to unit RMS and
//! the augmented matrix `[Phi | y]` of the fitting span is reduced by one Householder QR to a
//! small triangle `[R d; 0 rho]`, so that for every parameter vector
//!
//! `||Phi theta - y||^2 = ||R S^-1 theta - d||^2 + rho^2`
//!
//! and the RMS error costs `O(p^2)` to evaluate, whatever the number of samples. Least squares
//! and the particle swarm both minimise this one function ([`FitProblem::cost`]).
//!
//! # A zero threshold
//! When `r_1 = 0`, `F_0[x] = x` and the columns of `a2` and `b_1` are equal: only `a2 + b_1`
//! is determined by the data. The problem therefore has one parameter `s = a2 + b_1` and the
//! split is fixed by a rule:
//!
//! - plant models: `b_1 = -(3/2) a1 (x_lo^2 + x_hi^2)` over the input range (`b_1 = -1.5 a1` on
//!   `[0, 1]`). The plant model, IHC and exact WIHC are the same for every split; the delayed
//!   WIHC is not: its loop gain is `|3 a1 x^2 + b_1| / a2` (see `hystcomp_core::Wihc`), and
//!   this split makes its largest value over the range the smallest possible. Its gain
//!   around reversals (only the zero-threshold operators moving) is then bounded by the
//!   delayed-WIHC constraints below.
//! - inverse models: `b_1 = 0` (nothing depends on the split; Table 2 has `b_1 ~ 0`).
//!
//! # Constraints
//! Every row is `coefficients . theta >= margin`:
//!
//! - **branch slopes** (both directions): `a2 + 3 a1 x^2 + b_1 + ... + b_k >= margin` at every
//!   checkpoint `(k, x)` of [`hystcomp_core::branch_checkpoints`] over the normalised input
//!   range `[0, 1]`: exactly the points where the core's invertibility check looks, so the
//!   identified model always passes it (ERRATA item 5);
//! - **PI part** (plant models): `a2 + b_1 + ... + b_k >= margin` for every `k` from the number
//!   of zero thresholds to `n`, so that the analytic inverse of eq. (7) exists and IHC can be
//!   built;
//! - **delayed WIHC** (plant models): `a2 - (3 a1 x^2 + z) >= margin` and
//!   `a2 + (3 a1 x^2 + z) >= margin`, with `z` the sum of the zero-threshold weights, at the
//!   inputs where `x^2` is extreme: the two linear halves of `|3 a1 x^2 + z| < a2`, under which
//!   the delayed WIHC of eq. (9) contracts around reversals. They bound only that gain, not
//!   the worst case over every number of moving operators
//!   (`hystcomp_core::Mpim::delayed_wihc_loop_gain`) that decides whether the loop settles
//!   after a jump: a model meeting them may still ring when that gain exceeds 1.
//!
//! - **both delayed loops, for delayed compensation** (plant models, only when asked:
//!   [`FitProblem::with_delayed_loop_bound`], the command line's `--for-delayed`): the loop
//!   gains of `hystcomp_core::Mpim::delayed_wihc_loop_gain` and `delayed_ihc_loop_gain` at
//!   most a bound `rho < 1` at every branch checkpoint `(k, x)` (exactly the points where the
//!   core computes them, so the bound holds over the whole reachable state). With
//!   `S_k = b_1 + ... + b_k` each is linear in the parameters: the delayed WIHC's
//!   `|3 a1 x^2 + S_k| <= rho a2` is `rho a2 -+ (3 a1 x^2 + S_k) >= margin`, the delayed IHC's
//!   `|3 a1 x^2| <= rho (a2 + S_k)` (the PI part is positive by its own rows) is
//!   `rho (a2 + S_k) -+ 3 a1 x^2 >= margin`.
//!
//! Rows that coincide are kept once.
//!
//! # A higher-degree input polynomial
//! [`FitProblem::with_input_degree`] fits the odd input polynomial
//! `g(x) = a2 x + a1 x^3 + c_5 x^5 + ... + c_D x^D` (`D` odd, at most
//! [`MAX_FIT_INPUT_DEGREE`]; `D = 3` is the paper's cubic) instead of the cubic: one more column
//! `x^j` and one parameter `c_j` each, after `c` in `theta`. The constraints keep their form with
//! `3 a1 x^2` read as `h'(x) = 3 a1 x^2 + 5 c_5 x^4 + ...`, still linear in the parameters; since
//! the extremes of `h'` over an interval then lie where `g'' = 0`, which depends on the
//! parameters, every interval of the branch checkpoints is also sampled at
//! [`HIGHER_DEGREE_GRID`] inner points (the core's exact check of the identified model decides).
//!
//! # Extra regressors
//! [`FitProblem::with_extra_columns`] appends columns the caller computed (the creep link's
//! filtered outputs, see `crate::chain`) to the regressors, with one parameter each at the end
//! of `theta`: the fit stays one linear least-squares problem, jointly in the MPIM's
//! parameters and theirs, under the same constraints on the MPIM's. Each extra parameter `e_j`
//! is kept non-negative by the row `EXTRA_ROW_SCALE e_j >= margin`, i.e.
//! `e_j >= margin / EXTRA_ROW_SCALE` (1e-6 with the default margin): the rows share the
//! margin of the others, and the scale makes the bound zero for practical purposes.

use hystcomp_core::Shown;
use std::ops::Range;

use hystcomp_core::{OneSidedPlay, branch_checkpoints, branch_intervals};
use hystcomp_io::model_file::Direction;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::IdentifyError;
use crate::identification::parameter_count;

/// A constraint is **active** when its slack `a_j . theta - margin` is within this of 0
/// (normalised slope units, where the data's mean slope is 1), and **violated** when it is
/// below `-ACTIVE_TOLERANCE`: far below the default margin (1e-3), far above the rounding of
/// the exact active-set solve, and above the interior-point solver's distance from the
/// boundary when its answer is kept. The one definition of both counts
/// ([`FitProblem::active_count`], [`FitProblem::violated_count`]) and of the report's.
pub const ACTIVE_TOLERANCE: f64 = 1e-6;

/// The scale of the rows that keep the extra parameters non-negative (see the
/// [module documentation](self)).
pub const EXTRA_ROW_SCALE: f64 = 1000.0;

/// The highest degree of the input polynomial identification fits (odd degrees only:
/// [`FitProblem::with_input_degree`]); the core's [`hystcomp_core::MAX_INPUT_DEGREE`].
pub const MAX_FIT_INPUT_DEGREE: usize = hystcomp_core::MAX_INPUT_DEGREE;

/// Inner points per interval at which the constraints of a higher-degree input polynomial are
/// imposed besides the checkpoints of the cubic (see the [module documentation](self)).
pub const HIGHER_DEGREE_GRID: usize = 48;

/// The normalised input range the constraints are imposed on.
const INPUT_RANGE: (f64, f64) = (0.0, 1.0);

/// The parameters of one MPIM (eq. (4)) in normalised units, plus the output offset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Parameters {
    /// Cubic coefficient `a1`.
    pub a1: f64,
    /// Linear coefficient `a2`.
    pub a2: f64,
    /// Weights `b_i`, one per threshold.
    pub weights: Vec<f64>,
    /// The constant `c` added to the model output (0 unless the offset is fitted).
    pub offset: f64,
    /// The coefficients `c_5, c_7, ..., c_D` of a higher-degree odd input polynomial (empty
    /// for the paper's cubic; see [`FitProblem::with_input_degree`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub higher: Vec<f64>,
}

impl Parameters {
    /// The input polynomial's coefficients `[c_1, c_2, ..., c_D]` (`c_1 = a2`, `c_3 = a1`,
    /// even powers 0), for `hystcomp_core::InputPolynomial::new`.
    pub fn input_coefficients(&self) -> Vec<f64> {
        let degree = 3 + 2 * self.higher.len();
        let mut c = vec![0.0; degree];
        c[0] = self.a2;
        c[2] = self.a1;
        for (q, value) in self.higher.iter().enumerate() {
            c[4 + 2 * q] = *value;
        }
        c
    }

    /// The model these parameters describe (the cubic's own form when `higher` is empty).
    pub fn model(
        &self,
        thresholds: &[f64],
    ) -> Result<hystcomp_core::Mpim<f64, Vec<f64>>, hystcomp_core::CoreError> {
        if self.higher.is_empty() {
            hystcomp_core::Mpim::new(thresholds, &self.weights, self.a1, self.a2)
        } else {
            hystcomp_core::Mpim::with_input_polynomial(
                thresholds,
                &self.weights,
                hystcomp_core::InputPolynomial::new(&self.input_coefficients())?,
            )
        }
    }
}

/// What a constraint row stands for.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum ConstraintKind {
    /// `a2 + 3 a1 x^2 + b_1 + ... + b_k >= margin` (a branch-slope checkpoint).
    BranchSlope {
        /// Number of moving operators `k`.
        active_operators: usize,
        /// Normalised input `x`.
        input: f64,
    },
    /// `a2 + b_1 + ... + b_k >= margin` (eq. (7) exists).
    PiPart {
        /// Number of operators `k` in the prefix sum.
        active_operators: usize,
    },
    /// `a2 - sign (3 a1 x^2 + z) >= margin` (the delayed WIHC contracts around reversals;
    /// after a jump it may still ring, see the [module documentation](self)).
    DelayedWihc {
        /// Normalised input `x`.
        input: f64,
        /// `+1` or `-1`.
        sign: f64,
    },
    /// `rho a2 - sign (3 a1 x^2 + b_1 + ... + b_k) >= margin` (delayed WIHC) or
    /// `rho (a2 + b_1 + ... + b_k) - sign 3 a1 x^2 >= margin` (delayed IHC): the loop gain of
    /// that delayed compensator at most `rho` on the branch `(k, x)`
    /// ([`FitProblem::with_delayed_loop_bound`]).
    DelayedLoopGain {
        /// `"ihc"` or `"wihc"`.
        compensator: DelayedCompensator,
        /// Number of moving operators `k`.
        active_operators: usize,
        /// Normalised input `x`.
        input: f64,
        /// `+1` or `-1`.
        sign: f64,
    },
    /// `1 - sum_j j e_j w^(j - 1) >= margin`: the output map `psi(w) = w - sum_j e_j w^j`
    /// rises at the normalised output `w` ([`FitProblem::with_output_map`]).
    OutputMapSlope {
        /// Normalised output `w`.
        output: f64,
    },
    /// `EXTRA_ROW_SCALE e_j >= margin`: an extra regressor's parameter is non-negative.
    ExtraNonNegative {
        /// Which extra parameter (0-based).
        index: usize,
    },
}

/// Which one-sample-delayed compensator a [`ConstraintKind::DelayedLoopGain`] row bounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DelayedCompensator {
    /// The delayed IHC (eq. (5) with the previous drive in the cubic term).
    Ihc,
    /// The delayed WIHC (eq. (9)).
    Wihc,
}

/// One linear constraint `coefficients . theta + shift >= margin` on the problem's parameter
/// vector.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Constraint {
    /// One coefficient per entry of the parameter vector.
    pub coefficients: Vec<f64>,
    /// A constant added to the row (0 but for the output map's slopes, whose normalisation
    /// gives them a constant 1).
    #[serde(default)]
    pub shift: f64,
    /// What it stands for.
    pub kind: ConstraintKind,
}

impl Constraint {
    /// `coefficients . theta + shift - margin`: non-negative when the constraint holds.
    pub fn slack(&self, theta: &[f64], margin: f64) -> f64 {
        dot(&self.coefficients, theta) + self.shift - margin
    }
}

/// The normalised samples one problem is built from.
#[derive(Debug, Clone)]
pub struct ProblemData<'a> {
    /// The model input, normalised to `[0, 1]` over the record, every sample from the first
    /// (the operators run over all of them from zero memory).
    pub input: &'a [f64],
    /// The model output to fit, normalised, same length.
    pub output: &'a [f64],
    /// The samples (indices into `input`) the error is minimised over.
    pub fit: Range<usize>,
}

/// The fitting problem for one set of thresholds: the cost of any parameter vector and the
/// constraints it must meet. See the [module documentation](self).
///
/// The parameter vector `theta` is `[a1, s, b_j..., c]`: `s` is `a2`, or `a2 + b_1` when the
/// first threshold is 0 (then `b_1` is not an entry); the `b_j` follow for the other
/// thresholds; `c` (the output offset) is last when it is fitted.
#[derive(Debug, Clone)]
pub struct FitProblem {
    thresholds: Vec<f64>,
    direction: Direction,
    fit_offset: bool,
    /// `r_1 = 0`: `b_1` folded into `s`.
    folded: bool,
    /// Extra regressor columns, whose parameters end `theta`.
    extra: usize,
    /// The powers `2, ..., K` of the output map (before the extra parameters in `theta`).
    output_map: Vec<usize>,
    /// The powers `5, 7, ..., D` of a higher-degree input polynomial (after `c` in `theta`).
    higher: Vec<usize>,
    /// `b_1 = split * a1` when folded.
    split: f64,
    samples: usize,
    /// `R S^-1`: `||Phi theta - y|| = ||r_theta theta - d||` up to `rho`.
    r_theta: DMatrix<f64>,
    /// `R` of the column-scaled regressors (upper triangular).
    r_scaled: DMatrix<f64>,
    /// `S`: `theta = S z` (1 / RMS of each regressor column).
    column_scale: DVector<f64>,
    d: DVector<f64>,
    /// `rho^2`, the squared error no parameter vector can remove.
    residual_floor: f64,
    condition: f64,
    constraints: Vec<Constraint>,
    margin: f64,
    /// The bound on both delayed loops' gains, when constrained.
    delayed_loop_bound: Option<f64>,
}

impl FitProblem {
    /// Builds the problem: regressors with the core's play operators, column scaling, one QR,
    /// the condition number and the constraints (see the [module documentation](self)).
    ///
    /// `thresholds` must be strictly increasing in `[0, 1)` and `data.fit` a non-empty range of
    /// at least `dimension() + 1` samples within the record (checked).
    pub fn new(
        data: ProblemData<'_>,
        thresholds: &[f64],
        direction: Direction,
        fit_offset: bool,
        margin: f64,
    ) -> Result<Self, IdentifyError> {
        Self::with_extra_columns(data, thresholds, direction, fit_offset, margin, &[])
    }

    /// As [`FitProblem::new`], with `extra` regressor columns (each one value per sample of
    /// the record, like `data.input`) and one parameter each, unconstrained, at the end of
    /// `theta` (see the [module documentation](self)).
    pub fn with_extra_columns(
        data: ProblemData<'_>,
        thresholds: &[f64],
        direction: Direction,
        fit_offset: bool,
        margin: f64,
        extra: &[&[f64]],
    ) -> Result<Self, IdentifyError> {
        Self::build(data, thresholds, direction, fit_offset, margin, extra, 3, 1)
    }

    /// As [`FitProblem::with_input_degree`], with an output map of degree `map_degree`
    /// (1: none; at most [`MAX_OUTPUT_MAP_DEGREE`]) and `extra` columns: the model becomes
    /// `psi(y) = H[x] + c` with `psi(y) = y - e_2 y^2 - ... - e_K y^K` of the normalised output
    /// `y`, so that `y = H[x] + c + sum_j e_j y^j` stays linear in every parameter (an equation
    /// error, as Kuhnen's modified Prandtl-Ishlinskii operator `H = S^-1[Gamma]` is identified:
    /// Kuhnen 2003, Eur. J. Control 9 407-418, doi:10.3166/ejc.9.407-418). The `e_j` follow
    /// `c_5..` in `theta`, unconstrained in sign; `psi` is kept rising by the rows
    /// `1 - sum_j j e_j w^(j-1) >= margin` at [`OUTPUT_MAP_GRID`]` + 1` points of
    /// [`OUTPUT_MAP_RANGE`].
    #[allow(clippy::too_many_arguments)]
    pub fn with_output_map(
        data: ProblemData<'_>,
        thresholds: &[f64],
        direction: Direction,
        fit_offset: bool,
        margin: f64,
        input_degree: usize,
        map_degree: usize,
        extra: &[&[f64]],
    ) -> Result<Self, IdentifyError> {
        check_output_map_degree(map_degree)?;
        Self::build(
            data,
            thresholds,
            direction,
            fit_offset,
            margin,
            extra,
            input_degree,
            map_degree,
        )
    }

    /// The output map's `e_2, ..., e_K` of a parameter vector (empty without a map; see
    /// [`FitProblem::with_output_map`]).
    pub fn output_map_parameters<'t>(&self, theta: &'t [f64]) -> &'t [f64] {
        let end = theta.len() - self.extra;
        &theta[end - self.output_map.len()..end]
    }

    /// As [`FitProblem::new`], with the odd input polynomial of degree `degree` (3, 5, 7 or
    /// 9; 3 is the paper's cubic): one parameter `c_j` per power `j = 5, 7, ..., degree`,
    /// after `c` in `theta` (see the [module documentation](self)).
    pub fn with_input_degree(
        data: ProblemData<'_>,
        thresholds: &[f64],
        direction: Direction,
        fit_offset: bool,
        margin: f64,
        degree: usize,
    ) -> Result<Self, IdentifyError> {
        Self::build(
            data,
            thresholds,
            direction,
            fit_offset,
            margin,
            &[],
            degree,
            1,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn build(
        data: ProblemData<'_>,
        thresholds: &[f64],
        direction: Direction,
        fit_offset: bool,
        margin: f64,
        extra: &[&[f64]],
        degree: usize,
        map_degree: usize,
    ) -> Result<Self, IdentifyError> {
        check_input_degree(degree)?;
        let ProblemData { input, output, fit } = data;
        let folded = thresholds.first() == Some(&0.0);
        let higher: Vec<usize> = (5..=degree).step_by(2).collect();
        let output_map: Vec<usize> = (2..=map_degree).collect();
        let base = parameter_count(thresholds, fit_offset);
        let own = base + higher.len() + output_map.len();
        let p = own + extra.len();
        if let Some(column) = extra.iter().find(|c| c.len() != input.len()) {
            return Err(IdentifyError::InvalidOption {
                option: "extra regressor",
                value: format!("{} samples", column.len()),
                reason: format!(
                    "one value per sample of the record ({}) is needed",
                    input.len()
                ),
            });
        }
        if input.len() != output.len() || fit.end > input.len() || fit.len() < p + 1 {
            return Err(IdentifyError::InvalidOption {
                option: "fitting span",
                value: format!("{}..{} of {} samples", fit.start, fit.end, input.len()),
                reason: format!(
                    "a model with {p} parameters needs at least {} samples",
                    p + 1
                ),
            });
        }
        let rows = fit.len();

        // [Phi | y], column by column (each operator is independent: one pass per column).
        let mut phi = DMatrix::<f64>::zeros(rows, p + 1);
        let span = &input[fit.clone()];
        for (i, &x) in span.iter().enumerate() {
            phi[(i, 0)] = x * x * x;
            phi[(i, 1)] = x;
        }
        let first_free = usize::from(folded);
        for (j, &r) in thresholds.iter().enumerate().skip(first_free) {
            let column = 2 + j - first_free;
            let mut operator = OneSidedPlay::new(r, 0.0)?;
            let mut target = phi.column_mut(column);
            for (k, &x) in input[..fit.end].iter().enumerate() {
                let w = operator.step(x);
                if k >= fit.start {
                    target[k - fit.start] = w;
                }
            }
        }
        if fit_offset {
            phi.column_mut(base - 1).fill(1.0);
        }
        for (q, &power) in higher.iter().enumerate() {
            for (i, &x) in span.iter().enumerate() {
                phi[(i, base + q)] = x.powi(power as i32);
            }
        }
        let out_span = &output[fit.clone()];
        for (q, &power) in output_map.iter().enumerate() {
            for (i, &y) in out_span.iter().enumerate() {
                phi[(i, base + higher.len() + q)] = y.powi(power as i32);
            }
        }
        for (j, column) in extra.iter().enumerate() {
            phi.column_mut(own + j)
                .copy_from_slice(&column[fit.clone()]);
        }
        phi.column_mut(p).copy_from_slice(&output[fit.clone()]);

        // Scale each regressor column to unit RMS (theta = S z).
        let sqrt_rows = (rows as f64).sqrt();
        let mut column_scale = DVector::<f64>::from_element(p, 1.0);
        for j in 0..p {
            let norm = phi.column(j).norm();
            if norm > 0.0 && norm.is_finite() {
                column_scale[j] = sqrt_rows / norm;
                phi.column_mut(j).scale_mut(column_scale[j]);
            } else {
                column_scale[j] = 0.0;
            }
        }
        let r_aug = phi.qr().unpack_r();
        let r_scaled = r_aug.view((0, 0), (p, p)).into_owned();
        let d = r_aug.view((0, p), (p, 1)).column(0).into_owned();
        let residual_floor = r_aug[(p, p)] * r_aug[(p, p)];

        let condition = if column_scale.iter().any(|&s| s == 0.0) {
            f64::INFINITY
        } else {
            let singular = r_scaled.clone().singular_values();
            let max = singular.max();
            let min = singular.min();
            if min > 0.0 { max / min } else { f64::INFINITY }
        };
        let mut r_theta = r_scaled.clone();
        for j in 0..p {
            let s = column_scale[j];
            r_theta
                .column_mut(j)
                .scale_mut(if s > 0.0 { 1.0 / s } else { 0.0 });
        }

        let split = match direction {
            Direction::Plant => {
                let (lo, hi) = INPUT_RANGE;
                let (m_lo, m_hi) = square_range(lo, hi);
                -1.5 * (m_lo + m_hi)
            }
            Direction::Inverse => 0.0,
        };
        let mut problem = FitProblem {
            thresholds: thresholds.to_vec(),
            direction,
            fit_offset,
            folded,
            extra: extra.len(),
            output_map,
            higher,
            split,
            samples: rows,
            r_theta,
            r_scaled,
            column_scale,
            d,
            residual_floor,
            condition,
            constraints: Vec::new(),
            margin,
            delayed_loop_bound: None,
        };
        problem.constraints = problem.build_constraints();
        Ok(problem)
    }

    /// The same problem, with both delayed loops' gains constrained to at most `bound` over
    /// the whole reachable state (see the [module documentation](self)): for plant models
    /// meant for one-sample-delayed compensation. `bound` must lie in `(0, 1)`; inverse models
    /// (no delayed loop) are returned unchanged.
    pub fn with_delayed_loop_bound(mut self, bound: f64) -> Result<Self, IdentifyError> {
        if !(bound > 0.0 && bound < 1.0) {
            return Err(IdentifyError::InvalidOption {
                option: "delayed loop bound",
                value: Shown(bound).to_string(),
                reason: "the delayed loops' gain bound must lie strictly between 0 and 1"
                    .to_owned(),
            });
        }
        if self.direction != Direction::Plant {
            return Ok(self);
        }
        self.delayed_loop_bound = Some(bound);
        self.constraints = self.build_constraints();
        Ok(self)
    }

    /// The same problem with the extra parameters' first differences penalised (Tikhonov
    /// smoothing; Hansen 2010, *Discrete Inverse Problems*, SIAM, ch. 4): the cost becomes
    /// `(||Phi theta - y||^2 + N lambda^2 sum_j (e_j+1 - e_j)^2) / N` over the `N` fitted
    /// samples, so `lambda` weighs a difference of the extra parameters against the RMS error
    /// in normalised output units. For the creep link's weights at log-spaced time constants
    /// this pulls the spectrum towards a flat one, the logarithmic creep that piezo stacks show
    /// (Jung & Gweon 2000, doi:10.1063/1.1150570), where a short record cannot tell neighbouring
    /// time constants apart. `lambda` must be finite and non-negative (0 returns the problem
    /// unchanged); the condition number is that of the smoothed problem.
    pub fn with_extra_smoothness(mut self, lambda: f64) -> Result<Self, IdentifyError> {
        if !(lambda.is_finite() && lambda >= 0.0) {
            return Err(IdentifyError::InvalidOption {
                option: "creep smoothness",
                value: Shown(lambda).to_string(),
                reason: "give a finite, non-negative weight".to_owned(),
            });
        }
        if lambda == 0.0 || self.extra < 2 {
            return Ok(self);
        }
        let p = self.dimension();
        let penalties = self.extra - 1;
        // [R d; 0 rho; P 0] has the same normal equations as the whole penalised system: its
        // QR gives the new R, d and rho.
        let mut stacked = DMatrix::<f64>::zeros(p + 1 + penalties, p + 1);
        stacked.view_mut((0, 0), (p, p)).copy_from(&self.r_scaled);
        stacked.view_mut((0, p), (p, 1)).copy_from(&self.d);
        stacked[(p, p)] = self.residual_floor.sqrt();
        let weight = lambda * (self.samples as f64).sqrt();
        let first = p - self.extra;
        for k in 0..penalties {
            let (a, b) = (first + k, first + k + 1);
            stacked[(p + 1 + k, a)] = -weight * self.column_scale[a];
            stacked[(p + 1 + k, b)] = weight * self.column_scale[b];
        }
        let r_aug = stacked.qr().unpack_r();
        self.r_scaled = r_aug.view((0, 0), (p, p)).into_owned();
        self.d = r_aug.view((0, p), (p, 1)).column(0).into_owned();
        self.residual_floor = r_aug[(p, p)] * r_aug[(p, p)];
        let singular = self.r_scaled.clone().singular_values();
        let (max, min) = (singular.max(), singular.min());
        self.condition = if min > 0.0 { max / min } else { f64::INFINITY };
        let mut r_theta = self.r_scaled.clone();
        for j in 0..p {
            let s = self.column_scale[j];
            r_theta
                .column_mut(j)
                .scale_mut(if s > 0.0 { 1.0 / s } else { 0.0 });
        }
        self.r_theta = r_theta;
        Ok(self)
    }

    /// The bound on both delayed loops' gains, when the problem constrains them.
    pub fn delayed_loop_bound(&self) -> Option<f64> {
        self.delayed_loop_bound
    }

    /// The number of entries of the parameter vector.
    pub fn dimension(&self) -> usize {
        self.r_theta.ncols()
    }

    /// The names of the parameter vector's entries (`a1`, `a2` or `a2+b1`, `b2`, ..., `c`).
    pub fn parameter_names(&self) -> Vec<String> {
        let mut names = vec![
            "a1".to_owned(),
            if self.folded { "a2+b1" } else { "a2" }.to_owned(),
        ];
        for j in usize::from(self.folded)..self.thresholds.len() {
            names.push(format!("b{}", j + 1));
        }
        if self.fit_offset {
            names.push("c".to_owned());
        }
        names.extend(self.higher.iter().map(|j| format!("c{j}")));
        names.extend(self.output_map.iter().map(|j| format!("m{j}")));
        names.extend((1..=self.extra).map(|j| format!("e{j}")));
        names
    }

    /// The number of extra regressors (see [`FitProblem::with_extra_columns`]).
    pub fn extra_count(&self) -> usize {
        self.extra
    }

    /// The extra regressors' parameters: the last [`FitProblem::extra_count`] entries of
    /// `theta`.
    pub fn extra_parameters<'t>(&self, theta: &'t [f64]) -> &'t [f64] {
        &theta[theta.len() - self.extra..]
    }

    /// The thresholds `r_i`.
    pub fn thresholds(&self) -> &[f64] {
        &self.thresholds
    }

    /// The direction the model maps (decides the constraints and the zero-threshold split).
    pub fn direction(&self) -> Direction {
        self.direction
    }

    /// Whether the output offset `c` is a parameter.
    pub fn fits_offset(&self) -> bool {
        self.fit_offset
    }

    /// The entry of `theta` holding the output offset `c`, when it is fitted.
    pub fn offset_index(&self) -> Option<usize> {
        self.fit_offset
            .then(|| parameter_count(&self.thresholds, true) - 1)
    }

    /// The number of samples of the fitting span.
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// The condition number of the column-scaled regressor matrix (infinite when a column is
    /// zero or the columns are dependent).
    pub fn condition_number(&self) -> f64 {
        self.condition
    }

    /// The constraints, each `coefficients . theta >= margin`.
    pub fn constraints(&self) -> &[Constraint] {
        &self.constraints
    }

    /// The smallest branch slope every constraint demands.
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// The RMS model error over the fitting span, in normalised output units, of the
    /// parameter vector `theta` (NaN when `theta` has the wrong length). The one cost function
    /// both solvers minimise.
    pub fn cost(&self, theta: &[f64]) -> f64 {
        if theta.len() != self.dimension() {
            return f64::NAN;
        }
        let p = self.dimension();
        let mut sum = self.residual_floor;
        for i in 0..p {
            let mut e = -self.d[i];
            for (j, t) in theta.iter().enumerate().skip(i) {
                e += self.r_theta[(i, j)] * t;
            }
            sum += e * e;
        }
        (sum / self.samples as f64).sqrt()
    }

    /// The total violation `sum_j max(0, margin - a_j . theta)` of the constraints (0 when
    /// `theta` meets them all), in normalised slope units.
    pub fn violation(&self, theta: &[f64]) -> f64 {
        self.constraints
            .iter()
            .map(|c| (-c.slack(theta, self.margin)).max(0.0))
            .sum()
    }

    /// The smallest `a_j . theta - margin` over the constraints (>= 0 when all are met).
    pub fn smallest_slack(&self, theta: &[f64]) -> f64 {
        self.constraints
            .iter()
            .map(|c| c.slack(theta, self.margin))
            .fold(f64::INFINITY, f64::min)
    }

    /// The number of **active** constraints at `theta`: those that hold with equality within
    /// [`ACTIVE_TOLERANCE`], `|a_j . theta - margin| <= ACTIVE_TOLERANCE`. Violated ones (see
    /// [`FitProblem::violated_count`]) are not counted.
    pub fn active_count(&self, theta: &[f64]) -> usize {
        self.constraints
            .iter()
            .filter(|c| c.slack(theta, self.margin).abs() <= ACTIVE_TOLERANCE)
            .count()
    }

    /// The number of constraints **violated** at `theta` by more than [`ACTIVE_TOLERANCE`]:
    /// `a_j . theta - margin < -ACTIVE_TOLERANCE`.
    pub fn violated_count(&self, theta: &[f64]) -> usize {
        self.constraints
            .iter()
            .filter(|c| c.slack(theta, self.margin) < -ACTIVE_TOLERANCE)
            .count()
    }

    /// The model parameters of a parameter vector (the zero-threshold split applied).
    pub fn parameters(&self, theta: &[f64]) -> Parameters {
        let full = self.to_full(theta);
        let n = self.thresholds.len();
        Parameters {
            a1: full[0],
            a2: full[1],
            weights: full[2..2 + n].to_vec(),
            offset: if self.fit_offset { full[2 + n] } else { 0.0 },
            higher: full[2 + n + usize::from(self.fit_offset)..].to_vec(),
        }
    }

    /// The parameter vector of model parameters (the inverse of [`FitProblem::parameters`] up
    /// to the split: with a zero threshold only `a2 + b_1` is kept; extra parameters 0).
    pub fn theta(&self, parameters: &Parameters) -> Vec<f64> {
        let mut theta = vec![parameters.a1, parameters.a2];
        let mut weights = parameters.weights.iter();
        if self.folded {
            theta[1] += weights.next().copied().unwrap_or(0.0);
        }
        theta.extend(weights);
        if self.fit_offset {
            theta.push(parameters.offset);
        }
        for q in 0..self.higher.len() {
            theta.push(parameters.higher.get(q).copied().unwrap_or(0.0));
        }
        theta.resize(theta.len() + self.output_map.len() + self.extra, 0.0);
        theta
    }

    /// The upper-triangular factor `R` of the column-scaled regressors and the right-hand side
    /// `d`: `||Phi S z - y||^2 = ||R z - d||^2 + rho^2` with `theta = S z`.
    pub(crate) fn scaled_system(&self) -> (&DMatrix<f64>, &DVector<f64>, &DVector<f64>) {
        (&self.r_scaled, &self.d, &self.column_scale)
    }

    /// Full parameters `[a1, a2, b_1..b_n, (c)]` of a parameter vector.
    fn to_full(&self, theta: &[f64]) -> Vec<f64> {
        let n = self.thresholds.len();
        let mut full = Vec::with_capacity(n + 3);
        let a1 = theta[0];
        full.push(a1);
        if self.folded {
            let b1 = self.split * a1;
            full.push(theta[1] - b1);
            full.push(b1);
            full.extend_from_slice(&theta[2..2 + n - 1]);
        } else {
            full.push(theta[1]);
            full.extend_from_slice(&theta[2..2 + n]);
        }
        let base = parameter_count(&self.thresholds, self.fit_offset);
        if self.fit_offset {
            full.push(theta[base - 1]);
        }
        full.extend_from_slice(&theta[base..base + self.higher.len()]);
        full
    }

    /// A constraint row on the full parameters `[a1, a2, b_1..b_n, (c)]`, as a row on `theta`.
    fn reduce_row(&self, full: &[f64]) -> Vec<f64> {
        let p = self.dimension();
        let n = self.thresholds.len();
        let mut row = vec![0.0; p];
        row[0] = full[0];
        row[1] = full[1];
        if self.folded {
            // a2 = s - split a1, b1 = split a1.
            row[0] += self.split * (full[2] - full[1]);
            row[2..2 + n - 1].copy_from_slice(&full[3..3 + n - 1]);
        } else {
            row[2..2 + n].copy_from_slice(&full[2..2 + n]);
        }
        let base = parameter_count(&self.thresholds, self.fit_offset);
        let first = 2 + n + usize::from(self.fit_offset);
        let count = self.higher.len();
        row[base..base + count].copy_from_slice(&full[first..first + count]);
        row
    }

    /// The number of entries of the full parameter vector `[a1, a2, b_1..b_n, (c), c_5..]`.
    fn full_len(&self) -> usize {
        self.thresholds.len() + 2 + usize::from(self.fit_offset) + self.higher.len()
    }

    /// Writes `h'(x) / sign` into a full row: `3 x^2` for `a1` and `j x^(j - 1)` for each
    /// higher coefficient `c_j`, times `scale`.
    fn remainder_slope_row(&self, full: &mut [f64], x: f64, scale: f64) {
        full[0] = scale * 3.0 * x * x;
        let first = 2 + self.thresholds.len() + usize::from(self.fit_offset);
        for (q, &j) in self.higher.iter().enumerate() {
            full[first + q] = scale * j as f64 * x.powi(j as i32 - 1);
        }
    }

    /// The checkpoints `(k, x)` where the constraints are imposed: the cubic's exact ones, and
    /// with a higher-degree polynomial [`HIGHER_DEGREE_GRID`] inner points of every interval.
    fn checkpoints(&self) -> Vec<(usize, f64)> {
        let (lo, hi) = INPUT_RANGE;
        let mut points = Vec::new();
        branch_checkpoints(&self.thresholds, lo, hi, |k, x| points.push((k, x)));
        if !self.higher.is_empty() {
            branch_intervals(&self.thresholds, lo, hi, |k, p, q| {
                for i in 1..=HIGHER_DEGREE_GRID {
                    let t = i as f64 / (HIGHER_DEGREE_GRID + 1) as f64;
                    points.push((k, p + (q - p) * t));
                }
            });
        }
        points
    }

    fn build_constraints(&self) -> Vec<Constraint> {
        let n = self.thresholds.len();
        let full_len = self.full_len();
        let (lo, hi) = INPUT_RANGE;
        let mut rows: Vec<Constraint> = Vec::new();
        let push = |full: Vec<f64>, kind: ConstraintKind, rows: &mut Vec<Constraint>| {
            let coefficients = self.reduce_row(&full);
            let duplicate = rows.iter().any(|c| {
                c.coefficients
                    .iter()
                    .zip(&coefficients)
                    .all(|(a, b)| (a - b).abs() <= 1e-12 * (1.0 + a.abs()))
            });
            if !duplicate {
                rows.push(Constraint {
                    coefficients,
                    shift: 0.0,
                    kind,
                });
            }
        };
        // Branch slopes: a2 + 3 a1 x^2 + b_1 + ... + b_k.
        for (k, x) in self.checkpoints() {
            let mut full = vec![0.0; full_len];
            self.remainder_slope_row(&mut full, x, 1.0);
            full[1] = 1.0;
            full[2..2 + k].fill(1.0);
            push(
                full,
                ConstraintKind::BranchSlope {
                    active_operators: k,
                    input: x,
                },
                &mut rows,
            );
        }
        if self.direction == Direction::Plant {
            let always = self.thresholds.iter().take_while(|r| **r <= 0.0).count();
            // PI part, eq. (7): a2 + b_1 + ... + b_k.
            for k in always..=n {
                let mut full = vec![0.0; full_len];
                full[1] = 1.0;
                full[2..2 + k].fill(1.0);
                push(
                    full,
                    ConstraintKind::PiPart {
                        active_operators: k,
                    },
                    &mut rows,
                );
            }
            // Delayed WIHC: a2 -+ (3 a1 x^2 + z) at the inputs where x^2 is extreme.
            let mut inputs = vec![lo, hi];
            if lo < 0.0 && 0.0 < hi {
                inputs.push(0.0);
            }
            if !self.higher.is_empty() {
                inputs.extend(
                    (1..=HIGHER_DEGREE_GRID)
                        .map(|i| lo + (hi - lo) * i as f64 / (HIGHER_DEGREE_GRID + 1) as f64),
                );
            }
            for x in inputs {
                for sign in [1.0, -1.0] {
                    let mut full = vec![0.0; full_len];
                    self.remainder_slope_row(&mut full, x, -sign);
                    full[1] = 1.0;
                    full[2..2 + always].fill(-sign);
                    push(
                        full,
                        ConstraintKind::DelayedWihc { input: x, sign },
                        &mut rows,
                    );
                }
            }
        }
        if let (Direction::Plant, Some(rho)) = (self.direction, self.delayed_loop_bound) {
            for (k, x) in self.checkpoints() {
                for sign in [1.0, -1.0] {
                    // Delayed WIHC: rho a2 - sign (3 a1 x^2 + S_k).
                    let mut full = vec![0.0; full_len];
                    self.remainder_slope_row(&mut full, x, -sign);
                    full[1] = rho;
                    full[2..2 + k].fill(-sign);
                    push(
                        full,
                        ConstraintKind::DelayedLoopGain {
                            compensator: DelayedCompensator::Wihc,
                            active_operators: k,
                            input: x,
                            sign,
                        },
                        &mut rows,
                    );
                    // Delayed IHC: rho (a2 + S_k) - sign 3 a1 x^2.
                    let mut full = vec![0.0; full_len];
                    self.remainder_slope_row(&mut full, x, -sign);
                    full[1] = rho;
                    full[2..2 + k].fill(rho);
                    push(
                        full,
                        ConstraintKind::DelayedLoopGain {
                            compensator: DelayedCompensator::Ihc,
                            active_operators: k,
                            input: x,
                            sign,
                        },
                        &mut rows,
                    );
                }
            }
        }
        let p = self.dimension();
        for index in 0..self.extra {
            let mut coefficients = vec![0.0; p];
            coefficients[p - self.extra + index] = EXTRA_ROW_SCALE;
            rows.push(Constraint {
                coefficients,
                shift: 0.0,
                kind: ConstraintKind::ExtraNonNegative { index },
            });
        }
        // The output map rises over the fitted outputs [0, 1] (and a little beyond).
        let first = p - self.extra - self.output_map.len();
        for i in 0..=OUTPUT_MAP_GRID {
            let w = OUTPUT_MAP_RANGE.0
                + (OUTPUT_MAP_RANGE.1 - OUTPUT_MAP_RANGE.0) * i as f64 / OUTPUT_MAP_GRID as f64;
            if self.output_map.is_empty() {
                break;
            }
            let mut coefficients = vec![0.0; p];
            for (q, &j) in self.output_map.iter().enumerate() {
                coefficients[first + q] = -(j as f64) * w.powi(j as i32 - 1);
            }
            rows.push(Constraint {
                coefficients,
                shift: 1.0,
                kind: ConstraintKind::OutputMapSlope { output: w },
            });
        }
        rows
    }
}

/// The highest degree of the output map [`FitProblem::with_output_map`] fits.
pub const MAX_OUTPUT_MAP_DEGREE: usize = hystcomp_core::MAX_OUTPUT_MAP_DEGREE;

/// The normalised outputs the output map's slope constraints cover: the fitted range `[0, 1]`
/// and a tenth beyond each end.
pub const OUTPUT_MAP_RANGE: (f64, f64) = (-0.1, 1.1);

/// Intervals of [`OUTPUT_MAP_RANGE`] at whose ends the output map's slope is constrained.
pub const OUTPUT_MAP_GRID: usize = 60;

/// Refuses an output map degree identification cannot fit: 1 (none) to
/// [`MAX_OUTPUT_MAP_DEGREE`].
pub(crate) fn check_output_map_degree(degree: usize) -> Result<(), IdentifyError> {
    if (1..=MAX_OUTPUT_MAP_DEGREE).contains(&degree) {
        return Ok(());
    }
    Err(IdentifyError::InvalidOption {
        option: "output map degree",
        value: degree.to_string(),
        reason: format!(
            "the output map psi(y) = y - e2 y^2 - ... is a polynomial of degree 1 (none) to \
             {MAX_OUTPUT_MAP_DEGREE}"
        ),
    })
}

/// Refuses an input polynomial degree identification cannot fit: odd, 3 to
/// [`MAX_FIT_INPUT_DEGREE`].
pub(crate) fn check_input_degree(degree: usize) -> Result<(), IdentifyError> {
    if degree % 2 == 1 && (3..=MAX_FIT_INPUT_DEGREE).contains(&degree) {
        return Ok(());
    }
    Err(IdentifyError::InvalidOption {
        option: "input degree",
        value: degree.to_string(),
        reason: format!(
            "the input polynomial g(x) = a2 x + a1 x^3 + c5 x^5 + ... is odd, of degree 3 (the \
             paper's cubic), 5, 7 or 9 (at most {MAX_FIT_INPUT_DEGREE})"
        ),
    })
}

/// The smallest and largest `x^2` for `x` in `[lo, hi]`.
fn square_range(lo: f64, hi: f64) -> (f64, f64) {
    let max = (lo * lo).max(hi * hi);
    let min = if lo <= 0.0 && 0.0 <= hi {
        0.0
    } else {
        (lo * lo).min(hi * hi)
    };
    (min, max)
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

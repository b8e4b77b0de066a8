//! Identification of modified Prandtl-Ishlinskii models (MPIM, eq. (4) of Gu & Zhu,
//! *Smart Mater. Struct.* **23** (2014) 095029, doi:10.1088/0964-1726/23/9/095029) from
//! measured samples, the way the paper does (section 4.2), and better.
//!
//! - [`identify`]: (voltage, displacement) samples in, a [`ModelFile`](hystcomp_io::model_file::ModelFile)
//!   and a [`FitReport`] out, as a **plant** model (voltage to displacement, for IHC and WIHC)
//!   or an **inverse** model (displacement to voltage, for DIHC, section 3.3).
//! - [`crossval()`]: identify both on one record; on another, report the forward prediction
//!   error and the offline inverse replay error of every compensator.
//!
//! # One problem, two solvers
//! With the thresholds fixed, the MPIM is linear in `(a1, a2, b_i)`. [`FitProblem`] holds the
//! RMS model error of any parameter vector and the linear constraints it must meet:
//!
//! - both directions: the model is **strictly increasing along every branch** (every branch
//!   slope `a2 + 3 a1 x^2 + b_1 + ... + b_k >= margin` over the fitted input range), so that
//!   it is invertible (the core's `check_invertible`, ERRATA item 5);
//! - plant models, **beyond that**: the play-operator part `a2 + b_1 + ... + b_k >= margin`
//!   for every `k`, so that the analytic inverse of eq. (7) exists and IHC can be built, and
//!   `|3 a1 x^2 + b_1| <= a2 - margin` over the range, so that the one-sample-delayed WIHC of
//!   eq. (9) contracts around reversals (where only the zero-threshold operators move). After
//!   a jump more operators move and it may still ring when its full loop gain
//!   (`Mpim::delayed_wihc_loop_gain`, the worst case over every number of moving operators)
//!   exceeds 1; this fit does not bound that gain, and `hystcomp compensate` reports it. A
//!   model that is increasing along every branch may violate these; the constrained optimum
//!   is then (slightly) worse than the best merely invertible model.
//!
//! Before solving, the fitted samples' displacement must rise with the voltage (Pearson
//! correlation at least [`MIN_CORRELATION`]); after, the RMS error must not exceed
//! [`IdentifyOptions::max_fit_rms_percent`] (10 % by default). Two [`Solver`]s minimise it:
//!
//! - [`LeastSquares`] (`ls`, the default): the exact global optimum for those thresholds
//!   (QR, then a QP with Clarabel when a constraint binds, then an exact active-set solve);
//! - [`ParticleSwarm`] (`pso`): the paper's method (its ref. \[39\]), seeded and reproducible,
//!   with an optional least-squares polish.
//!
//! Solvers report progress to an [`Observer`] (the command line attaches a progress bar);
//! they never print.
//!
//! ```
//! use hystcomp_identify::{identify, IdentifyOptions};
//! use hystcomp_core::Mpim;
//!
//! // A record from Table 1 of the paper: a decaying 1 Hz sine at 200 Hz, 0..10 V -> um.
//! let thresholds = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];
//! let weights = [0.2313, 0.3059, 0.0155, 0.0752, 0.0683, 0.0252, 0.0035, 0.0094, 0.0264, 0.0032];
//! let mut table1: Mpim<f64, Vec<f64>> = Mpim::new(&thresholds, &weights, -0.1569, 0.4603)?;
//! let voltage: Vec<f64> = (0..4000)
//!     .map(|k| {
//!         let t = k as f64 / 200.0;
//!         5.0 - 5.0 * (-t / 10.0).exp() * (2.0 * std::f64::consts::PI * t).cos()
//!     })
//!     .collect();
//! let (lo, hi) = voltage.iter().fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
//! let displacement: Vec<f64> =
//!     voltage.iter().map(|v| 75.0 * table1.step((v - lo) / (hi - lo))).collect();
//!
//! let fit = identify(&voltage, &displacement, &IdentifyOptions::default())?;
//! assert!(fit.report.fit.rms_percent < 1e-6);
//! // Normalised by the record's displacement range instead of 75 um: rescale to compare.
//! let k = fit.model.output.scale / 75.0;
//! assert!((k * fit.model.a1 - -0.1569).abs() < 1e-6);
//! assert!((k * (fit.model.a2 + fit.model.weights[0]) - (0.4603 + 0.2313)).abs() < 1e-6);
//! assert!((k * fit.model.weights[1] - 0.3059).abs() < 1e-6);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

pub mod chain;
mod chain_crossval;
pub mod creep_holds;
pub mod crossval;
pub mod dynamics;
mod error;
mod identification;
pub mod ls;
mod options;
pub mod order;
pub mod predict;
pub mod problem;
pub mod pso;
mod report;
mod solver;
pub mod warmup;

pub use chain::{
    ChainIdentification, ChainOptions, ChainReport, Contribution, CreepFit, CreepOptions,
    FittedSpan, identify_chain, identify_inverse_chain,
};
pub use chain_crossval::{ChainCrossValidation, crossval_chain};
pub use crossval::{
    CrossValidation, CrossvalOptions, CrossvalReport, Record, Replay, TestRanges, TestStart,
    Validation, crossval, predict_test, validate_models, validate_models_from,
};
pub use dynamics::{DynamicsFit, DynamicsOptions, Mode, fit_dynamics};
pub use error::IdentifyError;
pub use identification::{Identification, identify, identify_observed};
pub use ls::LeastSquares;
pub use options::{
    AUTO_WARMUP_LEVEL, DEFAULT_DELAYED_LOOP_BOUND, DEFAULT_MARGIN, DEFAULT_MAX_CONDITION,
    DEFAULT_MAX_FIT_RMS_PERCENT, DEFAULT_OPERATORS, IdentifyOptions, MAX_OPERATORS,
    MAX_REGRESSOR_VALUES, MIN_CORRELATION, Method, OutputOffset, SAMPLES_PER_PARAMETER, Thresholds,
    Warmup,
};
pub use order::{
    AUTO_HOLDOUT, AUTO_OPERATOR_CANDIDATES, OrderCandidate, OrderSelection, select_operators,
};
pub use predict::{Prediction, predict};
pub use problem::{
    Constraint, ConstraintKind, DelayedCompensator, FitProblem, HIGHER_DEGREE_GRID,
    MAX_FIT_INPUT_DEGREE, Parameters, ProblemData,
};
pub use pso::{
    CONSTRICTION_ACCELERATION, CONSTRICTION_INERTIA, DEFAULT_ITERATIONS, DEFAULT_PARTICLES,
    MAX_ITERATIONS, MAX_PARTICLES, ParticleSwarm, PsoBounds, PsoOptions, Topology,
};
pub use report::{
    DelayedConstraint, DelayedGains, ErrorStats, FitReport, SampleCounts, SignalRange, WarmupReport,
};
pub use solver::{NoObserver, Observer, Progress, Solution, Solver};

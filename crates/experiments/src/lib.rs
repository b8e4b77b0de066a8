//! The comparative study of Gu & Zhu (2014), "Comparative experiments regarding approaches to
//! feedforward hysteresis compensation for piezoceramic actuators", Smart Mater. Struct. 23 095029
//! (doi:10.1088/0964-1726/23/9/095029), section 4, run on a simulated stage.
//!
//! This crate owns the trajectories, the tracking indices (D1), (D2) and (12), the study itself,
//! its figures and the HTML report. It holds no model maths of its own: models, inverses and
//! compensators come from `hystcomp-core`, identification from `hystcomp-identify` and the stage
//! from `hystcomp-stage`.

#![warn(missing_docs)]

pub mod beyond;
mod beyond_report;
pub mod chain_excitation;
pub mod duration;
pub mod excitation;
pub mod figures;
pub mod full;
pub mod learning;
mod learning_report;
pub mod learning_study;
pub mod reference;
pub mod report;
pub mod signals;
pub mod slew_drive;
pub mod speed;
pub mod study;
pub mod study_report;
pub mod trajectory;

/// The tracking indices of section 4.3 (the crate `hystcomp-indices`, re-exported).
pub use hystcomp_indices as indices;

pub use indices::{IndexError, TrackingIndices};
pub use reference::Reference;
pub use study::{Study, StudyError, StudyObserver, StudyOptions, run_study};
pub use study_report::{RunMeta, StudySummary, summarize, write_outputs};
pub use trajectory::MultisineTrajectory;

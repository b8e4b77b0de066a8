//! Learning from repetition: iterative learning control (ILC) of the reference a hystcomp
//! compensator follows, for motions repeated many times (raster scans, periodic mirror
//! patterns, lithography passes).
//!
//! # The law: learning in the desired-position domain
//! A model-based feedforward `v = C[y_d]` (the exact IHC or WIHC of the plant model, with the
//! chain's creep and vibration inverses when the model has them) leaves a residual set by the
//! model's mismatch; what repeats from trial to trial can be learned. Following Leang &
//! Devasia, who learn through an inverse hysteresis model so that the learning acts on a
//! nearly linear system (K. K. Leang, S. Devasia, "Design of hysteresis-compensating
//! iterative learning control for piezo-positioners: application to atomic force
//! microscopes", Mechatronics 16 (2006) 141-158, doi:10.1016/j.mechatronics.2005.11.006), the
//! learner never touches the drive directly: it learns the **reference** `r` the compensator
//! is asked to follow,
//!
//! ```text
//! r_0 = y_d,    r_k+1 = sat( r_k + Q[ L[ e_k ] ] ),    e_k = y_d - y_k,    v_k = C[r_k]
//! ```
//!
//! with `L = gamma z^m` (a gain and a phase lead of `m` samples, the "phase-lead" learning
//! law of R. W. Longman, "Iterative learning control and repetitive control for engineering
//! practice", Int. J. Control 73 (2000) 930-954, doi:10.1080/002071700405905) and `Q` a
//! zero-phase low-pass, `Q(f) = 1 / (1 + (f / f_c)^(2n))` (a Butterworth filter run forwards
//! and backwards, as Longman recommends), both applied in the frequency domain over the whole
//! trial ([`filter`]). `sat` clamps the reference into the displacements the model reaches
//! within the drive limits (anti-windup). Because `P[C[r]] = r` for the model `P`, the stage
//! maps `r` to `y = G[r] + d` with `G` close to identity below the stage's resonance (or at
//! every frequency the model's vibration link inverts) and `d` the repeating mismatch; the
//! error then evolves as `e_k+1 = (1 - Q L G) e_k` and contracts at every frequency where
//! `|1 - gamma Q(f) G(f) e^(j 2 pi f m / f_s)| < 1` (D. A. Bristow, M. Tharayil, A. G.
//! Alleyne, "A survey of iterative learning control", IEEE Control Syst. Mag. 26(3) (2006)
//! 96-114, doi:10.1109/MCS.2006.1636313, eq. (13)). With `0 < gamma < 2`, `Q <= 1` and `G`
//! within 90 degrees of the lead, that holds; `Q`'s cut-off keeps the learning below where the
//! phase is not known (the resonance, when the model has no vibration link: the default
//! cut-off is then a hundredth of the sample rate; with one, the top of the band the link was
//! identified on: the default is then a tenth of the sample rate, which keeps `Q` at 4 % by
//! the 1.5 kHz where the study's vibration excitation ends at 10 kHz. A quarter, tried first,
//! diverged on the built-in stage from the `full` pipeline: the paper's trajectory stopped by
//! the guard at trial 3, the 100 Hz raster at trial 2; measured cut-offs on the raster: 300 Hz
//! stalls at 0.76 %, 600 Hz creeps to 0.26 % by trial 20, 1 kHz reaches 0.053 %, 1.5 kHz
//! grows again after trial 2).
//!
//! The reference is the state between trials, and it is recoverable from a drive: the model
//! run forward over the drive of trial `k` gives `r_k` back ([`Learner::resume`]). So any
//! drive can start the learning (IHC, WIHC, the delayed loops, DIHC, a linear gain), and the
//! command line keeps no state but the drive files.
//!
//! # Guarantees
//! - **Limits**: every drive is the exact inverse's output for a reference within the reachable
//!   range, clamped to the limits once more: it never leaves them and is never NaN.
//! - **Divergence guard**: a trial whose e_rms exceeds `divergence_factor` (1.5 by default)
//!   times the best trial's stops the learning; [`Learner::drive`] is then the best trial's
//!   drive (the last good one), and [`Status::Diverged`] says which trials.
//! - **Noise is not amplified trial after trial.** A white sensor noise `n_k` of variance
//!   `s^2` enters the reference as `r_k+1 = r_k + gamma Q n_k + ...`; where the update
//!   contracts, the reference's noise follows `d_k+1 = (1 - g) d_k + g n_k` per frequency
//!   (`g = gamma Q`), whose variance settles at `g / (2 - g) s^2` instead of growing with `k`.
//!   Averaged over the band this is [`LearningLaw::stationary_noise_ratio`]: with the defaults
//!   (`gamma` 0.8, `f_c` a hundredth of the sample rate, order 4) about 0.013, so the learned
//!   reference carries about 11 % of the sensor's RMS noise and the measured error settles at
//!   the noise floor (`sqrt(1 + 0.013)` times it). Measured: `tests/noise.rs`.
//!
//! # Trials
//! A trial is a record of `N` samples aligned sample by sample: the desired trajectory, the
//! drive sent and the measured response. **Periodic** (the default): the record is one period
//! (or whole periods) of a periodic motion in its periodic state, e.g. the last period of a
//! wave table played several times; filters wrap around, and drives are computed in the
//! compensator's periodic state. **Finite**: a motion repeated from rest, filtered with zeros
//! beyond its ends. ILC assumes every trial starts from the same state (Bristow et al. 2006);
//! on a stage that creeps, start each trial from the same rest, or expect the learning to lag
//! the drift by one trial.
//!
//! ```
//! use hystcomp_io::model_file::ModelFile;
//! use hystcomp_learn::{Learner, LearningOptions};
//!
//! let model = ModelFile::load(std::path::Path::new("../../models/table1-plant.json"))?;
//! let desired: Vec<f64> = (0..1000)
//!     .map(|k| 35.0 + 20.0 * (2.0 * std::f64::consts::PI * k as f64 / 1000.0).sin())
//!     .collect();
//! let mut learner = Learner::new(&model, &desired, LearningOptions::new(1000.0))?;
//! // A "stage" the model gets 5 % wrong: it moves 0.95 times what the model says.
//! let mut plant = model.clone();
//! plant.output.scale *= 0.95;
//! plant.output.offset *= 0.95;
//! let mut e_rms = Vec::new();
//! for _ in 0..5 {
//!     let drive = learner.drive();
//!     let three: Vec<f64> = drive.iter().chain(drive).chain(drive).copied().collect();
//!     let measured = plant.predict(&three)?[1000..2000].to_vec(); // its periodic state
//!     e_rms.push(learner.update(&measured)?.indices.e_rms_percent);
//! }
//! assert!(e_rms[4] < e_rms[0] / 100.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

pub mod amplifier;
mod error;
pub mod filter;
mod learner;
mod options;
pub mod slew;

pub use amplifier::{AmplifierSpec, AntiWindup, AntiWindupLaw};
pub use error::LearnError;
pub use filter::LearningFilter;
pub use learner::{Learner, LearningLaw, Status, Update};
pub use options::{
    DEFAULT_DIVERGENCE_FACTOR, DEFAULT_FILTER_ORDER, DEFAULT_GAIN, Inverse, LearningOptions,
    MAX_DIVERGENCE_FACTOR, MAX_FILTER_ORDER, MAX_GAIN, MAX_LEAD_SAMPLES, MAX_TRIAL_SAMPLES,
};

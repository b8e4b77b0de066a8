//! A compensator built from a model file, in physical units: desired position in (e.g. um),
//! drive voltage out (e.g. V). The scaling lives here, once, for the command line, the
//! bindings and the study; the control law is the core's.

use std::fmt;
use std::str::FromStr;

use hystcomp_core::{
    ChainCompensator, Compensator, CoreError, Diagnostics, Dihc, Ihc, MapSide, MappedCompensator,
    Mpim, OutputLimits, SolveMode, Wihc,
};
use serde::{Deserialize, Serialize};

use crate::model_file::{Direction, ModelFile, Scale};

/// The compensators of the toolkit (section 3 of the paper, with the exact, the delayed and the
/// guarded delayed solution of the implicit laws).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// IHC, eqs. (5)-(8), implicit equation solved exactly each sample.
    Ihc,
    /// IHC with `v(t - Ts)` in the cubic term (real-time Simulink style); refused on a model
    /// whose delayed loop gain reaches 1 unless allowed explicitly ([`UnstableDelay::Allow`]).
    IhcDelayed,
    /// WIHC, eq. (9), implicit equation solved exactly each sample.
    Wihc,
    /// WIHC with `H[v](t - Ts)` (real-time Simulink style); refused on a model whose delayed
    /// loop gain reaches 1 unless allowed explicitly ([`UnstableDelay::Allow`]).
    WihcDelayed,
    /// DIHC, eq. (10): an inverse model evaluated on the desired trajectory.
    Dihc,
    /// The delayed IHC with its guard: an under-relaxed update that cannot oscillate on any
    /// model ([`hystcomp_core::SolveMode::DelayedGuarded`]).
    IhcGuarded,
    /// The delayed WIHC with its guard: only the input polynomial's remainder delayed and
    /// under-relaxed, the operators solved exactly; it cannot oscillate on any model
    /// ([`hystcomp_core::SolveMode::DelayedGuarded`]).
    WihcGuarded,
}

/// What to do with a delayed method (`ihc-delayed`, `wihc-delayed`) on a model whose delayed
/// loop gain over the drive limits is 1 or more, so that the loop can ring between the limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum UnstableDelay {
    /// Refuse it ([`hystcomp_core::CoreError::DelayedLoopUnstable`]): the default.
    #[default]
    Refuse,
    /// Build it anyway (the command line's `--allow-unstable-delay`): the drive still never
    /// leaves its limits, but may ring between them after a jump in the desired position.
    Allow,
}

impl Method {
    /// Every method: the paper's five in its order, then the guarded delayed loops.
    pub const ALL: [Method; 7] = [
        Method::Ihc,
        Method::IhcDelayed,
        Method::Wihc,
        Method::WihcDelayed,
        Method::Dihc,
        Method::IhcGuarded,
        Method::WihcGuarded,
    ];

    /// The name used on the command line and in files: `ihc`, `ihc-delayed`, ...
    pub fn name(self) -> &'static str {
        match self {
            Method::Ihc => "ihc",
            Method::IhcDelayed => "ihc-delayed",
            Method::Wihc => "wihc",
            Method::WihcDelayed => "wihc-delayed",
            Method::Dihc => "dihc",
            Method::IhcGuarded => "ihc-guarded",
            Method::WihcGuarded => "wihc-guarded",
        }
    }

    /// How the implicit law is solved: exactly, with the loop broken by one sample (refused at
    /// a loop gain of 1 or more), or with the guarded delayed loop (DIHC has no implicit law;
    /// it reports `Exact`).
    pub fn solve_mode(self) -> SolveMode {
        match self {
            Method::IhcDelayed | Method::WihcDelayed => SolveMode::Delayed,
            Method::IhcGuarded | Method::WihcGuarded => SolveMode::DelayedGuarded,
            _ => SolveMode::Exact,
        }
    }

    /// `true` for the plain delayed loops (`ihc-delayed`, `wihc-delayed`), which
    /// [`UnstableDelay`] concerns.
    pub fn is_plain_delayed(self) -> bool {
        self.solve_mode() == SolveMode::Delayed
    }

    /// The exact method of the same family (`ihc` for every IHC, `wihc` for every WIHC).
    pub fn exact(self) -> Method {
        match self {
            Method::Ihc | Method::IhcDelayed | Method::IhcGuarded => Method::Ihc,
            Method::Wihc | Method::WihcDelayed | Method::WihcGuarded => Method::Wihc,
            Method::Dihc => Method::Dihc,
        }
    }

    /// The guarded delayed method of the same family (`None` for DIHC).
    pub fn guarded(self) -> Option<Method> {
        match self.exact() {
            Method::Ihc => Some(Method::IhcGuarded),
            Method::Wihc => Some(Method::WihcGuarded),
            _ => None,
        }
    }

    /// The direction of model the method needs: a plant model for IHC and WIHC, an inverse
    /// model for DIHC.
    pub fn needs(self) -> Direction {
        match self {
            Method::Dihc => Direction::Inverse,
            _ => Direction::Plant,
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = CompensatorError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Method::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| CompensatorError::UnknownMethod(s.to_string()))
    }
}

/// Why a compensator could not be built from a model file.
#[derive(Debug, Clone, PartialEq)]
pub enum CompensatorError {
    /// Not one of `ihc`, `ihc-delayed`, `wihc`, `wihc-delayed`, `dihc`, `ihc-guarded`,
    /// `wihc-guarded`.
    UnknownMethod(String),
    /// The method needs the other direction of model.
    WrongDirection {
        /// The method asked for.
        method: Method,
        /// The direction of the model given.
        found: Direction,
    },
    /// The output limits are not finite and increasing.
    InvalidLimits {
        /// Lower limit, physical units.
        min: f64,
        /// Upper limit, physical units.
        max: f64,
        /// The unit.
        unit: String,
    },
    /// The core refused the model (not invertible, ...).
    Core(CoreError),
    /// The inverse's band is not finite or not between 0 and the Nyquist frequency.
    InvalidBand {
        /// The band asked for, Hz.
        band_hz: f64,
        /// The model's Nyquist frequency, Hz.
        nyquist_hz: f64,
    },
}

impl fmt::Display for CompensatorError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CompensatorError::UnknownMethod(s) => write!(
                f,
                "unknown method {s:?}; choose one of ihc, ihc-delayed, wihc, wihc-delayed, dihc, \
                 ihc-guarded, wihc-guarded"
            ),
            CompensatorError::WrongDirection { method, found } => write!(
                f,
                "{method} needs {} model, but this model file maps {found} ({}); {}",
                match method.needs() {
                    Direction::Plant => "a plant",
                    Direction::Inverse => "an inverse",
                },
                match found {
                    Direction::Plant => "voltage to displacement",
                    Direction::Inverse => "displacement to voltage",
                },
                match method.needs() {
                    Direction::Plant => {
                        "identify a plant model (hystcomp identify --direction plant) or use --method dihc"
                    }
                    Direction::Inverse => {
                        "identify an inverse model (hystcomp identify --direction inverse) or use ihc or wihc"
                    }
                }
            ),
            CompensatorError::InvalidLimits { min, max, unit } => write!(
                f,
                "output limits [{min}, {max}] {unit} are invalid: both must be finite and min < max"
            ),
            CompensatorError::Core(e) => write!(f, "{e}"),
            CompensatorError::InvalidBand {
                band_hz,
                nyquist_hz,
            } => write!(
                f,
                "the vibration inverse's band {band_hz} Hz is invalid: give a frequency between \
                 0 and the model's Nyquist frequency {nyquist_hz} Hz"
            ),
        }
    }
}

impl std::error::Error for CompensatorError {}

impl From<CoreError> for CompensatorError {
    fn from(e: CoreError) -> Self {
        CompensatorError::Core(e)
    }
}

/// Any of the paper's compensators, behind `dyn`.
type Hysteresis = Box<dyn Compensator<f64> + Send>;

/// The hysteresis compensator alone, or the chain around it.
enum Inner {
    Plain(Hysteresis),
    Chain(Box<ChainCompensator<f64, Vec<f64>, Hysteresis>>),
}

impl Inner {
    fn get(&self) -> &dyn Compensator<f64> {
        match self {
            Inner::Plain(c) => c.as_ref(),
            Inner::Chain(c) => c.as_ref(),
        }
    }

    fn get_mut(&mut self) -> &mut dyn Compensator<f64> {
        match self {
            Inner::Plain(c) => c.as_mut(),
            Inner::Chain(c) => c.as_mut(),
        }
    }
}

/// A compensator from a model file, in physical units.
///
/// `step(desired)` takes the desired position in the model's displacement unit and returns the
/// drive voltage in its voltage unit, always within [`ScaledCompensator::limits`], never NaN
/// (see [`hystcomp_core::Compensator`]).
pub struct ScaledCompensator {
    inner: Inner,
    method: Method,
    /// Physical meaning of the desired position (the compensator's input).
    desired: Scale,
    /// Physical meaning of the control (the compensator's output).
    control: Scale,
    limits: (f64, f64),
    /// The worst-case gain of the family's delayed loop over the limits (IHC and WIHC).
    delayed_loop_gain: Option<f64>,
    /// The under-relaxation of the family's guarded delayed loop (IHC and WIHC).
    guard_relaxation: Option<f64>,
    /// DIHC: the desired positions the inverse model accepts, physical units.
    desired_range: Option<(f64, f64)>,
    /// The vibration inverse's preview, samples (0 without a vibration link): `step`'s output
    /// lags its input by it.
    preview: usize,
    /// With a vibration link: the band, Hz, a known trajectory is low-passed to before the
    /// offline inversion ([`ScaledCompensator::with_inverse_band`]).
    inverse_band_hz: Option<f64>,
    /// The chain's sample rate, Hz (`None` without creep or vibration links).
    sample_rate_hz: Option<f64>,
}

impl fmt::Debug for ScaledCompensator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ScaledCompensator")
            .field("method", &self.method)
            .field("desired", &self.desired)
            .field("control", &self.control)
            .field("limits", &self.limits)
            .finish()
    }
}

impl ScaledCompensator {
    /// Builds `method` from `model`. `limits` are the drive limits in the model's voltage unit;
    /// without them, the voltage range the model was identified on (a plant model's
    /// `input_range`; an inverse model's normalised output range [0, 1]).
    ///
    /// A model with creep or vibration links (format version 2) gives the chain inverted in
    /// reverse order (`hystcomp_core::ChainCompensator`): the vibration inverse with the
    /// preview an offline inversion needs ([`ScaledCompensator::with_preview`] chooses
    /// another), the creep inverse, then `method`. It runs at the model's `sample_rate_hz`.
    /// `input_range`; an inverse model's normalised output range [0, 1]). A plain delayed
    /// method on a model whose delayed loop can oscillate (gain of 1 or more) is refused; see
    /// [`ScaledCompensator::with_unstable_delay`].
    pub fn new(
        model: &ModelFile,
        method: Method,
        limits: Option<(f64, f64)>,
    ) -> Result<Self, CompensatorError> {
        Self::with_options(model, method, limits, None, UnstableDelay::Refuse)
    }

    /// As [`ScaledCompensator::new`], with the vibration inverse's preview `preview` samples
    /// (`None`: the preview for a negligible cut of its anti-causal series; ignored without a
    /// vibration link). Streaming, `step`'s output then lags its input by the preview.
    pub fn with_preview(
        model: &ModelFile,
        method: Method,
        limits: Option<(f64, f64)>,
        preview: Option<usize>,
    ) -> Result<Self, CompensatorError> {
        Self::with_options(model, method, limits, preview, UnstableDelay::Refuse)
    }

    /// As [`ScaledCompensator::new`], saying what to do with a plain delayed method
    /// (`ihc-delayed`, `wihc-delayed`) whose loop gain over the limits is 1 or more:
    /// [`UnstableDelay::Refuse`] (as `new`) or [`UnstableDelay::Allow`], the explicit override.
    /// The other methods ignore it.
    pub fn with_unstable_delay(
        model: &ModelFile,
        method: Method,
        limits: Option<(f64, f64)>,
        unstable: UnstableDelay,
    ) -> Result<Self, CompensatorError> {
        Self::with_options(model, method, limits, None, unstable)
    }

    /// [`ScaledCompensator::with_preview`] and [`ScaledCompensator::with_unstable_delay`] in
    /// one.
    pub fn with_options(
        model: &ModelFile,
        method: Method,
        limits: Option<(f64, f64)>,
        preview: Option<usize>,
        unstable: UnstableDelay,
    ) -> Result<Self, CompensatorError> {
        if model.direction != method.needs() {
            return Err(CompensatorError::WrongDirection {
                method,
                found: model.direction,
            });
        }
        let (desired, control) = match model.direction {
            Direction::Plant => (model.output.clone(), model.input.clone()),
            Direction::Inverse => (model.input.clone(), model.output.clone()),
        };
        let default_normalised = match model.direction {
            Direction::Plant => (model.input_range[0], model.input_range[1]),
            Direction::Inverse => (0.0, 1.0),
        };
        let (min, max) = limits.unwrap_or((
            control.to_physical(default_normalised.0),
            control.to_physical(default_normalised.1),
        ));
        if !(min.is_finite() && max.is_finite() && min < max) {
            return Err(CompensatorError::InvalidLimits {
                min,
                max,
                unit: control.unit.clone(),
            });
        }
        let normalised = OutputLimits::new(control.normalise(min), control.normalise(max))?;
        let mpim: Mpim<f64, Vec<f64>> = model.core_model()?;
        let mode = match (method.solve_mode(), unstable) {
            (SolveMode::Delayed, UnstableDelay::Allow) => SolveMode::DelayedAllowUnstable,
            (mode, _) => mode,
        };
        let mut delayed_loop_gain = None;
        let mut guard_relaxation = None;
        let map = model.output_map.as_ref().map(|m| m.map()).transpose()?;
        // An inverse model's map acts on its output, the voltage: its DIHC works within the
        // mapped limits and maps back (hystcomp_core::MappedCompensator).
        let inner_limits = match (&map, model.direction) {
            (Some(m), Direction::Inverse) => {
                MappedCompensator::<f64, Hysteresis>::mapped_limits(m, normalised)?
            }
            _ => normalised,
        };
        let inner: Box<dyn Compensator<f64> + Send> = match method {
            Method::Ihc | Method::IhcDelayed | Method::IhcGuarded => {
                let ihc = Ihc::<f64, Vec<f64>>::new(&mpim, normalised, mode)?;
                delayed_loop_gain = Some(ihc.delayed_loop_gain().gain);
                guard_relaxation = Some(ihc.guard_relaxation());
                Box::new(ihc)
            }
            Method::Wihc | Method::WihcDelayed | Method::WihcGuarded => {
                let wihc = Wihc::<f64, Vec<f64>>::new(&mpim, normalised, mode)?;
                delayed_loop_gain = Some(wihc.delayed_loop_gain().gain);
                guard_relaxation = Some(wihc.guard_relaxation());
                Box::new(wihc)
            }
            Method::Dihc => Box::new(Dihc::<f64, Vec<f64>>::new(
                &mpim,
                model.input_range[0],
                model.input_range[1],
                inner_limits,
            )?),
        };
        let inner: Hysteresis = match map {
            Some(m) => {
                let side = match model.direction {
                    Direction::Plant => MapSide::Desired,
                    Direction::Inverse => MapSide::Control,
                };
                Box::new(MappedCompensator::new(inner, m, side, normalised))
            }
            None => inner,
        };
        let mut preview_samples = 0;
        let inner = if model.has_links() {
            let rate = model.sample_rate_hz.unwrap_or(1.0);
            let vibration = match &model.vibration {
                Some(v) => {
                    let p = match preview {
                        Some(p) => p,
                        None => v.needed_preview()?,
                    };
                    preview_samples = p;
                    Some(v.inverse(p)?)
                }
                None => None,
            };
            let creep = match &model.creep {
                Some(c) => Some(c.normalised(&desired).link(rate)?.inverse()),
                None => None,
            };
            Inner::Chain(Box::new(ChainCompensator::new(vibration, creep, inner)))
        } else {
            Inner::Plain(inner)
        };
        // A chain's inverse model takes the creep-free displacement: its range is not the
        // desired position's.
        let desired_range = (method == Method::Dihc && !model.has_links()).then(|| {
            let (a, b) = (
                desired.to_physical(model.input_range[0]),
                desired.to_physical(model.input_range[1]),
            );
            (a.min(b), a.max(b))
        });
        Ok(ScaledCompensator {
            inner,
            method,
            desired,
            control,
            limits: (min, max),
            delayed_loop_gain,
            guard_relaxation,
            desired_range,
            preview: preview_samples,
            inverse_band_hz: None,
            sample_rate_hz: model.sample_rate_hz,
        })
    }

    /// With a vibration link: the whole known trajectory [`ScaledCompensator::process`] (and
    /// [`ScaledCompensator::band_limited`]) inverts is first low-passed with zero phase at
    /// `band_hz` (`hystcomp_io::band_limit`; `None`: inverted whole, the default). Meant as
    /// the top of the band the vibration link was identified on: above it the link's inverse
    /// extrapolates and asks drive the amplifier may not have. Streaming ([`step`]) is not
    /// filtered. Refuses a band that is not finite or not between 0 and the Nyquist frequency
    /// of the model's sample rate; ignored without a vibration link.
    ///
    /// [`step`]: ScaledCompensator::step
    pub fn with_inverse_band(mut self, band_hz: Option<f64>) -> Result<Self, CompensatorError> {
        if let (Some(band), Some(rate)) = (band_hz, self.sample_rate_hz)
            && !(band.is_finite() && band > 0.0 && band < 0.5 * rate)
        {
            return Err(CompensatorError::InvalidBand {
                band_hz: band,
                nyquist_hz: 0.5 * rate,
            });
        }
        self.inverse_band_hz = band_hz.filter(|_| self.has_vibration());
        Ok(self)
    }

    fn has_vibration(&self) -> bool {
        matches!(&self.inner, Inner::Chain(c) if c.vibration().is_some())
    }

    /// The band of [`ScaledCompensator::with_inverse_band`], if one applies.
    pub fn inverse_band_hz(&self) -> Option<f64> {
        self.inverse_band_hz
    }

    /// The known trajectory `desired` as the offline inversion inverts it: low-passed with
    /// zero phase at [`ScaledCompensator::inverse_band_hz`] when a band applies (and every
    /// sample is finite: a non-finite one is left for the compensator to report), else as
    /// it is.
    pub fn band_limited(&self, desired: &[f64]) -> Vec<f64> {
        match (self.inverse_band_hz, self.sample_rate_hz) {
            (Some(band), Some(rate)) if desired.iter().all(|d| d.is_finite()) => {
                crate::band_limit::zero_phase_low_pass(desired, band, rate)
            }
            _ => desired.to_vec(),
        }
    }

    /// With a creep link: takes the stage as having rested long at the displacement
    /// `desired_at_rest` (physical units) instead of relaxed at the creep link's origin, for a
    /// record that starts in the middle of a history (cross-validation on a measured record).
    /// Call after a reset and before the first sample; no effect without a creep link.
    pub fn settle_creep(&mut self, desired_at_rest: f64) {
        if let Inner::Chain(c) = &mut self.inner {
            c.settle_creep(self.desired.normalise(desired_at_rest));
        }
    }

    /// The vibration inverse's preview, samples (0 without a vibration link): [`step`]'s
    /// output lags its input by this many samples.
    ///
    /// [`step`]: ScaledCompensator::step
    pub fn preview(&self) -> usize {
        self.preview
    }

    /// The method.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The drive limits `(min, max)`, in [`ScaledCompensator::control_unit`].
    pub fn limits(&self) -> (f64, f64) {
        self.limits
    }

    /// For the IHC and WIHC methods: the worst-case small-signal gain of the family's
    /// one-sample-delayed loop over the drive limits (whatever the method's own mode), see
    /// [`hystcomp_core::Ihc::delayed_loop_gain`] (`max |g'(x) - a2| / (a2 + b_1 + ... + b_k)`)
    /// and [`hystcomp_core::Wihc::delayed_loop_gain`] (`max |g'(x) - a2 + b_1 + ... + b_k| /
    /// a2`). At or above 1 the plain delayed loop can ring between the limits after a jump in
    /// the desired position (and is refused unless allowed); the exact and the guarded ones do
    /// not. `None` for DIHC.
    pub fn delayed_loop_gain(&self) -> Option<f64> {
        self.delayed_loop_gain
    }

    /// For the IHC and WIHC methods: the under-relaxation of the family's guarded delayed loop
    /// on this model and limits, in `(0, 1]` (1: no under-relaxation). `None`
    /// for DIHC.
    pub fn guard_relaxation(&self) -> Option<f64> {
        self.guard_relaxation
    }

    /// For `dihc`: the range of desired positions (physical units, increasing) the inverse
    /// model was identified on; DIHC clamps the desired position into it (eq. (10)). `None` for
    /// the other methods, and for an inverse model with creep or vibration links (its
    /// hysteresis link's input is the creep-free displacement, whose range the desired
    /// positions' is not).
    pub fn desired_range(&self) -> Option<(f64, f64)> {
        self.desired_range
    }

    /// The unit of the desired position (the input).
    pub fn desired_unit(&self) -> &str {
        &self.desired.unit
    }

    /// The unit of the drive voltage (the output).
    pub fn control_unit(&self) -> &str {
        &self.control.unit
    }

    /// Back to the initial state (operators' memory zero, eq. (1)).
    pub fn reset(&mut self) {
        self.inner.get_mut().reset();
    }

    /// One sample: the drive for the desired position `desired` (physical units). With a
    /// vibration link the drive returned is for the desired position fed
    /// [`ScaledCompensator::preview`] samples earlier (streaming with a preview).
    #[inline]
    pub fn step(&mut self, desired: f64) -> f64 {
        self.step_held(desired).0
    }

    /// [`ScaledCompensator::step`], and whether it held its previous drive for `desired`:
    /// when its normalised value is not finite (NaN or infinite, or finite but too large for
    /// the model's scale, which overflows to infinity when normalised), or, with creep or
    /// vibration links, too large for them to follow (`hystcomp_core::ChainCompensator`):
    /// whenever the compensator counts the sample as not finite.
    #[inline]
    pub fn step_held(&mut self, desired: f64) -> (f64, bool) {
        let normalised = self.desired.normalise(desired);
        let inner = self.inner.get_mut();
        let before = inner.diagnostics().non_finite;
        let v = self.control.to_physical(inner.step(normalised));
        let held = inner.diagnostics().non_finite != before;
        // The normalised limits map onto the physical ones up to rounding; clamp once more so
        // that the physical output never leaves them, not even by an ulp.
        (v.clamp(self.limits.0, self.limits.1), held)
    }

    /// A whole signal; refuses slices of different lengths. With a vibration link the signal
    /// is a whole known trajectory and the drive is aligned with it (`control[k]` for
    /// `desired[k]`, the preview's lag removed): the trajectory is held at its last value for
    /// the preview's samples after its end, and the drive of the preview's first samples
    /// (before the trajectory starts, for a trajectory at rest at its first value) is dropped.
    pub fn process(
        &mut self,
        desired: &[f64],
        control: &mut [f64],
    ) -> Result<(), CompensatorError> {
        self.process_held(desired, control).map(|_| ())
    }

    /// [`ScaledCompensator::process`], and how many of the trajectory's samples it held its
    /// previous drive for (see [`ScaledCompensator::step_held`]), with the index of the first.
    pub fn process_held(
        &mut self,
        desired: &[f64],
        control: &mut [f64],
    ) -> Result<(usize, Option<usize>), CompensatorError> {
        if desired.len() != control.len() {
            return Err(CompensatorError::Core(CoreError::LengthMismatch {
                what: "control",
                expected: desired.len(),
                found: control.len(),
            }));
        }
        let filtered;
        let desired = if self.inverse_band_hz.is_some() {
            filtered = self.band_limited(desired);
            &filtered[..]
        } else {
            desired
        };
        let Some(&last) = desired.last() else {
            return Ok((0, None));
        };
        let p = self.preview;
        let (mut count, mut first) = (0, None);
        for (k, d) in desired
            .iter()
            .chain(std::iter::repeat_n(&last, p))
            .enumerate()
        {
            let (v, held) = self.step_held(*d);
            if held && k < desired.len() {
                count += 1;
                first = first.or(Some(k));
            }
            if k >= p {
                control[k - p] = v;
            }
        }
        Ok((count, first))
    }

    /// Saturated (desired position out of reach), loop-saturated (drive clamped by a delayed
    /// loop although the position was reachable) and non-finite samples since the last reset
    /// (see [`hystcomp_core::Diagnostics`]).
    pub fn diagnostics(&self) -> Diagnostics {
        self.inner.get().diagnostics()
    }
}

//! Rate-independent hysteresis of the piezo stack: the displacement (creep-free, before the
//! stage's dynamics) as a functional of the amplifier voltage.
//!
//! Two models are built in, chosen by [`HysteresisModel`]:
//! - [`PreisachHysteresis`] (the default): a Preisach model with a smooth, asymmetric density,
//!   evaluated with the memory of dominant extrema and an Everett-function table;
//! - [`BoucWenHysteresis`]: an asymmetric Bouc-Wen model, integrated in closed form.
//!
//! A third, [`MpimHysteresis`], reads an MPIM from a model file: for tests of the chain only.
//!
//! A further model plugs in as one more variant of [`Hysteresis`] implementing
//! [`RateIndependentHysteresis`], one more [`HysteresisModel`] value and one more arm in
//! [`Hysteresis::from_config`].

mod bouc_wen;
mod mpim;
mod preisach;

pub use bouc_wen::BoucWenHysteresis;
pub use mpim::MpimHysteresis;
pub use preisach::PreisachHysteresis;

use crate::config::{HysteresisConfig, HysteresisModel};
use crate::error::StageError;

/// A rate-independent hysteresis: the output depends on the sequence of input values only,
/// never on when they came.
pub trait RateIndependentHysteresis {
    /// Moves the input to `voltage_v` (V) and returns the displacement, um. A non-finite
    /// voltage leaves the state and the input unchanged.
    fn displacement_um(&mut self, voltage_v: f64) -> f64;

    /// Back to the relaxed state at 0 V.
    fn reset(&mut self);
}

/// The hysteresis model of a stage, one variant per model.
#[derive(Debug, Clone)]
pub enum Hysteresis {
    /// A Preisach model.
    Preisach(PreisachHysteresis),
    /// An asymmetric Bouc-Wen model.
    BoucWen(BoucWenHysteresis),
    /// An MPIM from a model file (tests only).
    Mpim(Box<MpimHysteresis>),
}

impl Hysteresis {
    /// Builds the model the configuration selects; `amplifier_gain` (V/V) is needed by the MPIM,
    /// whose model file takes the command voltage.
    pub fn from_config(
        config: &HysteresisConfig,
        amplifier_gain: f64,
    ) -> Result<Hysteresis, StageError> {
        Ok(match config.model {
            HysteresisModel::Preisach => {
                Hysteresis::Preisach(PreisachHysteresis::new(&config.preisach)?)
            }
            HysteresisModel::BoucWen => {
                Hysteresis::BoucWen(BoucWenHysteresis::new(&config.bouc_wen)?)
            }
            HysteresisModel::Mpim => {
                let path = config.mpim.model_file.as_deref().ok_or_else(|| {
                    StageError::invalid(
                        "hysteresis.mpim.model_file",
                        "a model file path when hysteresis.model = \"mpim\"",
                        "nothing",
                    )
                })?;
                Hysteresis::Mpim(Box::new(MpimHysteresis::new(path, amplifier_gain)?))
            }
        })
    }
}

impl RateIndependentHysteresis for Hysteresis {
    fn displacement_um(&mut self, voltage_v: f64) -> f64 {
        match self {
            Hysteresis::Preisach(h) => h.displacement_um(voltage_v),
            Hysteresis::BoucWen(h) => h.displacement_um(voltage_v),
            Hysteresis::Mpim(h) => h.displacement_um(voltage_v),
        }
    }

    fn reset(&mut self) {
        match self {
            Hysteresis::Preisach(h) => h.reset(),
            Hysteresis::BoucWen(h) => h.reset(),
            Hysteresis::Mpim(h) => h.reset(),
        }
    }
}

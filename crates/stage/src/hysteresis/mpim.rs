//! An MPIM read from a model file as the stage's hysteresis: **for tests only**.

use hystcomp_core::Mpim;
use hystcomp_io::model_file::{Direction, ModelFile};

use super::RateIndependentHysteresis;
use crate::error::StageError;

/// The modified Prandtl-Ishlinskii model of eq. (4) of Gu & Zhu (2014), from a plant model file
/// (command voltage in V -> displacement in um), driven by the amplifier voltage divided by the
/// amplifier gain. For tests of the chain only: a compensator judged on the very model it
/// inverts proves nothing about real stages.
#[derive(Debug, Clone)]
pub struct MpimHysteresis {
    file: ModelFile,
    model: Mpim<f64, Vec<f64>>,
    amplifier_gain: f64,
    last_um: f64,
}

impl MpimHysteresis {
    /// Loads the model file at `path`; `amplifier_gain` converts the amplifier voltage back
    /// into the command voltage the model takes.
    pub fn new(path: &std::path::Path, amplifier_gain: f64) -> Result<Self, StageError> {
        let file = ModelFile::load(path).map_err(|e| StageError::FieldFile {
            field: "hysteresis.mpim.model_file",
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        if file.direction != Direction::Plant {
            return Err(StageError::invalid(
                "hysteresis.mpim.model_file",
                "a plant model (direction \"plant\": voltage in, displacement out)",
                path.display(),
            ));
        }
        let model = file.model().map_err(|e| StageError::FieldFile {
            field: "hysteresis.mpim.model_file",
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let mut h = MpimHysteresis {
            file,
            model,
            amplifier_gain,
            last_um: 0.0,
        };
        h.reset();
        Ok(h)
    }
}

impl RateIndependentHysteresis for MpimHysteresis {
    fn displacement_um(&mut self, voltage_v: f64) -> f64 {
        if voltage_v.is_finite() {
            let x = self.file.normalise_input(voltage_v / self.amplifier_gain);
            self.last_um = self.file.output_to_physical(self.model.step(x));
        }
        self.last_um
    }

    fn reset(&mut self) {
        self.model.reset();
        let x0 = self.file.normalise_input(0.0);
        self.last_um = self.file.output_to_physical(self.model.step(x0));
    }
}

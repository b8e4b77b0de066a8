//! The MPIM hysteresis (tests only): the stage follows the model file, and an exact inverse of
//! the same model tracks it, which checks that the chain is wired right.

use std::path::PathBuf;

use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_io::model_file::ModelFile;
use hystcomp_stage::{Stage, StageConfig};

fn table1() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models/table1-plant.json")
}

/// A quiet stage (no creep, no noise) whose hysteresis is Table 1 of the paper.
fn mpim_stage_file(dir: &std::path::Path) -> PathBuf {
    std::fs::copy(table1(), dir.join("table1.json")).unwrap();
    let path = dir.join("stage.toml");
    std::fs::write(
        &path,
        "[hysteresis]\nmodel = \"mpim\"\n[hysteresis.mpim]\nmodel_file = \"table1.json\"\n\
         [creep]\npercent_per_decade = 0.0\n[sensor]\nnoise_rms_nm = 0.0\n",
    )
    .unwrap();
    path
}

#[test]
fn an_mpim_stage_follows_its_model_file_quasi_statically() {
    let dir = tempfile::tempdir().unwrap();
    let config = StageConfig::from_toml_file(&mpim_stage_file(dir.path())).unwrap();
    let file = ModelFile::load(&table1()).unwrap();
    let mut model = file.model().unwrap();
    let mut stage = Stage::new(&config, 0).unwrap();
    // A slow voltage sweep with a minor loop: 10 s at 10 kHz.
    let command: Vec<f64> = (0..100_000)
        .map(|k| {
            let t = k as f64 / 10_000.0;
            4.5 - 4.0 * (0.2 * std::f64::consts::PI * t).cos() * (1.0 + 0.1 * (1.3 * t).sin())
        })
        .collect();
    let measured = stage.run(&command).measured_position_um;
    let mut worst: f64 = 0.0;
    for (k, (&v, &y)) in command.iter().zip(&measured).enumerate().skip(100) {
        let expected = file.output_to_physical(model.step(file.normalise_input(v)));
        // One sample of delay, the amplifier's and the resonance's lag, ADC quantisation.
        if k > 1000 {
            worst = worst.max((y - expected).abs());
        }
    }
    assert!(
        worst < 0.05,
        "the MPIM stage strays {worst} um from its model"
    );
}

#[test]
fn an_exact_inverse_of_the_same_mpim_tracks_it() {
    let dir = tempfile::tempdir().unwrap();
    let config = StageConfig::from_toml_file(&mpim_stage_file(dir.path())).unwrap();
    let file = ModelFile::load(&table1()).unwrap();
    let mut ihc = ScaledCompensator::new(&file, Method::Ihc, None).unwrap();
    let desired: Vec<f64> = (0..100_000)
        .map(|k| 35.0 - 25.0 * (0.4 * std::f64::consts::PI * k as f64 / 10_000.0).cos())
        .collect();
    let mut command = vec![0.0; desired.len()];
    ihc.process(&desired, &mut command).unwrap();
    let measured = Stage::new(&config, 0)
        .unwrap()
        .run(&command)
        .measured_position_um;
    let rms = (desired[1000..]
        .iter()
        .zip(&measured[1000..])
        .map(|(d, y)| (d - y).powi(2))
        .sum::<f64>()
        / (desired.len() - 1000) as f64)
        .sqrt();
    assert!(rms < 0.05, "RMS tracking error {rms} um on its own model");
}

#[test]
fn an_mpim_stage_needs_a_readable_plant_model_file() {
    let err = StageConfig::from_toml_str("[hysteresis]\nmodel = \"mpim\"\n").unwrap_err();
    assert_eq!(err.field(), Some("hysteresis.mpim.model_file"));
    let config = StageConfig::from_toml_str(
        "[hysteresis]\nmodel = \"mpim\"\n[hysteresis.mpim]\nmodel_file = \"/no/such/model.json\"\n",
    )
    .unwrap();
    let err = Stage::new(&config, 0).unwrap_err();
    assert_eq!(err.field(), Some("hysteresis.mpim.model_file"));
    let err = err.to_string();
    assert!(err.contains("/no/such/model.json"), "{err}");
    assert!(err.contains("hysteresis.mpim.model_file"), "{err}");
    assert!(
        !err.contains("stage file"),
        "not the stage file that is missing: {err}"
    );
    let inverse =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models/table2-inverse.json");
    let config = StageConfig::from_toml_str(&format!(
        "[hysteresis]\nmodel = \"mpim\"\n[hysteresis.mpim]\nmodel_file = {:?}\n",
        inverse.display().to_string()
    ))
    .unwrap();
    let err = Stage::new(&config, 0).unwrap_err().to_string();
    assert!(err.contains("plant model"), "{err}");
}

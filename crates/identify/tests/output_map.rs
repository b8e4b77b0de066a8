//! `IdentifyOptions::output_map_degree`: an MPIM with an output map `psi(y) = H[x] + c`
//! (Kuhnen's modified Prandtl-Ishlinskii structure) fitted jointly by least squares; the model
//! file carries the map, predicts through it and its compensators invert it.

use hystcomp_core::{Mpim, OutputMap};
use hystcomp_identify::{IdentifyError, IdentifyOptions, Method, PsoOptions, Warmup, identify};
use hystcomp_io::compensator::{Method as Comp, ScaledCompensator};
use hystcomp_io::model_file::{Direction, ModelFile};

fn options(degree: usize, direction: Direction) -> IdentifyOptions {
    IdentifyOptions {
        output_map_degree: degree,
        direction,
        warmup: Warmup::Samples(0),
        ..IdentifyOptions::default()
    }
}

/// A decaying 1 Hz sine (0..10 V) through Table 1's MPIM and then `psi^-1`, `psi(w) = w +
/// 0.25 w^2 - 0.3 w^3` (rising on [-0.1, 1.1]): 75 um full scale.
fn record() -> (Vec<f64>, Vec<f64>) {
    let thresholds: Vec<f64> = (0..10).map(|i| i as f64 / 10.0).collect();
    let weights = [
        0.2313, 0.3059, 0.0155, 0.0752, 0.0683, 0.0252, 0.0035, 0.0094, 0.0264, 0.0032,
    ];
    let mut truth: Mpim<f64, Vec<f64>> = Mpim::new(&thresholds, &weights, -0.1569, 0.4603).unwrap();
    let map = OutputMap::new(&[0.0, 1.0, 0.25, -0.3], -0.2, 1.2).unwrap();
    let v: Vec<f64> = (0..3000)
        .map(|k| {
            let t = k as f64 / 200.0;
            5.0 - 5.0 * (-t / 10.0).exp() * (2.0 * std::f64::consts::PI * t).cos()
        })
        .collect();
    let (lo, hi) = v
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    let y = v
        .iter()
        .map(|x| 75.0 * map.invert(truth.step((x - lo) / (hi - lo))))
        .collect();
    (v, y)
}

fn rms_percent(a: &[f64], b: &[f64]) -> f64 {
    let (lo, hi) = b
        .iter()
        .fold((f64::MAX, f64::MIN), |(p, q), &x| (p.min(x), q.max(x)));
    100.0 * (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
        / (hi - lo)
}

#[test]
fn a_mapped_model_is_recovered_and_the_plain_mpim_cannot_follow_it() {
    let (v, y) = record();
    let plain = identify(&v, &y, &options(1, Direction::Plant)).unwrap();
    assert!(plain.model.output_map.is_none());
    let mapped = identify(&v, &y, &options(3, Direction::Plant)).unwrap();
    let part = mapped
        .model
        .output_map
        .clone()
        .expect("the file holds the map");
    assert_eq!(part.coefficients.len(), 4);
    assert!(
        mapped.report.fit.rms_percent < 1e-6,
        "{:?}",
        mapped.report.fit
    );
    assert!(plain.report.fit.rms_percent > 100.0 * mapped.report.fit.rms_percent);
    // The file predicts through the map, and reloads bit for bit.
    let predicted = mapped.model.predict(&v).unwrap();
    assert!(rms_percent(&predicted, &y) < 1e-6);
    let back = ModelFile::from_json(&mapped.model.to_json()).unwrap();
    assert_eq!(back, mapped.model);
    // IHC and WIHC on the plant file reach the record's displacement from its voltage.
    for method in [Comp::Ihc, Comp::Wihc] {
        let mut c = ScaledCompensator::new(&mapped.model, method, Some((0.0, 10.0))).unwrap();
        let mut drive = vec![0.0; y.len()];
        c.process(&y, &mut drive).unwrap();
        let reached = mapped.model.predict(&drive).unwrap();
        assert!(rms_percent(&reached, &y) < 1e-6, "{method:?}");
    }
    // The inverse (DIHC) direction: the map on the voltage side fits better than none.
    let plain = identify(&v, &y, &options(1, Direction::Inverse)).unwrap();
    let mapped = identify(&v, &y, &options(3, Direction::Inverse)).unwrap();
    assert!(mapped.report.fit.rms_percent < plain.report.fit.rms_percent);
    let mut c = ScaledCompensator::new(&mapped.model, Comp::Dihc, Some((0.0, 10.0))).unwrap();
    let mut drive = vec![0.0; y.len()];
    c.process(&y, &mut drive).unwrap();
    let predicted = mapped.model.predict(&y).unwrap();
    for (d, p) in drive.iter().zip(&predicted) {
        assert!((d - p.clamp(0.0, 10.0)).abs() < 1e-9);
    }
}

#[test]
fn bad_degrees_and_the_swarm_are_refused_by_name() {
    let (v, y) = record();
    for degree in [0, 6] {
        match identify(&v, &y, &options(degree, Direction::Plant)) {
            Err(IdentifyError::InvalidOption { option, .. }) => {
                assert_eq!(option, "output map degree")
            }
            other => panic!("degree {degree}: {other:?}"),
        }
    }
    let pso = IdentifyOptions {
        method: Method::ParticleSwarm(PsoOptions::default()),
        ..options(3, Direction::Plant)
    };
    assert!(matches!(
        identify(&v, &y, &pso),
        Err(IdentifyError::InvalidOption {
            option: "output map degree",
            ..
        })
    ));
}

/// Files without the map load as before; a file with a map that falls is refused naming it.
#[test]
fn files_without_a_map_are_unchanged_and_a_falling_map_is_refused() {
    let (v, y) = record();
    let mapped = identify(&v, &y, &options(3, Direction::Plant)).unwrap();
    let mut text: serde_json::Value = serde_json::from_str(&mapped.model.to_json()).unwrap();
    text["output_map"]["coefficients"] = serde_json::json!([0.0, 1.0, -1.0]);
    let error = ModelFile::from_json(&text.to_string())
        .unwrap_err()
        .to_string();
    assert!(error.contains("output_map"), "{error}");
    text.as_object_mut().unwrap().remove("output_map");
    let plain = ModelFile::from_json(&text.to_string()).unwrap();
    assert!(plain.output_map.is_none());
    assert!(!plain.to_json().contains("output_map"));
}

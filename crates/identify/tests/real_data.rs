//! Real laboratory data (Aye & Ang's piezo micromanipulator, `../shared/data`, read in place):
//! identification on `Model_Vi_Do.dat` (column 1 -> column 5), cross-validation on
//! `Test_Vi_Do_Di.dat` (columns 1 and 5). Skipped, with a message, when the files are absent.
//! The figures are printed (`cargo test -- --nocapture`) and quoted in the notes.

use std::path::Path;

use hystcomp_identify::{
    CrossvalOptions, IdentifyOptions, Method, NoObserver, PsoOptions, Record, Thresholds, crossval,
    identify,
};
use hystcomp_io::data::{Column, ReadOptions, read_columns};
use hystcomp_io::model_file::Direction;

const DATA: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/data/dbo-micromanipulator/"
);

/// Columns 1 (voltage) and 5 (sensor) of a DBO file, or `None` (with a message) when absent.
fn record(file: &str) -> Option<(Vec<f64>, Vec<f64>)> {
    let path = Path::new(DATA).join(file);
    if !path.exists() {
        eprintln!("skipped: {} is absent", path.display());
        return None;
    }
    let columns = read_columns(
        &path,
        &[Column::Index(1), Column::Index(5)],
        &ReadOptions::default(),
    )
    .expect("the DBO file reads");
    let mut values = columns.values.into_iter();
    Some((values.next().unwrap(), values.next().unwrap()))
}

#[test]
fn dbo_identification_fits_within_sane_bounds() {
    let Some((v, y)) = record("Model_Vi_Do.dat") else {
        return;
    };
    for direction in [Direction::Plant, Direction::Inverse] {
        let mut previous_rms = f64::INFINITY;
        for n in [10, 20] {
            let options = IdentifyOptions {
                direction,
                holdout: 0.2,
                thresholds: Thresholds::Uniform(n),
                ..IdentifyOptions::default()
            };
            let fit = identify(&v, &y, &options).expect("identifies");
            let r = &fit.report;
            let h = r.holdout.expect("a hold-out span");
            eprintln!(
                "DBO {direction} n={n}: warm-up {}, fit {} samples RMS {:.3} % max {:.3} %, \
                 hold-out {} samples RMS {:.3} % max {:.3} %, condition {:.2e}, {}/{} \
                 constraints active, smallest slope {:.4}, {:.1} ms",
                r.samples.warmup,
                r.samples.fit,
                r.fit.rms_percent,
                r.fit.max_percent,
                r.samples.holdout,
                h.rms_percent,
                h.max_percent,
                r.condition_number,
                r.active_constraints,
                r.constraints,
                r.min_branch_slope,
                r.elapsed_s * 1e3,
            );
            // The record starts at 1.8 V, mid-range: the warm-up reaches the first minimum
            // (about 3/4 of the first 200-sample cycle).
            assert!(
                (100..200).contains(&r.samples.warmup),
                "{}",
                r.samples.warmup
            );
            assert!(r.fit.rms_percent > 0.05 && r.fit.rms_percent < 1.5);
            assert!(r.fit.max_percent < 5.0);
            assert!(h.rms_percent < 1.5 && h.max_percent < 5.0);
            assert!(r.min_branch_slope >= 1e-3 * (1.0 - 1e-9));
            // More operators never fit worse on the same span.
            assert!(r.fit.rms_percent <= previous_rms);
            previous_rms = r.fit.rms_percent;
        }
    }
}

#[test]
fn dbo_crossval_within_sane_bounds() {
    let (Some((v, y)), Some((tv, ty))) = (record("Model_Vi_Do.dat"), record("Test_Vi_Do_Di.dat"))
    else {
        return;
    };
    let mut fits = Vec::new();
    for method in [
        Method::LeastSquares,
        Method::ParticleSwarm(PsoOptions::default()),
    ] {
        let options = CrossvalOptions {
            identify: IdentifyOptions {
                method: method.clone(),
                ..IdentifyOptions::default()
            },
            ..CrossvalOptions::default()
        };
        let cv = crossval(
            Record {
                voltage: &v,
                displacement: &y,
            },
            Record {
                voltage: &tv,
                displacement: &ty,
            },
            &options,
            &mut NoObserver,
        )
        .expect("cross-validates");
        let name = match method {
            Method::LeastSquares => "ls",
            Method::ParticleSwarm(_) => "pso",
        };
        let (p, i, t) = (&cv.report.plant, &cv.report.inverse, &cv.report.test);
        eprintln!(
            "DBO crossval {name}: train plant RMS {:.3} % max {:.3} %, inverse RMS {:.3} % max \
             {:.3} %; test warm-up {}, forward RMS {:.3} % max {:.3} % (mean {:.3} um, \
             without it {:.3} %)",
            p.fit.rms_percent,
            p.fit.max_percent,
            i.fit.rms_percent,
            i.fit.max_percent,
            t.warmup,
            t.forward.rms_percent,
            t.forward.max_percent,
            t.forward.mean,
            t.forward.std_percent
        );
        for r in &t.replay {
            let e = r.error.expect("every compensator is built");
            eprintln!(
                "    replay {:13} RMS {:.3} % max {:.3} % (mean {:+.4} V), saturated {}",
                r.compensator, e.rms_percent, e.max_percent, e.mean, r.saturated
            );
            assert!(e.rms_percent.is_finite() && e.max_percent < 50.0);
            if name == "ls" {
                // The delayed WIHC may ring while several operators move (its loop gain is
                // then (3 a1 v^2 + sum of the moving b_i) / a2): a looser bound on its peak.
                let max_bound = if r.compensator == "wihc-delayed" {
                    20.0
                } else {
                    10.0
                };
                assert!(e.rms_percent < 3.0, "{}: {}", r.compensator, e.rms_percent);
                assert!(
                    e.max_percent < max_bound,
                    "{}: {}",
                    r.compensator,
                    e.max_percent
                );
            }
        }
        assert!((100..200).contains(&t.warmup), "{}", t.warmup);
        assert!(t.forward.rms_percent < 5.0 && t.forward.max_percent < 15.0);
        fits.push((p.fit.rms, i.fit.rms));
    }
    // On the same data and thresholds, least squares is never worse than the swarm.
    assert!(fits[0].0 <= fits[1].0 && fits[0].1 <= fits[1].1);
}

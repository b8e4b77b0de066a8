//! Which hysteresis model class follows the stage (issue 11): candidates measured on the
//! creep-, dynamics- and noise-free copy of the built-in stage, diagnosis only.
//! `cargo run --release -p hystcomp-experiments --example hyst_class_diag [N1,N2,..] [POWER]`
//! (environment `MAPS=3`: only these output-map degrees, 1 the MPIM alone):
//! for each operator count (thresholds `(i/n)^POWER`), the MPIM alone and with an output map
//! `psi(y) = y - e_2 y^2 - ... - e_K y^K` of degree 2-5 (`FitProblem::with_output_map`), plant
//! and inverse: the fit on the hysteresis excitation, the held-out error on the chain
//! excitation's rate sweep and holds, the map's least slope, and IHC / DIHC tracking of the
//! 20 s paper trajectory (second half) on the same copy of the stage.

#![allow(clippy::needless_range_loop)]

use hystcomp_experiments::chain_excitation::ChainExcitation;
use hystcomp_experiments::excitation::IdentificationExcitation;
use hystcomp_experiments::signals::Signal;
use hystcomp_identify::{
    FitProblem, IdentifyOptions, LeastSquares, NoObserver, ProblemData, Solver, Thresholds, Warmup,
};
use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_io::model_file::{Direction, ModelFile, Scale};
use hystcomp_stage::{Stage, StageConfig};

fn rms(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}
fn range(a: &[f64]) -> f64 {
    a.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - a.iter().copied().fold(f64::INFINITY, f64::min)
}
fn clean_stage() -> StageConfig {
    let mut s = StageConfig::default();
    s.sensor.noise_rms_nm = 0.0;
    s.amplifier.bandwidth_hz = 1e9;
    s.amplifier.peak_current_ma = 1e9;
    s.mechanics.rigid = true;
    s.creep.percent_per_decade = 0.0;
    s
}
fn run(stage: &StageConfig, seed: u64, command: &[f64]) -> Vec<f64> {
    Stage::new(stage, seed)
        .unwrap()
        .run(command)
        .measured_position_um
}

#[derive(Clone, Copy, Debug)]
enum Map {
    None,
    Poly(usize),
}

/// Output map psi(y) = y - sum e_j col_j(y) with col_j the map's basis.
fn basis(map: Map, y: f64) -> Vec<f64> {
    match map {
        Map::None => vec![],
        Map::Poly(k) => (2..=k).map(|j| y.powi(j as i32)).collect(),
    }
}
fn psi(map: Map, e: &[f64], y: f64) -> f64 {
    y - basis(map, y).iter().zip(e).map(|(b, e)| b * e).sum::<f64>()
}
fn psi_inv(map: Map, e: &[f64], u: f64) -> f64 {
    let (mut lo, mut hi) = (-1.0, 2.0);
    for _ in 0..80 {
        let m = 0.5 * (lo + hi);
        if psi(map, e, m) < u { lo = m } else { hi = m }
    }
    0.5 * (lo + hi)
}

struct Fitted {
    model: ModelFile,
    map: Map,
    e: Vec<f64>,
    out_min: f64,
    out_scale: f64,
    fit_pct: f64,
    min_slope: f64,
}

fn fit(input: &[f64], output: &[f64], n: usize, power: f64, map: Map, dir: Direction) -> Fitted {
    let mn = |a: &[f64]| a.iter().copied().fold(f64::INFINITY, f64::min);
    let (xmin, xs) = (mn(input), range(input));
    let (ymin, ys) = (mn(output), range(output));
    let x: Vec<f64> = input.iter().map(|v| (v - xmin) / xs).collect();
    let y: Vec<f64> = output.iter().map(|v| (v - ymin) / ys).collect();
    let thresholds: Vec<f64> = (0..n).map(|i| (i as f64 / n as f64).powf(power)).collect();
    let cols: Vec<Vec<f64>> = {
        let b: Vec<Vec<f64>> = y.iter().map(|&v| basis(map, v)).collect();
        let k = b.first().map_or(0, |r| r.len());
        (0..k).map(|j| b.iter().map(|r| r[j]).collect()).collect()
    };
    let refs: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
    let data = ProblemData {
        input: &x,
        output: &y,
        fit: 0..x.len(),
    };
    let m = hystcomp_identify::DEFAULT_MARGIN;
    let problem = match map {
        Map::Poly(k) => {
            FitProblem::with_output_map(data, &thresholds, dir, true, m, 3, k, &[]).unwrap()
        }
        _ => FitProblem::with_extra_columns(data, &thresholds, dir, true, m, &refs).unwrap(),
    };
    let sol = LeastSquares.solve(&problem, &mut NoObserver).unwrap();
    let p = problem.parameters(&sol.theta);
    let e = match map {
        Map::Poly(_) => problem.output_map_parameters(&sol.theta).to_vec(),
        _ => problem.extra_parameters(&sol.theta).to_vec(),
    };
    let mpim = p.model(&thresholds).unwrap();
    let (iq, oq, iu, ou) = match dir {
        Direction::Plant => ("voltage", "displacement", "V", "um"),
        Direction::Inverse => ("displacement", "voltage", "um", "V"),
    };
    let model = ModelFile::from_model(
        dir,
        Scale {
            quantity: iq.into(),
            unit: iu.into(),
            offset: xmin,
            scale: xs,
        },
        Scale {
            quantity: oq.into(),
            unit: ou.into(),
            offset: ymin + ys * p.offset,
            scale: ys,
        },
        [0.0, 1.0],
        &mpim,
    )
    .unwrap();
    let min_slope = (0..=200)
        .map(|i| {
            let a = -0.05 + 1.1 * i as f64 / 200.0;
            (psi(map, &e, a + 1e-4) - psi(map, &e, a)) / 1e-4
        })
        .fold(f64::INFINITY, f64::min);
    Fitted {
        model,
        map,
        e,
        out_min: ymin,
        out_scale: ys,
        fit_pct: 100.0 * sol.cost,
        min_slope,
    }
}

impl Fitted {
    fn map_to_psi(&self, phys: f64) -> f64 {
        let yn = (phys - self.out_min) / self.out_scale;
        self.out_min + self.out_scale * psi(self.map, &self.e, yn)
    }
    fn unmap(&self, phys: f64) -> f64 {
        let u = (phys - self.out_min) / self.out_scale;
        self.out_min + self.out_scale * psi_inv(self.map, &self.e, u)
    }
    /// Model prediction of its output from its input.
    fn predict(&self, input: &[f64]) -> Vec<f64> {
        self.model
            .predict(input)
            .unwrap()
            .iter()
            .map(|u| self.unmap(*u))
            .collect()
    }
}

fn main() {
    let stage = clean_stage();
    let fs = stage.sample_rate_hz;
    let full_scale = stage.full_scale_command_v();
    let hyst = IdentificationExcitation {
        full_scale_v: full_scale,
        ..Default::default()
    };
    let mut cmd = hyst.command_v(fs);
    let n0 = cmd.len();
    let (chain_part, segs) = ChainExcitation::default()
        .command_v(full_scale, fs, *cmd.last().unwrap())
        .unwrap();
    cmd.extend(chain_part);
    let end = n0 + segs.vibration.start;
    let clean = run(&stage, 1, &cmd);
    let dec = 10;
    let vv: Vec<f64> = cmd[..n0].iter().step_by(dec).copied().collect();
    let yy: Vec<f64> = clean[..n0].iter().step_by(dec).copied().collect();
    // held out: the chain excitation's slow part (rate sweep, holds), decimated
    let vh: Vec<f64> = cmd[..end].iter().step_by(dec).copied().collect();
    let yh: Vec<f64> = clean[..end].iter().step_by(dec).copied().collect();
    let h0 = n0 / dec;
    let desired = Signal::paper(1.0, 20.0, fs).sample().unwrap();
    let half = desired.len() / 2;
    let dr = range(&desired[half..]);
    let _ = IdentifyOptions {
        thresholds: Thresholds::Uniform(10),
        warmup: Warmup::Samples(0),
        ..IdentifyOptions::default()
    };
    let args: Vec<String> = std::env::args().collect();
    let ns: Vec<usize> = args
        .get(1)
        .map(|s| s.split(',').map(|x| x.parse().unwrap()).collect())
        .unwrap_or(vec![10]);
    let power: f64 = args.get(2).map_or(1.0, |s| s.parse().unwrap());
    // MAPS=3 (degrees, 1: none) restricts the output maps, e.g. to the `full` pipeline's.
    let maps: Vec<Map> = std::env::var("MAPS")
        .map(|s| {
            s.split(',')
                .map(|d| match d.parse().unwrap() {
                    1 => Map::None,
                    k => Map::Poly(k),
                })
                .collect()
        })
        .unwrap_or(vec![
            Map::None,
            Map::Poly(2),
            Map::Poly(3),
            Map::Poly(4),
            Map::Poly(5),
        ]);
    for &n in &ns {
        for &map in &maps {
            // plant
            let p = fit(&vv, &yy, n, power, map, Direction::Plant);
            let pred = p.predict(&vh);
            let held = 100.0 * rms(&pred[h0..], &yh[h0..]) / range(&yh[h0..]);
            let target: Vec<f64> = desired.iter().map(|y| p.map_to_psi(*y)).collect();
            let mut c =
                ScaledCompensator::new(&p.model, Method::Ihc, Some((0.0, full_scale))).unwrap();
            let mut u = vec![0.0; desired.len()];
            c.process(&target, &mut u).unwrap();
            let m = run(&stage, 2, &u);
            let ihc = 100.0 * rms(&m[half..], &desired[half..]) / dr;
            // inverse
            let q = fit(&yy, &vv, n, power, map, Direction::Inverse);
            let predv = q.predict(&yh);
            let heldv = 100.0 * rms(&predv[h0..], &vh[h0..]) / range(&vh[h0..]);
            let mut c = ScaledCompensator::new(&q.model, Method::Dihc, Some((-1e3, 1e3))).unwrap();
            let mut u = vec![0.0; desired.len()];
            c.process(&desired, &mut u).unwrap();
            let u: Vec<f64> = u
                .iter()
                .map(|w| q.unmap(*w).clamp(0.0, full_scale))
                .collect();
            let m = run(&stage, 2, &u);
            let dihc = 100.0 * rms(&m[half..], &desired[half..]) / dr;
            println!(
                "n={n:2} p={power} {map:?}: plant fit {:.3} held {:.4} slope {:.2} IHC {:.3} | inverse fit {:.3} held {:.4} slope {:.2} DIHC {:.3}",
                p.fit_pct, held, p.min_slope, ihc, q.fit_pct, heldv, q.min_slope, dihc
            );
        }
    }
}

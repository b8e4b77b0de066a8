//! The particle swarm's defaults against least squares on the built-in stage's record (issue
//! 10: within 10 % of the least-squares RMS at n = 10 and n = 50).
//!
//! The record is the study's: the identification excitation from rest on the default stage
//! (sensor-noise seed 1), every tenth sample, as `hystcomp reproduce` identifies it. Each
//! `n` is fitted as a plant model by least squares and by the swarm with `PsoOptions::default()`
//! (or the settings given), over seeds 0..SEEDS; the RMS errors and the times are printed.
//!
//! ```text
//! cargo run -p hystcomp-experiments --example pso_vs_ls [SEEDS] [PARTICLES ITERATIONS]
//! ```

use std::time::Instant;

use hystcomp_experiments::excitation::IdentificationExcitation;
use hystcomp_identify::{IdentifyOptions, Method, PsoOptions, Thresholds, Warmup, identify};
use hystcomp_stage::{Stage, StageConfig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seeds: u64 = args.first().map_or(Ok(3), |s| s.parse())?;
    let mut pso = PsoOptions::default();
    if let [_, particles, iterations, ..] = args.as_slice() {
        pso = pso
            .with_particles(particles.parse()?)?
            .with_iterations(iterations.parse()?)?;
    }
    let stage = StageConfig::default();
    let excitation = IdentificationExcitation {
        full_scale_v: stage.full_scale_command_v(),
        ..Default::default()
    };
    let command = excitation.command_v(stage.sample_rate_hz);
    let response = Stage::new(&stage, 1)?.run(&command);
    let v: Vec<f64> = command.iter().step_by(10).copied().collect();
    let y: Vec<f64> = response
        .measured_position_um
        .iter()
        .step_by(10)
        .copied()
        .collect();
    println!(
        "record: {} samples; swarm: {} particles, {} iterations",
        v.len(),
        pso.particles,
        pso.iterations
    );
    for n in [10, 50] {
        let base = IdentifyOptions {
            thresholds: Thresholds::Uniform(n),
            warmup: Warmup::Samples(0),
            max_fit_rms_percent: None,
            ..IdentifyOptions::default()
        };
        let t = Instant::now();
        let ls = identify(&v, &y, &base)?;
        let ls_s = t.elapsed().as_secs_f64();
        let ls_rms = ls.report.fit.rms_percent;
        println!("n = {n}: ls RMS {ls_rms:.4} % in {ls_s:.3} s");
        for seed in 0..seeds {
            let options = IdentifyOptions {
                method: Method::ParticleSwarm(pso.clone().with_seed(seed)),
                ..base.clone()
            };
            let t = Instant::now();
            match identify(&v, &y, &options) {
                Ok(fit) => {
                    let rms = fit.report.fit.rms_percent;
                    println!(
                        "  pso seed {seed}: RMS {rms:.4} % ({:+.1} % of ls) in {:.3} s",
                        100.0 * (rms / ls_rms - 1.0),
                        t.elapsed().as_secs_f64()
                    );
                }
                Err(e) => println!("  pso seed {seed}: {e}"),
            }
        }
    }
    Ok(())
}

//! Every compensator (IHC, WIHC exact and delayed, DIHC) on arbitrary valid models and
//! arbitrary desired positions (any f64 or f32 bit pattern: NaN, infinities, 1e308,
//! subnormals...): outputs finite and within the limits on any model the constructors accept;
//! on models of the normalised form identification gives (thresholds in [0, 1), parameters
//! zero or between 1e-6 and 10 in magnitude (Table 1 lies within 1.3), limits within [-1, 2],
//! every branch slope at least
//! 1e-3 over the limits, any mantissa) also exact modes reproduce y_d where reachable and every
//! clamp is counted (`crates/core/tests/common/invariants.rs`).
#![no_main]

use arbitrary::{Arbitrary, Unstructured};
use hystcomp_core::{Mpim, OutputLimits, Real};
use hystcomp_fuzz::ensure;
use hystcomp_fuzz::invariants::{Subject, check_dihc, check_plant_compensators};
use libfuzzer_sys::fuzz_target;

/// A model's parameters as the fuzzer gives them (the constructors refuse what is invalid).
#[derive(Debug, Arbitrary)]
struct Input {
    thresholds: Vec<f64>,
    weights: Vec<f64>,
    a1: f64,
    a2: f64,
    limits: (f64, f64),
    range: (f64, f64),
    desired: Vec<f64>,
    single: bool,
}

/// `x` as the fuzzer gave it, or (with `moderate`) zero or folded into `1e-6 <= |x| <= bound`
/// by powers of two (keeping its mantissa): the normalised size of model files.
fn fold(x: f64, bound: f64, moderate: bool) -> f64 {
    if !moderate || !x.is_finite() || x == 0.0 {
        return x;
    }
    let mut y = x;
    while y.abs() > bound {
        y /= 256.0;
    }
    while y.abs() < 1e-6 {
        y *= 256.0;
    }
    y
}

fn run<T: Real>(input: &Input, moderate: bool) -> Option<()> {
    let n = input.thresholds.len().min(input.weights.len()).clamp(1, 32);
    let convert = |v: &[f64], bound: f64| {
        v.iter()
            .take(n)
            .map(|&x| T::from_f64(fold(x, bound, moderate)))
            .collect::<Vec<T>>()
    };
    let mut thresholds = convert(&input.thresholds, 1.0);
    if moderate {
        // Thresholds of model files lie in [0, 1), increasing.
        for r in &mut thresholds {
            *r = r.abs();
            if r.is_nan() || *r >= T::one() {
                *r = T::zero();
            }
        }
        thresholds.sort_by(|a, b| Real::to_f64(*a).total_cmp(&Real::to_f64(*b)));
        thresholds.dedup();
    }
    let n = thresholds.len().max(1);
    thresholds.resize(n, T::zero());
    let mut weights = convert(&input.weights, 10.0);
    weights.resize(n, T::zero());
    let model: Mpim<T, Vec<T>> = Mpim::new(
        &thresholds,
        &weights,
        T::from_f64(fold(input.a1, 10.0, moderate)),
        T::from_f64(fold(input.a2, 10.0, moderate)),
    )
    .ok()?;
    let limits = OutputLimits::new(
        T::from_f64(fold(input.limits.0, 1.0, moderate)),
        T::from_f64(fold(input.limits.1, 2.0, moderate)),
    )
    .ok()?;
    // Models identification gives: every branch slope at least its default margin (1e-3 of
    // the mean slope, in normalised units) over the limits. Thinner models pass the
    // constructors (their slopes are positive) but lose digits in eq. (7): checked for the
    // safety invariants only.
    let moderate = moderate
        && model
            .min_branch_slope(limits.min(), limits.max())
            .is_ok_and(|s| Real::to_f64(s.slope) >= 1e-3);
    let desired: Vec<T> = input
        .desired
        .iter()
        .take(512)
        .map(|&y| T::from_f64(y))
        .collect();
    let subject = Subject {
        model,
        limits,
        moderate,
    };
    let result = check_plant_compensators(&subject, &desired).and_then(|()| {
        check_dihc(
            &subject,
            T::from_f64(fold(input.range.0, 1.0, moderate)),
            T::from_f64(fold(input.range.1, 2.0, moderate)),
            &desired,
        )
    });
    ensure(result.map_err(|violation| format!("{violation}\n{input:?}")));
    Some(())
}

fuzz_target!(|data: &[u8]| {
    let Ok(input) = Input::arbitrary(&mut Unstructured::new(data)) else {
        return;
    };
    // The safety invariants on the model exactly as given; all of them on its moderate
    // form (the desired positions stay arbitrary either way).
    for moderate in [false, true] {
        if input.single {
            run::<f32>(&input, moderate);
        } else {
            run::<f64>(&input, moderate);
        }
    }
});

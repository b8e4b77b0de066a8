//! The compensators' safety invariants (`common/invariants.rs`) on seeded random models and
//! on inputs that mix reachable positions with NaN, infinities, +-1e308, `f64::MAX`,
//! subnormals and zeros, in f64 and f32: the stable counterpart of the fuzz target
//! `compensators`, so that CI always checks the same properties.

mod common;

use common::invariants::{Subject, check_dihc, check_plant_compensators};
use common::*;
use hystcomp_core::{Mpim, OutputLimits};
use proptest::prelude::*;
use rand::{Rng, RngExt};

/// Values a desired position may take that no trajectory should: the fuzzers' favourites.
const EXTREMES: [f64; 14] = [
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    1e308,
    -1e308,
    f64::MAX,
    f64::MIN,
    5e-324,
    -5e-324,
    2.2e-308,
    0.0,
    -0.0,
    1e30,
    -1e30,
];

/// `len` desired positions: mostly reachable (the plant's output on a random input), with
/// extremes and values just beyond the reachable range mixed in.
fn desired(rng: &mut impl Rng, plant: &VecMpim, len: usize) -> Vec<f64> {
    let v = random_input(rng, len, -0.2, 1.2);
    let mut p = plant.clone();
    v.iter()
        .map(|&x| {
            let y = p.step(x);
            match rng.random::<u32>() % 10 {
                0 => EXTREMES[rng.random::<u32>() as usize % EXTREMES.len()],
                1 => y * 1.5 + 0.3,
                _ => y,
            }
        })
        .collect()
}

fn limits_from(rng: &mut impl Rng) -> OutputLimits<f64> {
    match rng.random::<u32>() % 3 {
        0 => OutputLimits::new(0.0, 1.0).unwrap(),
        1 => OutputLimits::new(0.1, 0.8).unwrap(),
        _ => OutputLimits::new(-0.5, 1.5).unwrap(),
    }
}

fn as_f32(model: &VecMpim) -> Mpim<f32, Vec<f32>> {
    let f = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
    Mpim::new(
        &f(model.thresholds()),
        &f(model.weights()),
        model.a1() as f32,
        model.a2() as f32,
    )
    .unwrap()
}

fn limits_f32(limits: OutputLimits<f64>) -> OutputLimits<f32> {
    OutputLimits::new(limits.min() as f32, limits.max() as f32).unwrap()
}

proptest! {
    #![proptest_config(seeded(96, 0x696e_7661_7269_616e))]

    /// IHC and WIHC, exact and delayed, in f64 and f32.
    #[test]
    fn plant_compensators_keep_their_invariants(seed in any::<u64>(), n in 1usize..20) {
        let mut rng = rng(seed);
        let plant = random_invertible_model(&mut rng, n);
        let limits = limits_from(&mut rng);
        let desired = desired(&mut rng, &plant, 400);
        let subject = Subject { model: plant.clone(), limits, moderate: true };
        if let Err(violation) = check_plant_compensators(&subject, &desired) {
            prop_assert!(false, "{}", violation);
        }
        let subject32 = Subject { model: as_f32(&plant), limits: limits_f32(limits), moderate: true };
        let desired32: Vec<f32> = desired.iter().map(|&y| y as f32).collect();
        if let Err(violation) = check_plant_compensators(&subject32, &desired32) {
            prop_assert!(false, "f32: {}", violation);
        }
    }

    /// DIHC on random inverse models, in f64 and f32.
    #[test]
    fn dihc_keeps_its_invariants(seed in any::<u64>(), n in 1usize..20) {
        let mut rng = rng(seed);
        let inverse = random_invertible_model(&mut rng, n);
        let limits = limits_from(&mut rng);
        let desired = desired(&mut rng, &inverse, 400);
        let subject = Subject { model: inverse.clone(), limits, moderate: true };
        if let Err(violation) = check_dihc(&subject, 0.0, 1.0, &desired) {
            prop_assert!(false, "{}", violation);
        }
        let subject32 = Subject { model: as_f32(&inverse), limits: limits_f32(limits), moderate: true };
        let desired32: Vec<f32> = desired.iter().map(|&y| y as f32).collect();
        if let Err(violation) = check_dihc(&subject32, 0.0, 1.0, &desired32) {
            prop_assert!(false, "f32: {}", violation);
        }
    }
}

/// Issue 13 item 7: the delayed WIHC fed 1e308 clamps its (overflowing) output and counts it.
#[test]
fn an_overflowing_delayed_wihc_sample_is_counted() {
    use hystcomp_core::{Compensator, SolveMode, Wihc};
    let mut wihc: Wihc<f64, Vec<f64>> =
        Wihc::new(&table1(), unit_limits(), SolveMode::DelayedAllowUnstable).unwrap();
    for (k, y_d) in [0.3, 1e308, 0.3, -1e308, f64::MAX].into_iter().enumerate() {
        let before = wihc.diagnostics();
        let v = wihc.step(y_d);
        let after = wihc.diagnostics();
        assert!((0.0..=1.0).contains(&v), "sample {k}: {v}");
        if y_d.abs() > 1e300 {
            assert_eq!(
                after.saturated + after.loop_saturated,
                before.saturated + before.loop_saturated + 1,
                "sample {k}: y_d = {y_d} clamped but not counted"
            );
        }
    }
}

/// Issue 13 item 7: models whose parameters are tiny or subnormal (a model file with a denormal
/// output scale comes to this) keep every invariant: each clamp counted, outputs within the
/// limits.
#[test]
fn tiny_and_subnormal_models_keep_their_invariants() {
    let mut rng = rng(5);
    for factor in [1e-100, 1e-300, 1e-310, 1e-320] {
        let t = table1();
        let scaled = |v: &[f64]| v.iter().map(|x| x * factor).collect::<Vec<f64>>();
        let Ok(plant) = Mpim::new(
            t.thresholds(),
            &scaled(t.weights()),
            t.a1() * factor,
            t.a2() * factor,
        ) else {
            continue;
        };
        let desired = desired(&mut rng, &plant, 300);
        let subject = Subject {
            model: plant,
            limits: unit_limits(),
            moderate: true,
        };
        check_plant_compensators(&subject, &desired)
            .unwrap_or_else(|v| panic!("factor {factor:e}: {v}"));
    }
}

/// Found by the fuzz target `compensators`: after a clamp at the lower limit, a subnormal
/// desired position (the root of eq. (5) at 0 with a subnormal constant term) made the exact
/// IHC's chord iteration creep towards 0 geometrically, never closing its bracket, and end on
/// a bisection step: a drive of 2022 where 0 was right, not counted as a clamp.
#[test]
fn a_subnormal_desired_position_after_a_clamp_gets_the_exact_drive() {
    use hystcomp_core::{Compensator, Ihc, SolveMode};
    let model = Mpim::new(&[0.0], &[0.0], 0.001454220124425284, 2732.6028137363173).unwrap();
    let limits = OutputLimits::new(-2.1333434983772617, 4044.953690536558).unwrap();
    for y_d in [5.8e-322, -5.8e-322, 1e-310, 0.0] {
        let mut ihc: Ihc<f64, Vec<f64>> = Ihc::new(&model, limits, SolveMode::Exact).unwrap();
        assert_eq!(ihc.step(-1e10), limits.min());
        let v = ihc.step(y_d);
        assert!(v.abs() < 1e-12, "y_d = {y_d:e}: v = {v}");
        let subject = Subject {
            model: model.clone(),
            limits,
            moderate: true,
        };
        check_plant_compensators(&subject, &[-1e10, y_d, -3.4e305, y_d]).unwrap();
    }
}

/// Found when the f32 tolerance was tightened to what it claims (about 1e-3): an f32 IHC driven
/// from one limit to the other took a clamped sample's input from beyond the start of the walk's
/// last segment, so the bank's memory and its running sum disagreed and the next reachable
/// positions missed by 1.2 % (y_d = 0.4387, P[v] = 0.4512), uncounted.
#[test]
fn an_f32_ihc_between_its_limits_keeps_reproducing_y_d() {
    let mut rng = rng(11_530_027_245_853_094_798);
    let plant = random_invertible_model(&mut rng, 15);
    let limits = limits_from(&mut rng);
    let desired = desired(&mut rng, &plant, 400);
    let subject = Subject {
        model: as_f32(&plant),
        limits: limits_f32(limits),
        moderate: true,
    };
    let desired: Vec<f32> = desired.iter().map(|&y| y as f32).collect();
    if let Err(violation) = check_plant_compensators(&subject, &desired) {
        panic!("{violation}");
    }
}

/// Found by the fuzz target `compensators` (10 minutes, `fuzz/corpus/compensators/
/// a2-small-beside-b1`): an f32 model with `a2 = 2.4e-6` beside a zero-threshold weight of 0.1.
/// Eq. (7)'s inverse then has `a_hat = 1 / a2 = 4.1e5` and a first weight of nearly `-4.1e5`,
/// and the segment slopes summed from them lost 2.5 % in f32: after a clamp at the upper limit
/// the exact IHC answered `y_d = 0` with `P[v] = 0.109`, uncounted. The compensator's bank folds
/// the zero-threshold operators into its linear term.
#[test]
fn an_f32_ihc_with_a_small_a2_beside_its_zero_threshold_weight_stays_exact() {
    let thresholds: [f32; 8] = [
        0.0,
        2.982_459_6e-6,
        4.216_294_5e-5,
        0.021_737_285,
        0.031_256_18,
        0.208_609_54,
        0.376_870_96,
        0.624_927_16,
    ];
    let weights: [f32; 8] = [
        0.104_208_95,
        0.127_792_97,
        0.605_151_1,
        0.602_491_14,
        10.0,
        0.104_208_95,
        0.127_792_97,
        -1.663_857_8,
    ];
    let model = Mpim::new(&thresholds, &weights, 0.000_106_971_94, 2.430_505_2e-6).unwrap();
    let limits = OutputLimits::new(-3.051_757_8e-5, 0.104_208_95).unwrap();
    let subject = Subject {
        model,
        limits,
        moderate: true,
    };
    let desired = [9.145_124e36, f32::NAN, -0.0, 0.05, 0.3, 0.0];
    if let Err(violation) = check_plant_compensators(&subject, &desired) {
        panic!("{violation}");
    }
}

/// Found by `plant_compensators_keep_their_invariants` at `PROPTEST_CASES=20000` (its minimal
/// case: seed 8648237401598759739, n = 1): a guarded delayed IHC with a relaxation below 1
/// (`a1 > 0`) fed a desired position twice beyond anything reachable (4.18 against a reach of
/// 2.04) took its under-relaxed step to v = 0.653, short of the limit, and the sample was not
/// counted. The guarded loops now learn first whether `y_d` is reachable from the current state
/// (the exact solve's walk, without its root) and, when it is not, emit the limit the exact
/// solution sits on and count the sample as saturated.
#[test]
fn a_guarded_ihc_counts_an_unreachable_position_on_its_first_step() {
    let mut rng = rng(8_648_237_401_598_759_739);
    let plant = random_invertible_model(&mut rng, 1);
    let limits = limits_from(&mut rng);
    let desired = desired(&mut rng, &plant, 400);
    let subject = Subject {
        model: plant.clone(),
        limits,
        moderate: true,
    };
    if let Err(violation) = check_plant_compensators(&subject, &desired) {
        panic!("{violation}");
    }
    let subject32 = Subject {
        model: as_f32(&plant),
        limits: limits_f32(limits),
        moderate: true,
    };
    let desired32: Vec<f32> = desired.iter().map(|&y| y as f32).collect();
    if let Err(violation) = check_plant_compensators(&subject32, &desired32) {
        panic!("f32: {violation}");
    }
}

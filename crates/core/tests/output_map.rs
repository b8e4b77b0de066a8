//! The hysteresis link's output map (`OutputMap`) and the compensator it wraps
//! (`MappedCompensator`), checked against plain references on seeded random maps: the
//! polynomial summed power by power with the linear continuation written out, its inverse by
//! plain bisection, and the mapped IHC / DIHC against the MPIM they invert.

mod common;

use common::{random_invertible_model, rng, unit_limits};
use hystcomp_core::{
    Compensator, CoreError, Dihc, Ihc, MapSide, MappedCompensator, Mpim, OutputLimits, OutputMap,
    SolveMode,
};
use rand::{Rng, RngExt};

/// A random strictly increasing map on a random range: `w + a (w - lo)^2 + b (w - lo)^3 + ...`
/// with small coefficients (rejected until the plain grid check finds it increasing).
fn random_map(rng: &mut impl Rng) -> (Vec<f64>, f64, f64, OutputMap<f64>) {
    loop {
        let degree = 1 + (rng.random::<f64>() * 5.0) as usize;
        let lo = rng.random::<f64>() * 0.4 - 0.3;
        let hi = lo + 0.5 + rng.random::<f64>();
        let mut c: Vec<f64> = (0..=degree)
            .map(|_| 0.6 * (rng.random::<f64>() - 0.5))
            .collect();
        c[1] = 1.0;
        let slope = |w: f64| {
            (1..c.len())
                .map(|j| j as f64 * c[j] * w.powi(j as i32 - 1))
                .sum::<f64>()
        };
        let plain_min = (0..=4000)
            .map(|i| slope(lo + (hi - lo) * i as f64 / 4000.0))
            .fold(f64::INFINITY, f64::min);
        match OutputMap::new(&c, lo, hi) {
            Ok(map) => {
                assert!(
                    plain_min > -1e-9,
                    "accepted a map whose slope reaches {plain_min}"
                );
                return (c, lo, hi, map);
            }
            Err(CoreError::NotPositive { value, .. }) => {
                assert!(
                    plain_min < 1e-6,
                    "refused a map whose slope is at least {plain_min}"
                );
                assert!(value <= plain_min + 1e-6);
            }
            Err(e) => panic!("unexpected refusal {e}"),
        }
    }
}

fn plain_polynomial(c: &[f64], w: f64) -> f64 {
    c.iter()
        .enumerate()
        .map(|(j, c)| c * w.powi(j as i32))
        .sum()
}

fn plain_apply(c: &[f64], lo: f64, hi: f64, w: f64) -> f64 {
    let slope = |w: f64| {
        (1..c.len())
            .map(|j| j as f64 * c[j] * w.powi(j as i32 - 1))
            .sum::<f64>()
    };
    if w < lo {
        plain_polynomial(c, lo) + slope(lo) * (w - lo)
    } else if w > hi {
        plain_polynomial(c, hi) + slope(hi) * (w - hi)
    } else {
        plain_polynomial(c, w)
    }
}

fn plain_invert(c: &[f64], lo: f64, hi: f64, u: f64) -> f64 {
    let (mut a, mut b) = (lo - 100.0, hi + 100.0);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if plain_apply(c, lo, hi, m) < u {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

#[test]
fn the_map_and_its_inverse_agree_with_plain_references_on_random_maps() {
    let mut rng = rng(0x6d61_7001);
    for _ in 0..300 {
        let (c, lo, hi, map) = random_map(&mut rng);
        assert_eq!(map.coefficients(), &c[..]);
        for _ in 0..40 {
            let w = lo - 0.5 + (hi - lo + 1.0) * rng.random::<f64>();
            let u = plain_apply(&c, lo, hi, w);
            assert!((map.apply(w) - u).abs() <= 1e-12 * (1.0 + u.abs()));
            let back = map.invert(u);
            assert!(
                (back - plain_invert(&c, lo, hi, u)).abs() <= 1e-9,
                "invert({u}) = {back}"
            );
            assert!((back - w).abs() <= 1e-9, "round trip {w} -> {u} -> {back}");
        }
        assert!(map.apply(f64::NAN).is_nan() && map.invert(f64::NAN).is_nan());
    }
}

#[test]
fn maps_that_do_not_rise_are_refused_and_bad_shapes_named() {
    // w - w^2 falls beyond w = 0.5.
    assert!(matches!(
        OutputMap::new(&[0.0, 1.0, -1.0], 0.0, 1.0),
        Err(CoreError::NotPositive { .. })
    ));
    // w^3 - 0.75 w... slope 3 w^2 - 0.75 < 0 around 0 only: a maximum of the slope's
    // derivative's sign change inside the range must be found.
    assert!(matches!(
        OutputMap::new(&[0.0, -0.001, 0.0, 1.0], -1.0, 1.0),
        Err(CoreError::NotPositive { .. })
    ));
    assert!(OutputMap::new(&[0.0, 1.0, 0.0, 0.2], -1.0, 1.0).is_ok());
    assert!(matches!(
        OutputMap::new(&[1.0], 0.0, 1.0),
        Err(CoreError::LengthMismatch { .. })
    ));
    assert!(matches!(
        OutputMap::new(&[0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0.0, 1.0),
        Err(CoreError::TooLarge { .. })
    ));
    assert!(matches!(
        OutputMap::new(&[0.0, f64::NAN], 0.0, 1.0),
        Err(CoreError::NonFinite { .. })
    ));
    assert!(matches!(
        OutputMap::new(&[0.0, 1.0], 1.0, 1.0),
        Err(CoreError::InvalidRange { .. })
    ));
}

/// The mapped IHC drives the MPIM to `psi(y_d)`, and the mapped DIHC's drive is `psi^-1` of
/// its MPIM's output; both within their limits and never NaN, NaN desired samples included.
#[test]
fn mapped_compensators_invert_the_mapped_model_within_their_limits() {
    let mut rng = rng(0x6d61_7002);
    for _ in 0..60 {
        let n = 1 + (rng.random::<f64>() * 12.0) as usize;
        let model: Mpim<f64, Vec<f64>> = random_invertible_model(&mut rng, n);
        let (_, _, _, map) = random_map(&mut rng);
        let limits = unit_limits();
        let ihc = Ihc::<f64, Vec<f64>>::new(&model, limits, SolveMode::Exact).unwrap();
        let mut mapped = MappedCompensator::new(ihc, map, MapSide::Desired, limits);
        let mut plant = model.clone();
        let mut reference = model.clone();
        let top = {
            let mut m = model.clone();
            m.step(1.0)
        };
        for k in 0..400 {
            let target = top * (0.05 + 0.9 * rng.random::<f64>());
            let desired = map.invert(target);
            let desired = if k % 97 == 13 { f64::NAN } else { desired };
            let v = mapped.step(desired);
            assert!(v.is_finite() && (0.0..=1.0).contains(&v));
            let h = plant.step(v);
            reference.step(v);
            if desired.is_finite() {
                assert!(
                    (h - target).abs() <= 1e-7,
                    "H[v] {h} against psi(y_d) {target}"
                );
            }
        }
        assert_eq!(mapped.limits(), limits);

        // DIHC: a random map on the voltage side, limits [0.1, 0.9].
        let limits = OutputLimits::new(0.1, 0.9).unwrap();
        let inner_limits =
            MappedCompensator::<f64, Dihc<f64, Vec<f64>>>::mapped_limits(&map, limits).unwrap();
        let dihc = Dihc::<f64, Vec<f64>>::new(&model, 0.0, 1.0, inner_limits).unwrap();
        let mut mapped = MappedCompensator::new(dihc, map, MapSide::Control, limits);
        let mut plain = model.clone();
        for k in 0..400 {
            let desired = if k % 89 == 7 {
                f64::NAN
            } else {
                rng.random::<f64>()
            };
            let v = mapped.step(desired);
            assert!(v.is_finite() && (0.1..=0.9).contains(&v), "{v}");
            if desired.is_finite() {
                let u = plain.step(desired);
                let expected = map.invert(u).clamp(0.1, 0.9);
                assert!((v - expected).abs() <= 1e-9, "{v} against {expected}");
            }
        }
    }
}

//! The delayed IHC's proofs, before a sample, that its output stays within the limits and (the
//! guarded loop's, [`proven_reachable`]) that its reach test passes.
//!
//! The delayed loop (eq. (5) with `v(t - Ts)` in the cubic) knows its target `w = y_d - h(v(t -
//! Ts))` before the sample and evaluates `v = P1^{-1}[w]` directly (section 3.1). Evaluated in
//! two passes over the operators, the sum at `w` first and the memory fed after, it feeds the
//! memory only when `v` lies within the limits (beyond them the loop walks to the limit
//! instead). When the bound below proves `v` within the limits before the evaluation, one pass
//! does both, as the DIHC's does (`crate::bank::dihc`), with the same bits: the memory and the
//! sum of that pass are those of the two.
//!
//! **The bound.** Let `v_prev = a w_prev + sum_i b_i z_i` be the bank's output at its last
//! input `w_prev` (memory `z_i`). Fed `w`, each one-sided play operator's memory moves towards
//! `w` by at most `|w - w_prev|`, the operators of smaller thresholds at least as far as those
//! of larger ones (fed from rest, the memory `z(r)` of the one-sided operators `max(x - r,
//! min(x, z))` stays non-increasing in the threshold `r` with a slope of at least -1: the two
//! bounds `x - r` and `x` it is clamped between have slopes -1 and 0), so the moves fold into
//! the segments' slopes `a + b_1 + ... + b_k`, `P1^{-1}` is monotone and moves by at most `|w -
//! w_prev| / q`, where `q` is the bank's least reciprocal slope `1 / max(a, a + b_1 + ... +
//! b_k)` (`crate::walk::PlayBank::least_inverse_alpha`; the inverse is increasing, eq. (7)'s
//! invertibility). So `v` lies within `[min, max]` when, rising, `v_prev + (w - w_prev) / q <=
//! max` and `v_prev >= min`, and falling the mirror image, each with a margin for rounding.
//!
//! **The margin.** The evaluated sums differ from the exact ones by at most `(n + 2) eps/2` of
//! the size of their terms, `sum |b_i z_i| <= (|a| + sum |b_i|) |x| + sum |b_i r_i|` at input
//! `x` (`|z_i| <= |x| + r_i`); the play operators' `x - r_i` round by `eps/2` of the same; and
//! after a walk the memory sum is the walk's segment sum, recomputed from the memory every
//! `crate::walk::SYNC_INTERVAL` (64) walks, each adding a few roundings of the size of the
//! terms at its own input (fed, like this one, where the drive is within the limits: an
//! argued bound, not a formal one). With
//! at most `crate::DIRECT_OPERATORS` (16) operators that is below `64 (16 + 4)` half-ulps of
//! the terms' size; the margin is `4096 eps` of it (six times more), plus `4096 eps` of
//! `|min| + |max|` for the rounding of the test itself. A lane it does not prove evaluates in
//! two passes as before; a proof the rounding could break would leave a lane's memory fed where
//! its single-channel twin's is not, which the bank's property tests (every channel equal to
//! its twin, bit for bit) would see.

use super::lanes::{Lanes, Mask};
use crate::Real;

type L<T, const W: usize> = Lanes<T, W>;

/// A lane's play-operator bank at its last input, as the bound reads it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LastInput<T, const W: usize> {
    /// The bank's output there, `a w(t - Ts) + sum b_i z_i` (`super::play::PlayState::output`).
    pub output: L<T, W>,
    /// The last input fed, `w(t - Ts)`.
    pub input: L<T, W>,
    /// `crate::walk::PlayBank::least_inverse_alpha`.
    pub least_inverse_alpha: L<T, W>,
    /// `crate::walk::PlayBank::slope_sum` and `reach_sum`: the scale of the rounding.
    pub slope_sum: L<T, W>,
    pub reach_sum: L<T, W>,
}

/// The lanes whose `P1^{-1}[w]`, evaluated directly from the memory at `last.input`, is proven
/// to lie within `[min, max]` before it is evaluated (see the [module documentation](self)).
/// Not finite anywhere: not proven.
#[inline(always)]
pub(crate) fn proven_within<T: Real, const W: usize>(
    last: &LastInput<T, W>,
    w: L<T, W>,
    min: L<T, W>,
    max: L<T, W>,
) -> Mask<T, W> {
    within_by(last, w, min, max, margin(last, w, min, max))
}

/// [`proven_within`] with its rounding allowance `margin` computed.
#[inline(always)]
fn within_by<T: Real, const W: usize>(
    last: &LastInput<T, W>,
    w: L<T, W>,
    min: L<T, W>,
    max: L<T, W>,
    margin: L<T, W>,
) -> Mask<T, W> {
    let zero = Lanes::zero();
    let v_prev = last.output;
    let up = (w - last.input).max(zero);
    let down = (last.input - w).max(zero);
    let q = last.least_inverse_alpha;
    up.le(q * (max - v_prev - margin)) & down.le(q * (v_prev - margin - min))
}

/// The allowance of [`proven_within`] for rounding: `4096 eps` of the size of the sums' terms
/// at `w` and at the last input, and of the limits (see the [module documentation](self)).
#[inline(always)]
fn margin<T: Real, const W: usize>(
    last: &LastInput<T, W>,
    w: L<T, W>,
    min: L<T, W>,
    max: L<T, W>,
) -> L<T, W> {
    let size = last.slope_sum * (w.abs() + last.input.abs()) + last.reach_sum + last.reach_sum;
    tolerance::<T, W>() * (size + min.abs() + max.abs())
}

/// `4096 eps`.
#[inline(always)]
fn tolerance<T: Real, const W: usize>() -> L<T, W> {
    Lanes::splat(T::epsilon() * T::from_f64(4096.0))
}

/// The lanes whose guarded delayed loop (`crate::SolveMode::DelayedGuarded`) is proven, before
/// `v = P1^{-1}[w]` is evaluated, to pass its reach test (`crate::ihc::guarded_reach`: `y_d`
/// reachable within the limits, so `v` is the sample's output without a walk) by the test's
/// bound at the limit, among the lanes [`proven_within`] proves (its test is part of this
/// one, with the same allowance): `h_min` and `h_max` are the remainder at the limits,
/// `f_exact = w(t - Ts) + h(v(t - Ts)) - y_d` the exact residual at the last sample.
///
/// Rising (`f_exact <= 0`), the reach test passes when `w >= w(t - Ts)` and `w + q (max - v) +
/// h(max) - y_d >= 0` (`q` the least reciprocal slope). Where [`proven_within`] holds, `v <=
/// v_prev + (w - w(t - Ts)) / q + margin` (the module documentation's bound, `margin` its
/// rounding allowance), so the test's left side is at least `w(t - Ts) + q (max - v_prev -
/// margin) + h(max) - y_d`, which this computes before the evaluation; `w` cancels. Falling,
/// the mirror image with `min`. The remainder's values at the limits are the same bits in both
/// (the same function of the same limits), so only the two expressions' additions and
/// products round: each within a few `eps` of the size of its terms, against an allowance of
/// `4096 eps` of it. `w` and `w(t - Ts)` are compared as the test compares them.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn proven_reachable<T: Real, const W: usize>(
    last: &LastInput<T, W>,
    w: L<T, W>,
    desired: L<T, W>,
    f_exact: L<T, W>,
    h_min: L<T, W>,
    h_max: L<T, W>,
    min: L<T, W>,
    max: L<T, W>,
) -> Mask<T, W> {
    let zero = Lanes::zero();
    let (w_prev, v_prev, q) = (last.input, last.output, last.least_inverse_alpha);
    let margin = margin(last, w, min, max);
    let up = w_prev + q * (max - v_prev - margin) + h_max - desired;
    let down = w_prev - q * (v_prev - margin - min) + h_min - desired;
    let size = w.abs()
        + w_prev.abs()
        + q * (max.abs() + min.abs() + v_prev.abs() + margin)
        + h_max.abs()
        + h_min.abs()
        + desired.abs();
    let slack = tolerance::<T, W>() * size;
    let rises = w.ge(w_prev) & up.ge(slack);
    let falls = w.le(w_prev) & down.le(-slack);
    within_by(last, w, min, max, margin) & Mask::choose(f_exact.le(zero), rises, falls)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Bounded;
    use crate::walk::PlayBank;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random bank of `P1^{-1}`'s shape (eq. (7)): thresholds from 0 upwards, the first
    /// weight positive and the others of either sign, every slope `a + b_1 + ... + b_k`
    /// positive; scaled by up to 100 either way.
    fn random_bank<T: Real>(rng: &mut ChaCha8Rng) -> PlayBank<T, Bounded<T, 16>> {
        let n = 1 + (rng.random::<u32>() % 16) as usize;
        let scale = 10f64.powf(4.0 * rng.random::<f64>() - 2.0);
        let a = 0.05 + rng.random::<f64>();
        let mut thresholds = [T::zero(); 16];
        let mut weights = [T::zero(); 16];
        let mut slope = a;
        for i in 0..n {
            thresholds[i] = T::from_f64(scale * i as f64 / n as f64);
            let b = if i == 0 {
                rng.random::<f64>()
            } else {
                // Never below 5 % of the slope so far.
                (2.0 * rng.random::<f64>() - 1.0) * 0.95 * slope
            };
            slope += b;
            weights[i] = T::from_f64(b);
        }
        PlayBank::new(T::from_f64(a), &thresholds[..n], &weights[..n]).expect("positive slopes")
    }

    /// A random bank after a random history of up to 40 inputs within twice its largest
    /// threshold (at least 1) either way, and that scale.
    fn random_history<T: Real>(rng: &mut ChaCha8Rng) -> (PlayBank<T, Bounded<T, 16>>, f64) {
        let mut bank = random_bank::<T>(rng);
        let scale = bank
            .thresholds()
            .last()
            .map_or(1.0, |&r| Real::to_f64(r))
            .max(1.0);
        for _ in 0..(rng.random::<u32>() % 40) {
            bank.feed(T::from_f64(scale * (4.0 * rng.random::<f64>() - 2.0)));
        }
        (bank, scale)
    }

    /// What the bounds read of `bank`, in one lane.
    fn last_input<T: Real>(bank: &PlayBank<T, Bounded<T, 16>>) -> LastInput<T, 1> {
        LastInput {
            output: Lanes::splat(bank.output()),
            input: Lanes::splat(bank.input()),
            least_inverse_alpha: Lanes::splat(bank.least_inverse_alpha()),
            slope_sum: Lanes::splat(bank.slope_sum()),
            reach_sum: Lanes::splat(bank.reach_sum()),
        }
    }

    /// Random banks after random histories of inputs, and limits placed around the bound's
    /// edge (within a few per cent of the move it allows): wherever the bound proves a target
    /// `w` within the limits, the direct evaluation `P1^{-1}[w]` (the bits the bank computes)
    /// is within them; and it proves most targets that stay well inside.
    fn bound_holds<T: Real>(seed: u64) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (mut proven, mut inside, mut roomy, mut roomy_proven) = (0, 0, 0, 0);
        for _ in 0..400 {
            let (bank, scale) = random_history::<T>(&mut rng);
            let q = bank.least_inverse_alpha();
            let last = last_input(&bank);
            for _ in 0..50 {
                let step =
                    scale * 10f64.powf(-6.0 * rng.random::<f64>()) * (rng.random::<f64>() - 0.5);
                let w = T::from_f64(Real::to_f64(bank.input()) + step);
                let v_prev = Real::to_f64(bank.output());
                let reach = step.abs() / Real::to_f64(q);
                // Limits at the bound's edge, give or take a few per cent of the move (and of
                // the rounding), or far away.
                let roomy_case = rng.random::<f64>() < 0.2;
                let edge = |rng: &mut ChaCha8Rng| {
                    if roomy_case {
                        reach * 2.0 + 0.1 * scale
                    } else {
                        reach * (0.9 + 0.2 * rng.random::<f64>())
                            + 1e-6 * scale * (rng.random::<f64>() - 0.5)
                    }
                };
                let max = T::from_f64(v_prev + edge(&mut rng));
                let min = T::from_f64(v_prev - edge(&mut rng));
                let is_proven =
                    proven_within(&last, Lanes::splat(w), Lanes::splat(min), Lanes::splat(max))
                        .all();
                let v = bank.output_at(w);
                if is_proven {
                    proven += 1;
                    assert!(
                        v >= min && v <= max,
                        "seed {seed}: proven but P1^-1[{w}] = {v} outside [{min}, {max}]"
                    );
                }
                inside += usize::from(v >= min && v <= max);
                if roomy_case {
                    roomy += 1;
                    roomy_proven += usize::from(is_proven);
                }
            }
        }
        // Not vacuous: the tight cases prove some, the roomy ones nearly all.
        assert!(
            proven > 1000 && proven < inside,
            "proven {proven} of {inside} inside"
        );
        assert!(
            roomy_proven * 100 >= roomy * 99,
            "roomy {roomy_proven} of {roomy}"
        );
    }

    /// Random banks after random histories, a random odd cubic as the remainder, random
    /// under-relaxations (half of them 1), and the desired position placed at the guarded
    /// loop's reach edge (its bound at the limit within a few per cent of the move, either
    /// side): wherever [`proven_within`] and [`proven_reachable`] both prove a lane, the
    /// single-channel loop's own reach test (`crate::ihc::guarded_reach`, with the bits the
    /// bank evaluates for `v`) passes; and of the lanes [`proven_within`] proves whose reach
    /// test passes, [`proven_reachable`] proves nearly all.
    fn reach_holds<T: Real>(seed: u64) {
        use crate::OutputLimits;
        use crate::ihc::guarded_reach;
        use crate::solve::{OddCubic, Remainder};
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (mut proven, mut passes, mut tight_proven, mut clear_proven) = (0, 0, 0, 0);
        for _ in 0..400 {
            let (mut bank, scale) = random_history::<T>(&mut rng);
            // Half the histories end far out the way the loop goes on: every operator then
            // moves with the input, and where the bank's steepest slope is its last, the
            // bound on `v` is met with equality (the allowances are what is left).
            let rising = rng.random::<bool>();
            if rng.random::<bool>() {
                let far = if rising { 3.0 } else { -3.0 };
                bank.feed(T::from_f64(far * scale));
            }
            let q = bank.least_inverse_alpha();
            let (w_prev, v_prev) = (bank.input(), bank.output());
            let last = last_input(&bank);
            let v_scale = Real::to_f64(v_prev).abs().max(scale);
            for _ in 0..50 {
                // h(v) = c v^3, of either sign, up to a tenth of the bank's scale at v_scale.
                let c = (2.0 * rng.random::<f64>() - 1.0) * 0.1 * v_scale / v_scale.powi(3);
                let h = OddCubic(T::from_f64(c));
                let room = |rng: &mut ChaCha8Rng| v_scale * (0.01 + rng.random::<f64>());
                let max = T::from_f64(Real::to_f64(v_prev) + room(&mut rng));
                let min = T::from_f64(Real::to_f64(v_prev) - room(&mut rng));
                let (h_min, h_max) = (h.value(min), h.value(max));
                // The reach bound at the limit, moved by a few per cent of its own scale
                // (or of the rounding) either way.
                let edge = if rising {
                    Real::to_f64(w_prev)
                        + Real::to_f64(q) * (Real::to_f64(max) - Real::to_f64(v_prev))
                        + Real::to_f64(h_max)
                } else {
                    Real::to_f64(w_prev)
                        - Real::to_f64(q) * (Real::to_f64(v_prev) - Real::to_f64(min))
                        + Real::to_f64(h_min)
                };
                let tight = rng.random::<f64>() < 0.5;
                let shift = if tight {
                    // From the rounding of f64 to that of f32 and beyond.
                    let size = 10f64.powf(-17.0 * rng.random::<f64>());
                    size * v_scale * (rng.random::<f64>() - 0.5)
                } else {
                    0.1 * v_scale * (rng.random::<f64>() - 0.5)
                };
                let desired = T::from_f64(edge + shift);
                let h_prev = h.value(v_prev);
                let f_exact = w_prev + h_prev - desired;
                let relaxation = if rng.random::<bool>() {
                    T::one()
                } else {
                    T::from_f64(rng.random::<f64>().max(1e-3))
                };
                // As `super::plant::guarded_target` computes it.
                let w = if relaxation < T::one() {
                    w_prev - relaxation * f_exact
                } else {
                    desired - h_prev
                };
                let lane = Lanes::splat;
                let within = proven_within(&last, lane(w), lane(min), lane(max)).all();
                let is_proven = within
                    && proven_reachable(
                        &last,
                        lane(w),
                        lane(desired),
                        lane(f_exact),
                        lane(h_min),
                        lane(h_max),
                        lane(min),
                        lane(max),
                    )
                    .all();
                let v = bank.output_at(w);
                let limits = OutputLimits::new(min, max).expect("min < max");
                let passed = guarded_reach(limits, q, h, desired, f_exact, w_prev, w, v);
                // Reachable at the limit by more than the rounding's allowance.
                let clear = if rising { shift } else { -shift } < -1e-2 * v_scale;
                passes += usize::from(passed && within && clear);
                clear_proven += usize::from(is_proven && clear);
                if is_proven {
                    proven += 1;
                    tight_proven += usize::from(tight);
                    assert!(
                        passed,
                        "seed {seed}: proven, but the reach test fails at w = {w}, v = {v}, \
                         y_d = {desired}, limits [{min}, {max}]"
                    );
                }
            }
        }
        // Not vacuous: nearly every lane that passes, of those proven within the limits, is
        // proven to; some of them at the edge.
        assert!(
            clear_proven * 100 >= passes * 95 && tight_proven > 20,
            "proven {proven} ({tight_proven} at the edge), {clear_proven} of {passes} clear ones"
        );
    }

    #[test]
    fn a_proven_reach_passes_the_guarded_loops_test_f64() {
        for seed in 0..4 {
            reach_holds::<f64>(0x5EED_2000 + seed);
        }
    }

    #[test]
    fn a_proven_reach_passes_the_guarded_loops_test_f32() {
        for seed in 0..4 {
            reach_holds::<f32>(0x5EED_3000 + seed);
        }
    }

    #[test]
    fn a_proven_target_evaluates_within_the_limits_f64() {
        for seed in 0..4 {
            bound_holds::<f64>(0x5EED_0000 + seed);
        }
    }

    #[test]
    fn a_proven_target_evaluates_within_the_limits_f32() {
        for seed in 0..4 {
            bound_holds::<f32>(0x5EED_1000 + seed);
        }
    }
}

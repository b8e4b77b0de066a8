//! The plain delayed IHC's proof, before a sample, that its output stays within the limits.
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
    let zero = Lanes::zero();
    let v_prev = last.output;
    let tol = Lanes::splat(T::epsilon() * T::from_f64(4096.0));
    let size = last.slope_sum * (w.abs() + last.input.abs()) + last.reach_sum + last.reach_sum;
    let margin = tol * (size + min.abs() + max.abs());
    let up = (w - last.input).max(zero);
    let down = (last.input - w).max(zero);
    let q = last.least_inverse_alpha;
    up.le(q * (max - v_prev - margin)) & down.le(q * (v_prev - margin - min))
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

    /// Random banks after random histories of inputs, and limits placed around the bound's
    /// edge (within a few per cent of the move it allows): wherever the bound proves a target
    /// `w` within the limits, the direct evaluation `P1^{-1}[w]` (the bits the bank computes)
    /// is within them; and it proves most targets that stay well inside.
    fn bound_holds<T: Real>(seed: u64) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (mut proven, mut inside, mut roomy, mut roomy_proven) = (0, 0, 0, 0);
        for _ in 0..400 {
            let mut bank = random_bank::<T>(&mut rng);
            let scale = bank
                .thresholds()
                .last()
                .map_or(1.0, |&r| Real::to_f64(r))
                .max(1.0);
            for _ in 0..(rng.random::<u32>() % 40) {
                bank.feed(T::from_f64(scale * (4.0 * rng.random::<f64>() - 2.0)));
            }
            let q = bank.least_inverse_alpha();
            for _ in 0..50 {
                let last = LastInput::<T, 1> {
                    output: Lanes::splat(bank.output()),
                    input: Lanes::splat(bank.input()),
                    least_inverse_alpha: Lanes::splat(q),
                    slope_sum: Lanes::splat(bank.slope_sum()),
                    reach_sum: Lanes::splat(bank.reach_sum()),
                };
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

//! `W` values side by side, one per channel of a block, and the masks that stand in for the
//! single-channel code's branches.
//!
//! Every operation is the scalar operation applied lane by lane (written out once per lane or
//! as a loop over the lanes, see [`lanewise`]) with no branch inside, so that the compiler
//! turns it into vector instructions (and, on a target without them, into the scalar code it
//! replaces). A branch of
//! the single-channel compensator becomes a [`Mask`] and a [`Lanes::select`]: each lane
//! computes exactly the operations its single-channel twin computes, in the same order, so its
//! results are the same bits.

// Lane loops (optimised builds) index every array by the lane, the form the compiler vectorises
// (each lane the same operation): clearer here than zipped iterators.
#![allow(clippy::needless_range_loop)]

use core::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use crate::Real;

/// `[f(0), f(1), ..., f(W - 1)]`, in that order.
///
/// With debug assertions (the `dev` and `test` profiles) it is written out lane by lane,
/// without a loop, for blocks of up to eight lanes (the branch for `W` is chosen when the code
/// is generated, an inline `const` condition), and every lane operation below takes it: a loop
/// per lane operation left the optimiser tens of thousands of small loops in one kernel to
/// rotate and unroll one by one, most of the compile time of every crate that instantiates a
/// bank (one IHC bank's three vector paths at `opt-level = 1`: 4 min 15 s of CPU with loops,
/// 1 min 40 s written out; the bank tests 37 min, 5.6 min). Optimised builds keep the loops
/// (`core::array::from_fn` here, the loops below): the loop vectoriser turns them into vector
/// instructions where the written-out lanes, left to the straight-line vectoriser, ran the
/// delayed IHC kernel 30 % slower. Both compute the same operations in the same order, the
/// same bits: `lanewise` is checked against `from_fn` below, and the bank tests compare every
/// channel with its single compensator in the written-out form. The same tests run on the loop
/// form with `cargo test --release -p hystcomp-core --test bank_f64 --test bank_f32` (all
/// passed on every vector path, AVX-512 included); CI leaves that run out, since its build
/// alone takes 9 min on the project's 2-core machine.
#[inline(always)]
pub(crate) fn lanewise<V, const W: usize>(f: impl FnMut(usize) -> V) -> [V; W] {
    #[cfg(debug_assertions)]
    let mut f = f;
    #[cfg(debug_assertions)]
    macro_rules! written_out {
        ($($n:literal => [$($l:literal),*]);*) => {$(
            if const { W == $n } {
                let out: [V; $n] = [$(f($l)),*];
                // SAFETY: `W == $n`: `[V; $n]` and `[V; W]` are the same type; `out` is
                // forgotten, so that nothing is dropped twice.
                let out = core::mem::ManuallyDrop::new(out);
                return unsafe { core::mem::transmute_copy(&*out) };
            }
        )*};
    }
    #[cfg(debug_assertions)]
    written_out!(
        1 => [0];
        2 => [0, 1];
        3 => [0, 1, 2];
        4 => [0, 1, 2, 3];
        5 => [0, 1, 2, 3, 4];
        6 => [0, 1, 2, 3, 4, 5];
        7 => [0, 1, 2, 3, 4, 5, 6];
        8 => [0, 1, 2, 3, 4, 5, 6, 7]
    );
    core::array::from_fn(f)
}

/// One value per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Lanes<T, const W: usize>(pub [T; W]);

/// One flag per lane: the vector form of a condition. A lane is all ones (set) or all zeros in
/// an integer as wide as `T` ([`Real::Bits`]), the form vector compares produce and blends
/// consume, so that a condition never leaves the vector registers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Mask<T: Real, const W: usize>(pub [T::Bits; W]);

impl<T: Copy, const W: usize> Lanes<T, W> {
    /// The same value in every lane.
    #[inline(always)]
    pub fn splat(value: T) -> Self {
        #[cfg(debug_assertions)]
        return Lanes(lanewise(|_| value));
        #[cfg(not(debug_assertions))]
        {
            Lanes([value; W])
        }
    }

    /// `f(a, b)` lane by lane.
    #[inline(always)]
    pub fn zip<U: Copy, V: Copy>(self, other: Lanes<U, W>, f: impl Fn(T, U) -> V) -> Lanes<V, W> {
        Lanes(lanewise(|l| f(self.0[l], other.0[l])))
    }

    /// `f(a)` lane by lane.
    #[inline(always)]
    pub fn map<V: Copy>(self, f: impl Fn(T) -> V) -> Lanes<V, W> {
        Lanes(lanewise(|l| f(self.0[l])))
    }

    /// `f(a)` lane by lane, as a mask.
    #[inline(always)]
    pub fn test<M: Real>(self, f: impl Fn(T) -> bool) -> Mask<M, W> {
        #[cfg(debug_assertions)]
        return Mask(lanewise(|l| Mask::<M, W>::flag(f(self.0[l]))));
        #[cfg(not(debug_assertions))]
        {
            let mut out = [M::Bits::default(); W];
            for l in 0..W {
                out[l] = Mask::<M, W>::flag(f(self.0[l]));
            }
            Mask(out)
        }
    }

    /// `f(a, b)` lane by lane, as a mask.
    #[inline(always)]
    pub fn compare<M: Real>(self, other: Self, f: impl Fn(T, T) -> bool) -> Mask<M, W> {
        #[cfg(debug_assertions)]
        return Mask(lanewise(|l| Mask::<M, W>::flag(f(self.0[l], other.0[l]))));
        #[cfg(not(debug_assertions))]
        {
            let mut out = [M::Bits::default(); W];
            for l in 0..W {
                out[l] = Mask::<M, W>::flag(f(self.0[l], other.0[l]));
            }
            Mask(out)
        }
    }

    /// `if mask { yes } else { no }` lane by lane.
    #[inline(always)]
    pub fn select<M: Real>(mask: Mask<M, W>, yes: Self, no: Self) -> Self {
        #[cfg(debug_assertions)]
        return Lanes(lanewise(|l| {
            if mask.0[l] != M::Bits::default() {
                yes.0[l]
            } else {
                no.0[l]
            }
        }));
        #[cfg(not(debug_assertions))]
        {
            let mut out = no.0;
            for l in 0..W {
                out[l] = if mask.0[l] != M::Bits::default() {
                    yes.0[l]
                } else {
                    no.0[l]
                };
            }
            Lanes(out)
        }
    }

    /// `self` where `mask` is set, `no` elsewhere.
    #[inline(always)]
    pub fn or_keep<M: Real>(self, mask: Mask<M, W>, no: Self) -> Self {
        Self::select(mask, self, no)
    }
}

impl<T: Real, const W: usize> Lanes<T, W> {
    #[inline(always)]
    pub fn zero() -> Self {
        Self::splat(T::zero())
    }

    #[inline(always)]
    pub fn max(self, other: Self) -> Self {
        self.zip(other, |a, b| a.max(b))
    }

    #[inline(always)]
    pub fn min(self, other: Self) -> Self {
        self.zip(other, |a, b| a.min(b))
    }

    #[inline(always)]
    pub fn abs(self) -> Self {
        self.map(|a| a.abs())
    }

    #[inline(always)]
    pub fn lt(self, other: Self) -> Mask<T, W> {
        self.compare(other, |a, b| a < b)
    }

    #[inline(always)]
    pub fn le(self, other: Self) -> Mask<T, W> {
        self.compare(other, |a, b| a <= b)
    }

    #[inline(always)]
    pub fn gt(self, other: Self) -> Mask<T, W> {
        self.compare(other, |a, b| a > b)
    }

    #[inline(always)]
    pub fn ge(self, other: Self) -> Mask<T, W> {
        self.compare(other, |a, b| a >= b)
    }

    #[inline(always)]
    pub fn is_finite(self) -> Mask<T, W> {
        self.test(|a| a.is_finite())
    }

    #[inline(always)]
    pub fn is_nan(self) -> Mask<T, W> {
        self.test(|a| a.is_nan())
    }
}

macro_rules! lane_operator {
    ($trait:ident, $method:ident, $op:tt) => {
        impl<T: Copy + $trait<Output = T>, const W: usize> $trait for Lanes<T, W> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, other: Self) -> Self {
                self.zip(other, |a, b| a $op b)
            }
        }
    };
}

lane_operator!(Add, add, +);
lane_operator!(Sub, sub, -);
lane_operator!(Mul, mul, *);
lane_operator!(Div, div, /);

impl<T: Copy + Neg<Output = T>, const W: usize> Neg for Lanes<T, W> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        self.map(|a| -a)
    }
}

impl<T: Real, const W: usize> Mask<T, W> {
    /// The lane of a condition: all ones if set.
    #[inline(always)]
    pub fn flag(set: bool) -> T::Bits {
        if set {
            !T::Bits::default()
        } else {
            T::Bits::default()
        }
    }

    /// Every lane set to `value`.
    #[inline(always)]
    pub fn splat(value: bool) -> Self {
        #[cfg(debug_assertions)]
        return Mask(lanewise(|_| Self::flag(value)));
        #[cfg(not(debug_assertions))]
        {
            Mask([Self::flag(value); W])
        }
    }

    /// Whether any lane is set (no early exit, so that it vectorises).
    #[inline(always)]
    pub fn any(self) -> bool {
        #[cfg(debug_assertions)]
        {
            let mut all = T::Bits::default();
            lanewise::<(), W>(|l| all = all | self.0[l]);
            all != T::Bits::default()
        }
        #[cfg(not(debug_assertions))]
        {
            self.0.iter().fold(T::Bits::default(), |a, &b| a | b) != T::Bits::default()
        }
    }

    /// Whether every lane is set.
    #[inline(always)]
    pub fn all(self) -> bool {
        !(!self).any()
    }

    /// `if choose { yes } else { no }` lane by lane.
    #[inline(always)]
    pub fn choose(choose: Self, yes: Self, no: Self) -> Self {
        (choose & yes) | (!choose & no)
    }

    /// `self && !other` lane by lane.
    #[inline(always)]
    pub fn and_not(self, other: Self) -> Self {
        self & !other
    }

    /// 1 where set, 0 elsewhere.
    #[inline(always)]
    pub fn count(self) -> Lanes<u64, W> {
        Lanes(self.0).map(|m| u64::from(T::low_bit(m)))
    }

    /// 1 where set, 0 elsewhere, as counts of operators.
    #[inline(always)]
    pub fn count32(self) -> Lanes<u32, W> {
        Lanes(self.0).map(T::low_bit)
    }
}

impl<T: Real, const W: usize> BitAnd for Mask<T, W> {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, other: Self) -> Self {
        #[cfg(debug_assertions)]
        return Mask(lanewise(|l| self.0[l] & other.0[l]));
        #[cfg(not(debug_assertions))]
        {
            let mut out = self.0;
            for l in 0..W {
                out[l] = self.0[l] & other.0[l];
            }
            Mask(out)
        }
    }
}

impl<T: Real, const W: usize> BitOr for Mask<T, W> {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, other: Self) -> Self {
        #[cfg(debug_assertions)]
        return Mask(lanewise(|l| self.0[l] | other.0[l]));
        #[cfg(not(debug_assertions))]
        {
            let mut out = self.0;
            for l in 0..W {
                out[l] = self.0[l] | other.0[l];
            }
            Mask(out)
        }
    }
}

impl<T: Real, const W: usize> Not for Mask<T, W> {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        #[cfg(debug_assertions)]
        return Mask(lanewise(|l| !self.0[l]));
        #[cfg(not(debug_assertions))]
        {
            let mut out = self.0;
            for l in 0..W {
                out[l] = !self.0[l];
            }
            Mask(out)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::lanewise;
    use alloc::string::{String, ToString};
    use alloc::vec::Vec;

    /// `lanewise` against its plain reference, `core::array::from_fn`, for `W` lanes: the same
    /// values, each lane's closure called once and in lane order, owned values (`String`)
    /// moved out once (a double drop would abort the test).
    fn agrees<const W: usize>() {
        let mut calls = Vec::new();
        let out: [u64; W] = lanewise(|l| {
            calls.push(l);
            (l as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ W as u64
        });
        let reference: [u64; W] =
            core::array::from_fn(|l| (l as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ W as u64);
        assert_eq!(out, reference, "{W} lanes");
        assert_eq!(calls, (0..W).collect::<Vec<_>>(), "{W} lanes: calls");
        let owned: [String; W] = lanewise(|l| l.to_string().repeat(l + 1));
        let reference: [String; W] = core::array::from_fn(|l| l.to_string().repeat(l + 1));
        assert_eq!(owned, reference, "{W} lanes: owned");
    }

    #[test]
    fn written_out_lanes_equal_the_loop_for_every_width() {
        agrees::<1>();
        agrees::<2>();
        agrees::<3>();
        agrees::<4>();
        agrees::<5>();
        agrees::<6>();
        agrees::<7>();
        agrees::<8>();
        // Beyond the written-out widths: the loop itself.
        agrees::<9>();
        agrees::<16>();
    }
}

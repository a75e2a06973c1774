//! Hyper-dual numbers with M eps1 and N eps2 directions, for the exact
//! Hessians of the transcription (see `transcription::HessPlan`).
//!
//! The same numbers as `num_dual::HyperDualSVec64<M, N>`: a value, the
//! first derivatives along eps1 and eps2 and the mixed second derivatives
//! eps1 × eps2, each derivative part absent (zero) until an operation makes
//! it non-zero. What differs is the arithmetic: a product or a chain rule
//! writes each part once, in one loop over its entries, where num-dual
//! builds every term as a matrix of its own and moves the partial sums
//! (on the jump's 13 × 17 passes, memory copies took about half the time of
//! a Hessian evaluation). The tests check every operation against
//! num-dual's.

use num_dual::{DualNum, DualStruct, Mappable};
use num_traits::{FromPrimitive, Inv, Num, One, Signed, Zero};
use std::cmp::Ordering;
use std::fmt;
use std::iter::{Product, Sum};
use std::ops::{
    Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Rem, RemAssign, Sub, SubAssign,
};

/// A hyper-dual number over f64 with `M` eps1 and `N` eps2 directions.
#[derive(Clone, Copy)]
pub struct HyperDualS<const M: usize, const N: usize> {
    /// The value.
    pub re: f64,
    /// ∂/∂eps1 (None: zero).
    pub eps1: Option<[f64; M]>,
    /// ∂/∂eps2 (None: zero).
    pub eps2: Option<[f64; N]>,
    /// ∂²/∂eps1∂eps2, row i for eps1 direction i (None: zero).
    pub eps1eps2: Option<[[f64; N]; M]>,
}

#[inline]
fn scaled<const K: usize>(v: &[f64; K], s: f64) -> [f64; K] {
    std::array::from_fn(|i| v[i] * s)
}

/// a·x + b·y, where a missing vector is zero.
#[inline]
fn lin<const K: usize>(
    x: Option<&[f64; K]>,
    a: f64,
    y: Option<&[f64; K]>,
    b: f64,
) -> Option<[f64; K]> {
    match (x, y) {
        (Some(x), Some(y)) => Some(std::array::from_fn(|i| a * x[i] + b * y[i])),
        (Some(x), None) => Some(scaled(x, a)),
        (None, Some(y)) => Some(scaled(y, b)),
        (None, None) => None,
    }
}

impl<const M: usize, const N: usize> HyperDualS<M, N> {
    /// A constant.
    #[inline]
    pub fn from_re(re: f64) -> Self {
        HyperDualS {
            re,
            eps1: None,
            eps2: None,
            eps1eps2: None,
        }
    }

    /// The same number with its eps1 derivative set to unit direction `i`.
    #[inline]
    pub fn derivative1(mut self, i: usize) -> Self {
        let mut e = [0.0; M];
        e[i] = 1.0;
        self.eps1 = Some(e);
        self
    }

    /// The same number with its eps2 derivative set to unit direction `j`.
    #[inline]
    pub fn derivative2(mut self, j: usize) -> Self {
        let mut e = [0.0; N];
        e[j] = 1.0;
        self.eps2 = Some(e);
        self
    }

    /// f(self) from f's value and first and second derivatives at `re`.
    #[inline]
    fn chain_rule(&self, f0: f64, f1: f64, f2: f64) -> Self {
        let eps1eps2 = match (&self.eps1eps2, &self.eps1, &self.eps2) {
            (Some(h), Some(a), Some(b)) => Some(std::array::from_fn(|i| {
                std::array::from_fn(|j| f1 * h[i][j] + f2 * a[i] * b[j])
            })),
            (Some(h), _, _) => Some(std::array::from_fn(|i| scaled(&h[i], f1))),
            (None, Some(a), Some(b)) => Some(std::array::from_fn(|i| scaled(b, f2 * a[i]))),
            _ => None,
        };
        HyperDualS {
            re: f0,
            eps1: self.eps1.as_ref().map(|e| scaled(e, f1)),
            eps2: self.eps2.as_ref().map(|e| scaled(e, f1)),
            eps1eps2,
        }
    }

    /// self · other (the product rule, each part written once).
    #[inline]
    fn mul_ref(&self, o: &Self) -> Self {
        let (a, b) = (self.re, o.re);
        let cross1 = self.eps1.as_ref().zip(o.eps2.as_ref());
        let cross2 = o.eps1.as_ref().zip(self.eps2.as_ref());
        let eps1eps2 = if self.eps1eps2.is_none()
            && o.eps1eps2.is_none()
            && cross1.is_none()
            && cross2.is_none()
        {
            None
        } else {
            let mut h = match (&self.eps1eps2, &o.eps1eps2) {
                (Some(x), Some(y)) => {
                    std::array::from_fn(|i| std::array::from_fn(|j| b * x[i][j] + a * y[i][j]))
                }
                (Some(x), None) => std::array::from_fn(|i| scaled(&x[i], b)),
                (None, Some(y)) => std::array::from_fn(|i| scaled(&y[i], a)),
                (None, None) => [[0.0; N]; M],
            };
            if let Some((u, v)) = cross1 {
                for (hi, ui) in h.iter_mut().zip(u) {
                    for (hij, vj) in hi.iter_mut().zip(v) {
                        *hij += ui * vj;
                    }
                }
            }
            if let Some((u, v)) = cross2 {
                for (hi, ui) in h.iter_mut().zip(u) {
                    for (hij, vj) in hi.iter_mut().zip(v) {
                        *hij += ui * vj;
                    }
                }
            }
            Some(h)
        };
        HyperDualS {
            re: a * b,
            eps1: lin(self.eps1.as_ref(), b, o.eps1.as_ref(), a),
            eps2: lin(self.eps2.as_ref(), b, o.eps2.as_ref(), a),
            eps1eps2,
        }
    }

    /// self += a·o, in place.
    #[inline]
    fn add_scaled_in_place(&mut self, a: f64, o: &Self) {
        self.re += a * o.re;
        if let Some(y) = &o.eps1 {
            match &mut self.eps1 {
                Some(x) => x.iter_mut().zip(y).for_each(|(x, y)| *x += a * y),
                None => self.eps1 = Some(scaled(y, a)),
            }
        }
        if let Some(y) = &o.eps2 {
            match &mut self.eps2 {
                Some(x) => x.iter_mut().zip(y).for_each(|(x, y)| *x += a * y),
                None => self.eps2 = Some(scaled(y, a)),
            }
        }
        if let Some(y) = &o.eps1eps2 {
            match &mut self.eps1eps2 {
                Some(x) => x
                    .iter_mut()
                    .flatten()
                    .zip(y.iter().flatten())
                    .for_each(|(x, y)| *x += a * y),
                None => self.eps1eps2 = Some(std::array::from_fn(|i| scaled(&y[i], a))),
            }
        }
    }

    /// Every part times `s`, in place.
    #[inline]
    fn scale_in_place(&mut self, s: f64) {
        self.re *= s;
        if let Some(x) = &mut self.eps1 {
            x.iter_mut().for_each(|x| *x *= s);
        }
        if let Some(x) = &mut self.eps2 {
            x.iter_mut().for_each(|x| *x *= s);
        }
        if let Some(x) = &mut self.eps1eps2 {
            x.iter_mut().flatten().for_each(|x| *x *= s);
        }
    }

    /// The parts other than the value, all zero.
    fn derivatives_are_zero(&self) -> bool {
        self.eps1.is_none_or(|e| e.iter().all(|v| *v == 0.0))
            && self.eps2.is_none_or(|e| e.iter().all(|v| *v == 0.0))
            && self
                .eps1eps2
                .is_none_or(|h| h.iter().flatten().all(|v| *v == 0.0))
    }
}

// Arithmetic with another hyper-dual number, by value or by reference.

impl<const M: usize, const N: usize> Add<&Self> for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: &Self) -> Self {
        self.add_scaled_in_place(1.0, o);
        self
    }
}
impl<const M: usize, const N: usize> Add for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self.add_scaled_in_place(1.0, &o);
        self
    }
}
impl<const M: usize, const N: usize> Sub<&Self> for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: &Self) -> Self {
        self.add_scaled_in_place(-1.0, o);
        self
    }
}
impl<const M: usize, const N: usize> Sub for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self.add_scaled_in_place(-1.0, &o);
        self
    }
}
impl<const M: usize, const N: usize> Mul<&Self> for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: &Self) -> Self {
        self.mul_ref(o)
    }
}
impl<const M: usize, const N: usize> Mul for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        self.mul_ref(&o)
    }
}
impl<const M: usize, const N: usize> Div<&Self> for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn div(self, o: &Self) -> Self {
        self.mul_ref(&o.recip())
    }
}
impl<const M: usize, const N: usize> Div for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        self.mul_ref(&o.recip())
    }
}
/// The remainder has no derivatives here, as in num-dual (which leaves it
/// unimplemented): the model code never takes one of a dual number. It
/// keeps the dividend's derivatives (∂(x mod y)/∂x = 1 away from the jumps).
impl<const M: usize, const N: usize> Rem<&Self> for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn rem(self, o: &Self) -> Self {
        HyperDualS {
            re: self.re % o.re,
            ..self
        }
    }
}
impl<const M: usize, const N: usize> Rem for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn rem(self, o: Self) -> Self {
        Rem::<&Self>::rem(self, &o)
    }
}

// Arithmetic with f64.

impl<const M: usize, const N: usize> Add<f64> for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: f64) -> Self {
        self.re += o;
        self
    }
}
impl<const M: usize, const N: usize> Sub<f64> for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: f64) -> Self {
        self.re -= o;
        self
    }
}
impl<const M: usize, const N: usize> Mul<f64> for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn mul(mut self, o: f64) -> Self {
        self.scale_in_place(o);
        self
    }
}
impl<const M: usize, const N: usize> Div<f64> for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn div(mut self, o: f64) -> Self {
        self.scale_in_place(1.0 / o);
        self
    }
}
impl<const M: usize, const N: usize> Rem<f64> for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn rem(mut self, o: f64) -> Self {
        self.re %= o;
        self
    }
}

impl<const M: usize, const N: usize> Neg for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn neg(mut self) -> Self {
        self.scale_in_place(-1.0);
        self
    }
}

impl<const M: usize, const N: usize> AddAssign for HyperDualS<M, N> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        self.add_scaled_in_place(1.0, &o);
    }
}
impl<const M: usize, const N: usize> SubAssign for HyperDualS<M, N> {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        self.add_scaled_in_place(-1.0, &o);
    }
}
impl<const M: usize, const N: usize> MulAssign<f64> for HyperDualS<M, N> {
    #[inline]
    fn mul_assign(&mut self, o: f64) {
        self.scale_in_place(o);
    }
}
impl<const M: usize, const N: usize> DivAssign<f64> for HyperDualS<M, N> {
    #[inline]
    fn div_assign(&mut self, o: f64) {
        self.scale_in_place(1.0 / o);
    }
}
impl<const M: usize, const N: usize> AddAssign<f64> for HyperDualS<M, N> {
    #[inline]
    fn add_assign(&mut self, o: f64) {
        self.re += o;
    }
}
impl<const M: usize, const N: usize> SubAssign<f64> for HyperDualS<M, N> {
    #[inline]
    fn sub_assign(&mut self, o: f64) {
        self.re -= o;
    }
}
impl<const M: usize, const N: usize> RemAssign<f64> for HyperDualS<M, N> {
    #[inline]
    fn rem_assign(&mut self, o: f64) {
        self.re %= o;
    }
}

macro_rules! assign_ops {
    ($($tr:ident $f:ident $op:tt),*) => {$(
        impl<const M: usize, const N: usize> $tr for HyperDualS<M, N> {
            #[inline]
            fn $f(&mut self, o: Self) {
                *self = *self $op &o;
            }
        }
    )*};
}
assign_ops!(MulAssign mul_assign *, DivAssign div_assign /, RemAssign rem_assign %);

impl<const M: usize, const N: usize> Zero for HyperDualS<M, N> {
    #[inline]
    fn zero() -> Self {
        Self::from_re(0.0)
    }
    fn is_zero(&self) -> bool {
        self.re == 0.0 && self.derivatives_are_zero()
    }
}

impl<const M: usize, const N: usize> One for HyperDualS<M, N> {
    #[inline]
    fn one() -> Self {
        Self::from_re(1.0)
    }
}

impl<const M: usize, const N: usize> Num for HyperDualS<M, N> {
    type FromStrRadixErr = <f64 as Num>::FromStrRadixErr;
    fn from_str_radix(s: &str, radix: u32) -> Result<Self, Self::FromStrRadixErr> {
        f64::from_str_radix(s, radix).map(Self::from_re)
    }
}

impl<const M: usize, const N: usize> Signed for HyperDualS<M, N> {
    #[inline]
    fn abs(&self) -> Self {
        if self.re < 0.0 {
            -*self
        } else {
            *self
        }
    }
    fn abs_sub(&self, other: &Self) -> Self {
        if self.re > other.re {
            *self - other
        } else {
            Self::zero()
        }
    }
    #[inline]
    fn signum(&self) -> Self {
        Self::from_re(self.re.signum())
    }
    #[inline]
    fn is_positive(&self) -> bool {
        self.re.is_sign_positive()
    }
    #[inline]
    fn is_negative(&self) -> bool {
        self.re.is_sign_negative()
    }
}

impl<const M: usize, const N: usize> Inv for HyperDualS<M, N> {
    type Output = Self;
    #[inline]
    fn inv(self) -> Self {
        self.recip()
    }
}

impl<const M: usize, const N: usize> Sum for HyperDualS<M, N> {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::zero(), |a, b| a + b)
    }
}
impl<'a, const M: usize, const N: usize> Sum<&'a Self> for HyperDualS<M, N> {
    fn sum<I: Iterator<Item = &'a Self>>(iter: I) -> Self {
        iter.fold(Self::zero(), |a, b| a + b)
    }
}
impl<const M: usize, const N: usize> Product for HyperDualS<M, N> {
    fn product<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::one(), |a, b| a * b)
    }
}
impl<'a, const M: usize, const N: usize> Product<&'a Self> for HyperDualS<M, N> {
    fn product<I: Iterator<Item = &'a Self>>(iter: I) -> Self {
        iter.fold(Self::one(), |a, b| a * b)
    }
}

impl<const M: usize, const N: usize> FromPrimitive for HyperDualS<M, N> {
    fn from_i64(n: i64) -> Option<Self> {
        Some(Self::from_re(n as f64))
    }
    fn from_u64(n: u64) -> Option<Self> {
        Some(Self::from_re(n as f64))
    }
    fn from_f64(n: f64) -> Option<Self> {
        Some(Self::from_re(n))
    }
}

impl<const M: usize, const N: usize> From<f64> for HyperDualS<M, N> {
    #[inline]
    fn from(re: f64) -> Self {
        Self::from_re(re)
    }
}

impl<const M: usize, const N: usize> DualStruct for HyperDualS<M, N> {
    type Real = f64;
    type Inner = f64;
    #[inline]
    fn re(&self) -> f64 {
        self.re
    }
    #[inline]
    fn from_inner(inner: &f64) -> Self {
        Self::from_re(*inner)
    }
}

impl<const M: usize, const N: usize> Mappable<Self> for HyperDualS<M, N> {
    type Output<O> = O;
    #[inline]
    fn map_dual<G: Fn(Self) -> O, O>(self, g: G) -> O {
        g(self)
    }
}

/// Comparisons read the value only, as num-dual's do.
impl<const M: usize, const N: usize> PartialEq for HyperDualS<M, N> {
    #[inline]
    fn eq(&self, other: &Self) -> bool {
        self.re == other.re
    }
}
impl<const M: usize, const N: usize> PartialEq<f64> for HyperDualS<M, N> {
    #[inline]
    fn eq(&self, other: &f64) -> bool {
        self.re == *other
    }
}
impl<const M: usize, const N: usize> PartialOrd for HyperDualS<M, N> {
    #[inline]
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        self.re.partial_cmp(&other.re)
    }
}
impl<const M: usize, const N: usize> PartialOrd<f64> for HyperDualS<M, N> {
    #[inline]
    fn partial_cmp(&self, other: &f64) -> Option<Ordering> {
        self.re.partial_cmp(other)
    }
}

impl<const M: usize, const N: usize> fmt::Display for HyperDualS<M, N> {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}", self.re)?;
        if let Some(e) = &self.eps1 {
            write!(f, " + {e:?}ε1")?;
        }
        if let Some(e) = &self.eps2 {
            write!(f, " + {e:?}ε2")?;
        }
        if let Some(h) = &self.eps1eps2 {
            write!(f, " + {h:?}ε1ε2")?;
        }
        Ok(())
    }
}

impl<const M: usize, const N: usize> fmt::Debug for HyperDualS<M, N> {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.debug_struct("HyperDualS")
            .field("re", &self.re)
            .field("eps1", &self.eps1)
            .field("eps2", &self.eps2)
            .field("eps1eps2", &self.eps1eps2)
            .finish()
    }
}

impl<const M: usize, const N: usize> DualNum for HyperDualS<M, N> {
    type Primitive = f64;
    const NDERIV: usize = 2;
    type InnerDual = f64;

    #[inline]
    fn from_re(re: f64) -> Self {
        HyperDualS::from_re(re)
    }
    #[inline]
    fn scale(mut self, factor: &f64) -> Self {
        self.scale_in_place(*factor);
        self
    }
    #[inline]
    fn recip(&self) -> Self {
        let r = 1.0 / self.re;
        self.chain_rule(r, -r * r, 2.0 * r * r * r)
    }
    fn powi(&self, n: i32) -> Self {
        match n {
            0 => Self::one(),
            1 => *self,
            2 => self.mul_ref(self),
            _ => {
                let x = self.re;
                let p = x.powi(n - 2);
                let nf = n as f64;
                self.chain_rule(p * x * x, nf * p * x, nf * (nf - 1.0) * p)
            }
        }
    }
    fn powf(&self, n: f64) -> Self {
        if n == 0.0 {
            Self::one()
        } else if n == 1.0 {
            *self
        } else if (n - 2.0).abs() < f64::EPSILON {
            self.mul_ref(self)
        } else {
            let x = self.re;
            let p = x.powf(n - 2.0);
            self.chain_rule(p * x * x, n * p * x, n * (n - 1.0) * p)
        }
    }
    #[inline]
    fn sqrt(&self) -> Self {
        let s = self.re.sqrt();
        let r = 1.0 / self.re;
        let f1 = 0.5 * s * r;
        self.chain_rule(s, f1, -0.5 * f1 * r)
    }
    fn cbrt(&self) -> Self {
        let c = self.re.cbrt();
        let r = 1.0 / self.re;
        let f1 = c * r / 3.0;
        self.chain_rule(c, f1, f1 * r * (1.0 / 3.0 - 1.0))
    }
    #[inline]
    fn exp(&self) -> Self {
        let e = self.re.exp();
        self.chain_rule(e, e, e)
    }
    fn exp2(&self) -> Self {
        let e = self.re.exp2();
        let l = std::f64::consts::LN_2;
        self.chain_rule(e, e * l, e * l * l)
    }
    fn exp_m1(&self) -> Self {
        let e = self.re.exp();
        self.chain_rule(self.re.exp_m1(), e, e)
    }
    #[inline]
    fn ln(&self) -> Self {
        let r = 1.0 / self.re;
        self.chain_rule(self.re.ln(), r, -r * r)
    }
    fn log(&self, base: f64) -> Self {
        let r = 1.0 / (self.re * base.ln());
        self.chain_rule(self.re.log(base), r, -r / self.re)
    }
    fn log2(&self) -> Self {
        self.log(2.0)
    }
    fn log10(&self) -> Self {
        self.log(10.0)
    }
    fn ln_1p(&self) -> Self {
        let r = 1.0 / (1.0 + self.re);
        self.chain_rule(self.re.ln_1p(), r, -r * r)
    }
    #[inline]
    fn sin(&self) -> Self {
        let (s, c) = self.re.sin_cos();
        self.chain_rule(s, c, -s)
    }
    #[inline]
    fn cos(&self) -> Self {
        let (s, c) = self.re.sin_cos();
        self.chain_rule(c, -s, -c)
    }
    fn tan(&self) -> Self {
        let t = self.re.tan();
        let f1 = 1.0 + t * t;
        self.chain_rule(t, f1, 2.0 * t * f1)
    }
    #[inline]
    fn sin_cos(&self) -> (Self, Self) {
        let (s, c) = self.re.sin_cos();
        (self.chain_rule(s, c, -s), self.chain_rule(c, -s, -c))
    }
    fn asin(&self) -> Self {
        let x = self.re;
        let r = 1.0 / (1.0 - x * x);
        let f1 = r.sqrt();
        self.chain_rule(x.asin(), f1, x * f1 * r)
    }
    fn acos(&self) -> Self {
        let x = self.re;
        let r = 1.0 / (1.0 - x * x);
        let f1 = -r.sqrt();
        self.chain_rule(x.acos(), f1, x * f1 * r)
    }
    fn atan(&self) -> Self {
        let x = self.re;
        let r = 1.0 / (1.0 + x * x);
        self.chain_rule(x.atan(), r, -2.0 * x * r * r)
    }
    /// atan2(self, other) = atan(self/other) plus a constant where
    /// |other| ≥ |self|, −atan(other/self) plus a constant otherwise: the
    /// derivatives of whichever quotient is bounded.
    fn atan2(&self, other: Self) -> Self {
        let mut d = if other.re.abs() >= self.re.abs() {
            (*self / other).atan()
        } else {
            -(other / self).atan()
        };
        d.re = self.re.atan2(other.re);
        d
    }
    fn sinh(&self) -> Self {
        let (s, c) = (self.re.sinh(), self.re.cosh());
        self.chain_rule(s, c, s)
    }
    fn cosh(&self) -> Self {
        let (s, c) = (self.re.sinh(), self.re.cosh());
        self.chain_rule(c, s, c)
    }
    fn tanh(&self) -> Self {
        let t = self.re.tanh();
        let f1 = 1.0 - t * t;
        self.chain_rule(t, f1, -2.0 * t * f1)
    }
    fn asinh(&self) -> Self {
        let x = self.re;
        let r = 1.0 / (1.0 + x * x);
        let f1 = r.sqrt();
        self.chain_rule(x.asinh(), f1, -x * f1 * r)
    }
    fn acosh(&self) -> Self {
        let x = self.re;
        let r = 1.0 / (x * x - 1.0);
        let f1 = r.sqrt();
        self.chain_rule(x.acosh(), f1, -x * f1 * r)
    }
    fn atanh(&self) -> Self {
        let x = self.re;
        let r = 1.0 / (1.0 - x * x);
        self.chain_rule(x.atanh(), r, 2.0 * x * r * r)
    }
    fn sph_j0(&self) -> Self {
        if self.re.abs() < f64::EPSILON {
            Self::one() - self.mul_ref(self) / 6.0
        } else {
            self.sin() / *self
        }
    }
    fn sph_j1(&self) -> Self {
        if self.re.abs() < f64::EPSILON {
            *self / 3.0
        } else {
            let (s, c) = self.sin_cos();
            (s - *self * c) / self.mul_ref(self)
        }
    }
    fn sph_j2(&self) -> Self {
        if self.re.abs() < f64::EPSILON {
            self.mul_ref(self) / 15.0
        } else {
            let (s, c) = self.sin_cos();
            let s2 = self.mul_ref(self);
            ((s - *self * c) * 3.0 - s2 * s) / (s2 * *self)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::HyperDualSVec64;

    const M: usize = 3;
    const N: usize = 4;
    type Ours = HyperDualS<M, N>;
    type Theirs = HyperDualSVec64<M, N>;

    /// A number with all parts set from `seed` (values in (0.2, 0.8)).
    fn pair(seed: u64, full: bool) -> (Ours, Theirs) {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            0.2 + 0.6 * ((s >> 11) as f64 / (1u64 << 53) as f64)
        };
        let re = next();
        let e1: [f64; M] = std::array::from_fn(|_| next());
        let e2: [f64; N] = std::array::from_fn(|_| next());
        let h: [[f64; N]; M] = std::array::from_fn(|_| std::array::from_fn(|_| next()));
        let ours = HyperDualS {
            re,
            eps1: Some(e1),
            eps2: Some(e2),
            eps1eps2: full.then_some(h),
        };
        let mut theirs = Theirs::from_re(re);
        theirs.eps1 = num_dual::Derivative::some(nalgebra::SVector::from(e1));
        theirs.eps2 = num_dual::Derivative::some(nalgebra::RowSVector::from(e2));
        if full {
            theirs.eps1eps2 =
                num_dual::Derivative::some(nalgebra::SMatrix::from_fn(|i, j| h[i][j]));
        }
        (ours, theirs)
    }

    fn assert_same(what: &str, a: &Ours, b: &Theirs) {
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * (1.0 + y.abs());
        assert!(close(a.re, b.re), "{what}: value {} against {}", a.re, b.re);
        let e1 = b.eps1.0.map(|v| v.into()).unwrap_or([0.0; M]);
        let e2: [f64; N] = b
            .eps2
            .0
            .map(|v| std::array::from_fn(|j| v[j]))
            .unwrap_or([0.0; N]);
        let h = b.eps1eps2.0.unwrap_or_default();
        for i in 0..M {
            let x = a.eps1.map_or(0.0, |e| e[i]);
            assert!(close(x, e1[i]), "{what}: eps1[{i}] {x} against {}", e1[i]);
            for j in 0..N {
                let x = a.eps1eps2.map_or(0.0, |e| e[i][j]);
                assert!(
                    close(x, h[(i, j)]),
                    "{what}: eps1eps2[{i}][{j}] {x} against {}",
                    h[(i, j)]
                );
            }
        }
        for j in 0..N {
            let x = a.eps2.map_or(0.0, |e| e[j]);
            assert!(close(x, e2[j]), "{what}: eps2[{j}] {x} against {}", e2[j]);
        }
    }

    /// Every operation the trait offers, against num-dual's HyperDualVec,
    /// on numbers with and without a second-order part.
    #[test]
    fn matches_num_dual() {
        for seed in 1..6 {
            for full in [false, true] {
                let (a, ta) = pair(seed, full);
                let (b, tb) = pair(seed + 100, !full);
                assert_same("a + b", &(a + b), &(ta + tb));
                assert_same("a - b", &(a - b), &(ta - tb));
                assert_same("a * b", &(a * b), &(ta * tb));
                assert_same("a / b", &(a / b), &(ta / tb));
                assert_same("a * 1.7", &(a * 1.7), &(ta * 1.7));
                assert_same("a / 1.7", &(a / 1.7), &(ta / 1.7));
                assert_same("a + 1.7", &(a + 1.7), &(ta + 1.7));
                assert_same("a - 1.7", &(a - 1.7), &(ta - 1.7));
                assert_same("-a", &(-a), &(-ta));
                let mut c = a;
                c *= b;
                c += a;
                c -= b;
                c /= a;
                let mut tc = ta;
                tc *= tb;
                tc += ta;
                tc -= tb;
                tc /= ta;
                assert_same("assign ops", &c, &tc);
                assert_same("recip", &a.recip(), &ta.recip());
                for n in [-3, -1, 0, 1, 2, 3, 5] {
                    assert_same(&format!("powi {n}"), &a.powi(n), &ta.powi(n));
                }
                for n in [-1.5, 0.0, 1.0, 2.0, 0.5, 3.7] {
                    assert_same(&format!("powf {n}"), &a.powf(n), &ta.powf(n));
                }
                type Pair = (&'static str, fn(&Ours) -> Ours, fn(&Theirs) -> Theirs);
                let unary: [Pair; 24] = [
                    ("sqrt", |x| x.sqrt(), |x| x.sqrt()),
                    ("cbrt", |x| x.cbrt(), |x| x.cbrt()),
                    ("exp", |x| x.exp(), |x| x.exp()),
                    ("exp2", |x| x.exp2(), |x| x.exp2()),
                    ("exp_m1", |x| x.exp_m1(), |x| x.exp_m1()),
                    ("ln", |x| x.ln(), |x| x.ln()),
                    ("log 3", |x| x.log(3.0), |x| x.log(3.0)),
                    ("log2", |x| x.log2(), |x| x.log2()),
                    ("log10", |x| x.log10(), |x| x.log10()),
                    ("ln_1p", |x| x.ln_1p(), |x| x.ln_1p()),
                    ("sin", |x| x.sin(), |x| x.sin()),
                    ("cos", |x| x.cos(), |x| x.cos()),
                    ("tan", |x| x.tan(), |x| x.tan()),
                    ("asin", |x| x.asin(), |x| x.asin()),
                    ("acos", |x| x.acos(), |x| x.acos()),
                    ("atan", |x| x.atan(), |x| x.atan()),
                    ("sinh", |x| x.sinh(), |x| x.sinh()),
                    ("cosh", |x| x.cosh(), |x| x.cosh()),
                    ("tanh", |x| x.tanh(), |x| x.tanh()),
                    ("asinh", |x| x.asinh(), |x| x.asinh()),
                    (
                        "acosh of 1 + x",
                        |x| (*x + 1.0).acosh(),
                        |x| (*x + 1.0).acosh(),
                    ),
                    ("atanh", |x| x.atanh(), |x| x.atanh()),
                    ("abs of -x", |x| (-*x).abs(), |x| (-*x).abs()),
                    ("sph_j2", |x| x.sph_j2(), |x| x.sph_j2()),
                ];
                for (name, f, g) in unary {
                    assert_same(name, &f(&a), &g(&ta));
                }
                assert_same("sph_j0", &a.sph_j0(), &ta.sph_j0());
                assert_same("sph_j1", &a.sph_j1(), &ta.sph_j1());
                let (s, c) = a.sin_cos();
                let (ts, tc) = ta.sin_cos();
                assert_same("sin_cos.0", &s, &ts);
                assert_same("sin_cos.1", &c, &tc);
                assert_same("mul_add", &a.mul_add(b, a), &ta.mul_add(tb, ta));
                assert_same("powd", &a.powd(b), &ta.powd(tb));
                // atan2 in all four quadrants and on both sides of |y| = |x|.
                for (sy, sx) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                    for k in [0.3, 3.0] {
                        let (y, x) = (a * sy, b * (sx * k));
                        let (ty, tx) = (ta * sy, tb * (sx * k));
                        assert_same(
                            &format!("atan2 ({sy}, {sx}·{k})"),
                            &y.atan2(x),
                            &ty.atan2(tx),
                        );
                    }
                }
                let v = [a, b, a * b];
                let tv = [ta, tb, ta * tb];
                assert_same("sum", &v.iter().copied().sum(), &tv.iter().copied().sum());
                assert_same("product", &v.iter().product(), &tv.iter().product());
            }
        }
    }

    /// Seeded directions give the second derivatives of a known function:
    /// f = x² y sin z, with x, y in eps1 and y, z in eps2.
    #[test]
    fn seeded_second_derivatives_of_a_closed_form() {
        let (x0, y0, z0) = (0.7, -1.3, 0.4);
        let x = HyperDualS::<2, 2>::from_re(x0).derivative1(0);
        let y = HyperDualS::<2, 2>::from_re(y0)
            .derivative1(1)
            .derivative2(0);
        let z = HyperDualS::<2, 2>::from_re(z0).derivative2(1);
        let f = x * x * y * z.sin();
        let h = f.eps1eps2.expect("second-order part");
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-14;
        // ∂²f/∂x∂y = 2x sin z, ∂²f/∂x∂z = 2xy cos z,
        // ∂²f/∂y² = 0, ∂²f/∂y∂z = x² cos z.
        assert!(close(h[0][0], 2.0 * x0 * z0.sin()));
        assert!(close(h[0][1], 2.0 * x0 * y0 * z0.cos()));
        assert!(close(h[1][0], 0.0));
        assert!(close(h[1][1], x0 * x0 * z0.cos()));
        assert!(close(f.re, x0 * x0 * y0 * z0.sin()));
    }
}

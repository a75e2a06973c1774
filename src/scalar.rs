//! The scalar type that model code is generic over.
//!
//! Everything on the hot path of the state equation (kinematics, muscles,
//! contact, ligaments) is written once for any `S: Scalar`: `f64` for plain
//! evaluation and forward-mode dual numbers from `num-dual` (`Dual64`,
//! `DualVec64<N>`, `HyperDual64`, and leap's own [`crate::hyperdual::HyperDualS`] in
//! the exact Hessian's passes) for exact derivatives.

pub use num_dual::{Dual64, DualNum, DualStruct};

/// A real number or a forward-mode dual number over `f64`.
pub trait Scalar: DualNum<Primitive = f64> + Copy + Send + Sync {}

impl<T> Scalar for T where T: DualNum<Primitive = f64> + Copy + Send + Sync {}

/// The `f64` value of a scalar (the real part of a dual number).
#[inline]
pub fn value<S: Scalar>(x: S) -> f64 {
    x.re()
}

/// Lift a constant into the scalar type.
#[inline]
pub fn c<S: Scalar>(x: f64) -> S {
    S::from(x)
}

/// tanh(x) for any scalar, without the overflow of num-dual's tanh of a
/// dual number (sinh/cosh, whose quotient rule squares cosh: NaN from |x| ≈
/// 355, where a smoothed switch with b = 1000 sends it). Beyond |x| = 300
/// it is ±1 with zero derivatives (the true ones are below 1e-260); below,
/// num-dual's, to the bit.
#[inline]
pub fn tanh<S: Scalar>(x: S) -> S {
    let r = x.re();
    if r.abs() > TANH_SATURATION {
        S::from(r.signum())
    } else {
        x.tanh()
    }
}

/// Where [`tanh`] saturates.
pub const TANH_SATURATION: f64 = 300.0;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hyperdual::HyperDualS;

    /// Below the saturation, num-dual's tanh to the bit; beyond it ±1 with
    /// zero derivatives, where num-dual's gave NaN (its quotient rule
    /// squares cosh).
    #[test]
    fn tanh_of_dual_numbers_saturates_instead_of_overflowing() {
        for x in [-299.0, -20.0, -0.3, 0.0, 1e-3, 7.5, 299.0] {
            let d = Dual64::from(x).derivative();
            let (ours, theirs) = (tanh(d), d.tanh());
            assert_eq!(ours.re.to_bits(), theirs.re.to_bits(), "{x}");
            assert_eq!(ours.eps.to_bits(), theirs.eps.to_bits(), "{x}");
        }
        assert!(Dual64::from(400.0).derivative().tanh().eps.is_nan());
        for x in [-1e300, -400.0, 301.0, 1e4] {
            let d = tanh(Dual64::from(x).derivative());
            assert_eq!((d.re, d.eps), (x.signum(), 0.0), "{x}");
            let h = tanh(HyperDualS::<1, 1>::from_re(x).derivative1(0).derivative2(0));
            assert_eq!(h.re, x.signum());
            assert!(h.eps1.is_none_or(|e| e[0] == 0.0), "{x}");
            assert!(h.eps1eps2.is_none_or(|e| e[0][0] == 0.0), "{x}");
        }
        assert_eq!(tanh(2.0f64), 2.0f64.tanh());
    }
}

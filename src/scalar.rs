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

//! The bottom layer of the rotation math, under both charts of SO(3) ([`crate::so3`] over
//! matrices, [`crate::quat`] over quaternions): the skew map ([`skew`]) and the scalar series of
//! `Exp`, `Log` and their Jacobians ([`series`]), each written once with its Taylor branch and
//! checked against 50-digit values, and `(sin x, cos x)` four lanes at a time ([`sincos`]). Nothing
//! here imports `so3` or `quat`.

pub mod series;
pub mod sincos;
pub mod skew;

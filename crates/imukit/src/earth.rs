//! The rotating Earth: a local-level navigation frame fixed on the WGS-84 ellipsoid.
//!
//! | item | convention |
//! |---|---|
//! | frame | [`LocalLevel`]: origin at geodetic `latitude` \[rad\] and `height` \[m\] above the ellipsoid, axes ENU (x east, y north, z up) or NED; it turns with the Earth |
//! | Earth rate | `ω_ie` in the frame's axes: ENU `Ω (0, cos φ, sin φ)`, NED `Ω (cos φ, 0, −sin φ)`, `Ω = 7.292115e-5` rad/s (Groves 2013, eq. 2.123) |
//! | gravity | plumb-bob gravity at the origin (mass attraction plus centrifugal), pointing down: Somigliana's normal gravity on the ellipsoid (Groves eq. 2.134) with the free-air height correction to second order (Groves eq. 2.139) |
//! | model | in this frame `v̇ = R f + g − 2 ω_ie × v`, `Ṙ = R [ω]× − [ω_ie]× R`; the change of gravity and of the centrifugal term across the frame (a few 1e-6 m/s² per metre) and the transport rate of a frame that follows the vehicle are not modelled |
//!
//! Groves, *Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed.,
//! 2013, ch. 2; WGS-84 constants from NIMA TR8350.2 (2000).

use nalgebra::Vector3;

use crate::error::{Error, Result};

/// WGS-84 Earth rotation rate Ω [rad/s].
pub const EARTH_RATE: f64 = 7.292_115e-5;
/// WGS-84 equatorial radius a \[m\].
pub const SEMI_MAJOR_AXIS: f64 = 6_378_137.0;
/// WGS-84 flattening f.
pub const FLATTENING: f64 = 1.0 / 298.257_223_563;
/// WGS-84 gravitational constant GM [m³/s²].
pub const GM: f64 = 3.986_004_418e14;
/// Normal gravity on the equator γ_e [m/s²] (TR8350.2, table 3.4).
const GAMMA_EQUATOR: f64 = 9.780_325_335_9;
/// Somigliana's constant k = (b γ_p − a γ_e) / (a γ_e).
const SOMIGLIANA_K: f64 = 0.001_931_852_652_41;

/// Axes of a local-level frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Axes {
    /// x east, y north, z up (imukit's z-up world).
    #[default]
    Enu,
    /// x north, y east, z down.
    Ned,
}

crate::named_enum!(Axes, "axes", [Enu => "enu", Ned => "ned"]);

/// A local-level frame fixed on the Earth (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalLevel {
    /// Geodetic latitude φ \[rad\], in [−π/2, π/2].
    pub latitude: f64,
    /// Height above the WGS-84 ellipsoid \[m\].
    pub height: f64,
    /// ENU or NED.
    pub axes: Axes,
}

/// The highest origin \[m\] a frame takes (see [`LocalLevel::new`]).
pub const MAX_HEIGHT: f64 = 1.0e6;

impl LocalLevel {
    /// Checks the values: a finite latitude within ±π/2, a height from −a/2 to 1000 km (the domain of
    /// the second-order free-air series: ~1e-6 relative below 100 km, 1.5 % at 1000 km against the
    /// inverse square; beyond it the series is no gravity model, and it overflows near 1e154 m).
    pub fn new(latitude: f64, height: f64, axes: Axes) -> Result<Self> {
        if !(latitude.is_finite() && latitude.abs() <= std::f64::consts::FRAC_PI_2) {
            return Err(Error::Parameter {
                name: "latitude",
                expected: "finite, within ±π/2 rad",
                got: format!("{latitude}"),
            });
        }
        if !(height > -0.5 * SEMI_MAJOR_AXIS && height <= MAX_HEIGHT) {
            return Err(Error::Parameter {
                name: "height",
                expected: "from −a/2 (−3189 km) to 1000 km",
                got: format!("{height}"),
            });
        }
        Ok(Self { latitude, height, axes })
    }

    /// `ω_ie` in the frame's axes [rad/s].
    pub fn earth_rate(&self) -> Vector3<f64> {
        let (s, c) = self.latitude.sin_cos();
        match self.axes {
            Axes::Enu => Vector3::new(0.0, EARTH_RATE * c, EARTH_RATE * s),
            Axes::Ned => Vector3::new(EARTH_RATE * c, 0.0, -EARTH_RATE * s),
        }
    }

    /// Magnitude of plumb-bob gravity at the origin [m/s²].
    pub fn gravity_magnitude(&self) -> f64 {
        let s2 = self.latitude.sin().powi(2);
        let e2 = FLATTENING * (2.0 - FLATTENING);
        let surface = GAMMA_EQUATOR * (1.0 + SOMIGLIANA_K * s2) / (1.0 - e2 * s2).sqrt();
        // m = Ω² a² b / GM; the free-air factor of Groves eq. 2.139.
        let b = SEMI_MAJOR_AXIS * (1.0 - FLATTENING);
        let m = EARTH_RATE * EARTH_RATE * SEMI_MAJOR_AXIS * SEMI_MAJOR_AXIS * b / GM;
        let h = self.height / SEMI_MAJOR_AXIS;
        surface * (1.0 - 2.0 * (1.0 + FLATTENING + m - 2.0 * FLATTENING * s2) * h + 3.0 * h * h)
    }

    /// `(∂γ/∂φ, ∂γ/∂h)` of [`Self::gravity_magnitude`] (m/s² per rad, s⁻²), differentiated
    /// term by term (with `s = sin²φ`, `ds/dφ = sin 2φ`): the error model of a frame that follows
    /// the vehicle needs them ([`crate::ellipsoid_errors`]).
    pub fn gravity_derivatives(&self) -> (f64, f64) {
        let s2 = self.latitude.sin().powi(2);
        let ds2 = (2.0 * self.latitude).sin();
        let e2 = FLATTENING * (2.0 - FLATTENING);
        let root = (1.0 - e2 * s2).sqrt();
        let surface = GAMMA_EQUATOR * (1.0 + SOMIGLIANA_K * s2) / root;
        let d_surface = GAMMA_EQUATOR * (SOMIGLIANA_K / root + (1.0 + SOMIGLIANA_K * s2) * 0.5 * e2 / root.powi(3));
        let b = SEMI_MAJOR_AXIS * (1.0 - FLATTENING);
        let m = EARTH_RATE * EARTH_RATE * SEMI_MAJOR_AXIS * SEMI_MAJOR_AXIS * b / GM;
        let h = self.height / SEMI_MAJOR_AXIS;
        let free_air = 1.0 - 2.0 * (1.0 + FLATTENING + m - 2.0 * FLATTENING * s2) * h + 3.0 * h * h;
        let d_lat = (d_surface * free_air + surface * 4.0 * FLATTENING * h) * ds2;
        let d_height = surface * (-2.0 * (1.0 + FLATTENING + m - 2.0 * FLATTENING * s2) + 6.0 * h) / SEMI_MAJOR_AXIS;
        (d_lat, d_height)
    }

    /// Gravity at the origin in the frame's axes [m/s²], pointing down (added to the rotated
    /// specific force, as imukit's `gravity`).
    pub fn gravity(&self) -> Vector3<f64> {
        let g = self.gravity_magnitude();
        match self.axes {
            Axes::Enu => Vector3::new(0.0, 0.0, -g),
            Axes::Ned => Vector3::new(0.0, 0.0, g),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn earth_rate_has_the_sidereal_magnitude_and_points_along_the_axis() -> Result<()> {
        let lat = 48f64.to_radians();
        for axes in [Axes::Enu, Axes::Ned] {
            let w = LocalLevel::new(lat, 0.0, axes)?.earth_rate();
            assert!((w.norm() - 2.0 * std::f64::consts::PI / 86_164.090_5).abs() < 1e-11);
            // the vertical component is Ω sin φ, up in ENU, −down in NED
            let up = if axes == Axes::Enu { w.z } else { -w.z };
            assert!((up - EARTH_RATE * lat.sin()).abs() < 1e-18);
        }
        Ok(())
    }

    #[test]
    fn normal_gravity_matches_published_values() -> Result<()> {
        // WGS-84 normal gravity (TR8350.2 table 3.4): equator 9.7803253359, poles 9.8321849378.
        let at = |deg: f64, h: f64| {
            Ok::<f64, Error>(LocalLevel::new(f64::to_radians(deg), h, Axes::Enu)?.gravity_magnitude())
        };
        assert!((at(0.0, 0.0)? - 9.780_325_335_9).abs() < 1e-9);
        assert!((at(90.0, 0.0)? - 9.832_184_937_8).abs() < 1e-8);
        // free-air gradient ≈ −3.086e-6 s⁻² at the equator
        let gradient = (at(0.0, 1000.0)? - at(0.0, 0.0)?) / 1000.0;
        assert!((gradient + 3.086e-6).abs() < 5e-9);
        Ok(())
    }

    #[test]
    fn gravity_derivatives_are_the_central_differences() -> Result<()> {
        for (lat, h) in [(0.3, 0.0), (-1.1, 2500.0), (0.785, 9e5)] {
            let g = |lat: f64, h: f64| Ok::<f64, Error>(LocalLevel::new(lat, h, Axes::Enu)?.gravity_magnitude());
            let (d_lat, d_h) = LocalLevel::new(lat, h, Axes::Ned)?.gravity_derivatives();
            let (e, dh) = (1e-5, 1.0);
            let num_lat = (g(lat + e, h)? - g(lat - e, h)?) / (2.0 * e);
            let num_h = (g(lat, h + dh)? - g(lat, h - dh)?) / (2.0 * dh);
            assert!(
                (d_lat - num_lat).abs() < 1e-7 * num_lat.abs().max(1e-3),
                "{d_lat} {num_lat}"
            );
            assert!((d_h - num_h).abs() < 1e-12, "{d_h} {num_h}");
        }
        Ok(())
    }

    #[test]
    fn out_of_range_is_refused() {
        assert!(LocalLevel::new(1.6, 0.0, Axes::Enu).is_err());
        assert!(LocalLevel::new(f64::NAN, 0.0, Axes::Enu).is_err());
        assert!(LocalLevel::new(0.0, -4e6, Axes::Ned).is_err());
    }
}

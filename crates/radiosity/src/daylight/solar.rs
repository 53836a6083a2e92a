//! Where the sun is: NOAA's solar position algorithm (the NOAA Global Monitoring Laboratory
//! solar calculator, after J. Meeus, *Astronomical Algorithms*, 2nd ed., 1998, chapters 7,
//! 22, 25 and 28), stated accurate to about 0.01° between 1800 and 2100.
//!
//! From the Julian day JD (Meeus eq. 7.1) and T = (JD − 2451545)/36525 Julian centuries:
//! the sun's geometric mean longitude L₀ and mean anomaly M, the equation of the centre C,
//! the apparent longitude λ (nutation and aberration by the low-accuracy terms of Meeus
//! ch. 25), the obliquity ε, the declination δ = asin(sin ε sin λ) and the equation of time
//! (Smart's series, Meeus eq. 28.3). Then at a site of latitude φ, longitude (east positive)
//! and time-zone offset Z hours: true solar time = local standard time + E + 4·longitude −
//! 60·Z minutes, hour angle H = true solar time/4 − 180°, and
//!
//! sin(altitude) = sin φ sin δ + cos φ cos δ cos H,
//! azimuth = atan2(sin H, cos H sin φ − tan δ cos φ) + 180° (clockwise from north).
//!
//! The altitude returned is the geometric one, as sky models (Perez, CIE) and Radiance's
//! `gendaylit` use; [`SolarPosition::apparent_altitude`] adds NOAA's atmospheric refraction
//! for comparison with published apparent positions.

use std::f64::consts::PI;

/// A place on the earth, for the sun's position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Site {
    /// Degrees north.
    pub latitude: f64,
    /// Degrees east (west negative).
    pub longitude: f64,
    /// Hours from GMT of local standard time, east positive.
    pub time_zone: f64,
}

/// The sun seen from a site.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolarPosition {
    /// Geometric altitude above the horizon, radians (negative below it).
    pub altitude: f64,
    /// Azimuth clockwise from north, radians in `[0, 2π)`.
    pub azimuth: f64,
}

impl SolarPosition {
    /// The altitude seen through the atmosphere: the geometric one plus NOAA's refraction
    /// ([`refraction`]), radians.
    pub fn apparent_altitude(&self) -> f64 {
        self.altitude + refraction(self.altitude.to_degrees()).to_radians()
    }

    /// The unit direction towards the sun in the sky's frame (x east, y north, z up).
    pub fn direction(&self) -> [f64; 3] {
        super::direction(self.altitude, self.azimuth)
    }
}

/// The Julian day of a Gregorian calendar date at `ut_hours` of universal time (Meeus eq.
/// 7.1; hours outside 0…24 carry into the neighbouring days).
pub fn julian_day(year: i32, month: u32, day: u32, ut_hours: f64) -> f64 {
    let (y, m) = if month <= 2 {
        (year as f64 - 1.0, month as f64 + 12.0)
    } else {
        (year as f64, month as f64)
    };
    let a = (y / 100.0).floor();
    let b = 2.0 - a + (a / 4.0).floor();
    (365.25 * (y + 4716.0)).floor() + (30.6001 * (m + 1.0)).floor() + day as f64 + b - 1524.5
        + ut_hours / 24.0
}

/// The sun's declination (radians) and the equation of time (minutes: apparent minus mean
/// solar time) at Julian day `jd`.
pub fn declination_and_equation_of_time(jd: f64) -> (f64, f64) {
    let t = (jd - 2451545.0) / 36525.0;
    let l0 = (280.46646 + t * (36000.76983 + 0.0003032 * t)).rem_euclid(360.0);
    let m = 357.52911 + t * (35999.05029 - 0.0001537 * t);
    let e = 0.016708634 - t * (0.000042037 + 0.0000001267 * t);
    let mr = m.to_radians();
    let c = mr.sin() * (1.914602 - t * (0.004817 + 0.000014 * t))
        + (2.0 * mr).sin() * (0.019993 - 0.000101 * t)
        + (3.0 * mr).sin() * 0.000289;
    let omega = (125.04 - 1934.136 * t).to_radians();
    let lambda = (l0 + c - 0.00569 - 0.00478 * omega.sin()).to_radians();
    let eps0 = 23.0 + (26.0 + (21.448 - t * (46.815 + t * (0.00059 - t * 0.001813))) / 60.0) / 60.0;
    let eps = (eps0 + 0.00256 * omega.cos()).to_radians();
    let declination = (eps.sin() * lambda.sin()).asin();
    let y = (eps / 2.0).tan().powi(2);
    let l0r = l0.to_radians();
    let eot = y * (2.0 * l0r).sin() - 2.0 * e * mr.sin()
        + 4.0 * e * y * mr.sin() * (2.0 * l0r).cos()
        - 0.5 * y * y * (4.0 * l0r).sin()
        - 1.25 * e * e * (2.0 * mr).sin();
    (declination, 4.0 * eot.to_degrees())
}

/// The sun's position at `site` on a date at `hours` of local standard time (0…24; the
/// middle of an EPW record's hour is [`super::epw::Record::mid_hour`]).
pub fn solar_position(site: &Site, year: i32, month: u32, day: u32, hours: f64) -> SolarPosition {
    let jd = julian_day(year, month, day, hours - site.time_zone);
    let (declination, eot) = declination_and_equation_of_time(jd);
    let true_solar_minutes = hours * 60.0 + eot + 4.0 * site.longitude - 60.0 * site.time_zone;
    let hour_angle = (true_solar_minutes / 4.0 - 180.0).to_radians();
    let phi = site.latitude.to_radians();
    let sin_alt = phi.sin() * declination.sin() + phi.cos() * declination.cos() * hour_angle.cos();
    let altitude = sin_alt.clamp(-1.0, 1.0).asin();
    // atan2 of the sun's east and north components (rather than the tan δ form, which fails
    // at the poles): east = −cos δ sin H, north = sin δ cos φ − cos δ sin φ cos H.
    let east = -declination.cos() * hour_angle.sin();
    let north = declination.sin() * phi.cos() - declination.cos() * phi.sin() * hour_angle.cos();
    let mut azimuth = east.atan2(north);
    if azimuth < 0.0 {
        azimuth += 2.0 * PI;
    }
    SolarPosition { altitude, azimuth }
}

/// NOAA's atmospheric refraction (degrees) at a geometric altitude of `altitude` degrees,
/// for a standard atmosphere; 0 above 85°.
pub fn refraction(altitude: f64) -> f64 {
    let arcsec = if altitude > 85.0 {
        0.0
    } else if altitude > 5.0 {
        let t = altitude.to_radians().tan();
        58.1 / t - 0.07 / t.powi(3) + 0.000086 / t.powi(5)
    } else if altitude > -0.575 {
        let e = altitude;
        1735.0 + e * (-518.2 + e * (103.4 + e * (-12.79 + e * 0.711)))
    } else {
        -20.772 / altitude.to_radians().tan()
    };
    arcsec / 3600.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn julian_day_matches_meeus() {
        // Meeus, examples 7.a and 7.b: 1957 October 4.81 = 2436116.31; 333 January 27.5 is
        // before the Gregorian calendar, so only the Gregorian example and J2000.0.
        assert!((julian_day(1957, 10, 4, 0.81 * 24.0) - 2436116.31).abs() < 1e-6);
        assert_eq!(julian_day(2000, 1, 1, 12.0), 2451545.0);
        assert_eq!(julian_day(1987, 1, 27, 0.0), 2446822.5);
    }

    #[test]
    fn declination_and_equation_of_time_match_meeus() {
        // Meeus example 25.a (1992 October 13.0 TD): δ = −7.78507°; example 28.b: the
        // equation of time that day is 13 min 42.6 s (Smart's series).
        let (d, e) = declination_and_equation_of_time(2448908.5);
        assert!(
            (d.to_degrees() + 7.78507).abs() < 2e-4,
            "{}",
            d.to_degrees()
        );
        assert!((e - (13.0 + 42.6 / 60.0)).abs() < 0.02, "{e}");
    }

    #[test]
    fn position_matches_the_spa_example() {
        // Reda & Andreas (2004), NREL's Solar Position Algorithm, table A4.1: Golden, CO,
        // 2003-10-17 12:30:30 local standard time (UTC−7), 39.742476° N, 105.1786° W:
        // topocentric zenith 50.11162°, azimuth 194.34024°. NOAA's algorithm leaves out the
        // parallax (0.0024°) and takes its refraction for a standard atmosphere rather than
        // the example's 820 mbar (0.004°): agreement to 0.01° is expected.
        let site = Site {
            latitude: 39.742476,
            longitude: -105.1786,
            time_zone: -7.0,
        };
        let p = solar_position(&site, 2003, 10, 17, 12.0 + 30.5 / 60.0);
        let zenith = 90.0 - p.apparent_altitude().to_degrees();
        assert!((zenith - 50.11162).abs() < 0.01, "{zenith}");
        assert!(
            (p.azimuth.to_degrees() - 194.34024).abs() < 0.01,
            "{}",
            p.azimuth.to_degrees()
        );
    }

    #[test]
    fn noon_and_the_solstices() {
        // At true solar noon the sun is due south (north of the tropics) at 90° − φ + δ, and
        // the June solstice's declination is the obliquity, 23.44° (2021-06-21 03:32 UT).
        let jd = julian_day(2021, 6, 21, 3.53);
        let (d, eot) = declination_and_equation_of_time(jd);
        assert!(
            (d.to_degrees() - 23.437).abs() < 0.005,
            "{}",
            d.to_degrees()
        );
        let site = Site {
            latitude: 51.48,
            longitude: 0.0,
            time_zone: 0.0,
        };
        // Greenwich: true noon is 12:00 − E.
        let noon = 12.0 - eot / 60.0;
        let p = solar_position(&site, 2021, 6, 21, noon);
        assert!(
            (p.azimuth.to_degrees() - 180.0).abs() < 0.05,
            "{}",
            p.azimuth.to_degrees()
        );
        let want = 90.0 - 51.48 + d.to_degrees();
        assert!((p.altitude.to_degrees() - want).abs() < 0.01);
        // Sunrise is in the north-east, sunset in the north-west.
        let morning = solar_position(&site, 2021, 6, 21, 4.0);
        let evening = solar_position(&site, 2021, 6, 21, 20.0);
        assert!(morning.azimuth.to_degrees() > 40.0 && morning.azimuth.to_degrees() < 60.0);
        assert!(evening.azimuth.to_degrees() > 300.0 && evening.azimuth.to_degrees() < 320.0);
        // Southern hemisphere at noon: the sun is due north.
        let sydney = Site {
            latitude: -33.87,
            longitude: 151.21,
            time_zone: 10.0,
        };
        let p = solar_position(
            &sydney,
            2021,
            6,
            21,
            12.0 - eot / 60.0 + (150.0 - 151.21) / 15.0,
        );
        assert!(p.azimuth.to_degrees() < 0.05 || p.azimuth.to_degrees() > 359.95);
    }

    #[test]
    fn refraction_is_noaas() {
        // Half a degree at the horizon, an arc minute at 45°, nothing overhead.
        assert!((refraction(0.0) - 1735.0 / 3600.0).abs() < 1e-12);
        assert!((refraction(45.0) - (58.1 - 0.07 + 0.000086) / 3600.0).abs() < 1e-9);
        assert_eq!(refraction(89.0), 0.0);
    }
}

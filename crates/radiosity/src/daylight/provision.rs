//! EN 17037's daylight provision from hourly illuminance (EN 17037:2018, "Daylight in
//! buildings", clause 5.1 and Annex A, calculation method 2: illuminance levels, hour by
//! hour, from a climate-based simulation).
//!
//! A room's reference plane (here: a grid of points) meets a level of recommendation when,
//! for at least half of the *daylight hours*,
//!
//! - a target illuminance E_T is reached over at least half of the plane's points, and
//! - a minimum target illuminance E_TM is reached over at least 95 % of them;
//!
//! the two are counted apart, each over half the daylight hours. The levels (vertical and
//! inclined openings, Table A.1): minimum E_T 300 lx with E_TM 100 lx, medium 500 lx with 300
//! lx, high 750 lx with 500 lx. Roof openings need only E_T over the plane; that is the target
//! share reported here too.
//!
//! The daylight hours are half the year's hours, those of the highest diffuse horizontal
//! illuminance outside (the convention of the standard's climate-based method, as tools such
//! as ClimateStudio apply it: 4,380 of 8,760 hours), chosen here by
//! [`daylight_hours`] from the hours' diffuse horizontal illuminance, ties taken in hour
//! order. A point counts when its illuminance is at least the threshold. Counting is in whole
//! hours and points, so the result does not depend on how the hours are split into blocks.

use std::ops::Range;

/// The three levels of recommendation: (name, E_T, E_TM) in lx, EN 17037:2018 Table A.1.
pub const LEVELS: [(&str, f64, f64); 3] = [
    ("minimum", 300.0, 100.0),
    ("medium", 500.0, 300.0),
    ("high", 750.0, 500.0),
];
/// Share of the plane's points that must reach E_T.
pub const TARGET_SHARE: f64 = 0.5;
/// Share of the plane's points that must reach E_TM.
pub const MINIMUM_SHARE: f64 = 0.95;
/// Share of the daylight hours that each must hold for.
pub const TIME_SHARE: f64 = 0.5;

/// Which of `diffuse.len()` hours are daylight hours: the `diffuse.len() / 2` with the
/// highest diffuse horizontal illuminance `diffuse` (lx), ties (and NaN, taken as 0) in hour
/// order.
pub fn daylight_hours(diffuse: &[f64]) -> Vec<bool> {
    let key = |v: f64| if v.is_nan() { 0.0 } else { v };
    let mut order: Vec<usize> = (0..diffuse.len()).collect();
    // Stable: equal values keep hour order.
    order.sort_by(|&a, &b| key(diffuse[b]).total_cmp(&key(diffuse[a])));
    let mut out = vec![false; diffuse.len()];
    for &h in order.iter().take(diffuse.len() / 2) {
        out[h] = true;
    }
    out
}

/// One grid's daylight provision.
#[derive(Clone, Debug, PartialEq)]
pub struct Provision {
    /// Daylight hours counted.
    pub daylight_hours: u32,
    /// Per level ([`LEVELS`]): the share of daylight hours in which E_T is reached over at
    /// least [`TARGET_SHARE`] of the points, and that in which E_TM is reached over at least
    /// [`MINIMUM_SHARE`] of them.
    pub shares: [[f64; 2]; 3],
    /// The highest level met (an index into [`LEVELS`]); None when not even the minimum is.
    pub level: Option<usize>,
}

impl Provision {
    /// The level's name, or "not met".
    pub fn level_name(&self) -> &'static str {
        self.level.map_or("not met", |k| LEVELS[k].0)
    }
}

/// Hour counts per grid, fed a block of hours at a time.
#[derive(Clone, Debug, PartialEq)]
pub struct ProvisionAccumulator {
    grids: Vec<Range<usize>>,
    /// Per grid and level: hours meeting E_T, hours meeting E_TM.
    hours: Vec<[[u32; 2]; 3]>,
    daylight_hours: u32,
}

impl ProvisionAccumulator {
    /// Counts for the grids `grids` (ranges of point indices).
    pub fn new(grids: Vec<Range<usize>>) -> ProvisionAccumulator {
        let n = grids.len();
        ProvisionAccumulator {
            grids,
            hours: vec![[[0; 2]; 3]; n],
            daylight_hours: 0,
        }
    }

    /// Count the daylight hours of a block of `daylight.len()` hours: `total[i * hours + h]`
    /// is point i's illuminance in hour h (lx); hours whose `daylight` is false are skipped.
    /// Points past `total`'s are taken as dark.
    pub fn add_block(&mut self, daylight: &[bool], total: &[f64]) {
        let hours = daylight.len();
        if hours == 0 {
            return;
        }
        let points = total.len() / hours;
        for (g, counts) in self.grids.iter().zip(&mut self.hours) {
            let r = g.start.min(points)..g.end.min(points);
            let n = g.len();
            if n == 0 {
                continue;
            }
            for h in (0..hours).filter(|&h| daylight[h]) {
                // Points at or above each E_T and E_TM of every level.
                let mut at = [[0usize; 2]; 3];
                for i in r.clone() {
                    let e = total[i * hours + h];
                    for (k, &(_, target, minimum)) in LEVELS.iter().enumerate() {
                        at[k][0] += (e >= target) as usize;
                        at[k][1] += (e >= minimum) as usize;
                    }
                }
                for k in 0..3 {
                    // Whole-point comparisons: count ≥ share × n.
                    counts[k][0] += (at[k][0] as f64 >= TARGET_SHARE * n as f64) as u32;
                    counts[k][1] += (at[k][1] as f64 >= MINIMUM_SHARE * n as f64) as u32;
                }
            }
        }
        self.daylight_hours += daylight.iter().filter(|&&d| d).count() as u32;
    }

    /// Each grid's provision (every share 0 and no level when no daylight hour was counted).
    pub fn finish(&self) -> Vec<Provision> {
        let d = self.daylight_hours;
        self.hours
            .iter()
            .map(|counts| {
                let shares = counts.map(|c| c.map(|h| h as f64 / d.max(1) as f64));
                let met = |k: usize| {
                    d > 0 && counts[k].iter().all(|&h| h as f64 >= TIME_SHARE * d as f64)
                };
                Provision {
                    daylight_hours: d,
                    shares,
                    level: (0..3).rev().find(|&k| met(k)),
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Feed `series[i][h]` in blocks of `block` hours.
    fn run(
        grids: Vec<Range<usize>>,
        daylight: &[bool],
        series: &[Vec<f64>],
        block: usize,
    ) -> Vec<Provision> {
        let points = series.len();
        let hours = daylight.len();
        let mut acc = ProvisionAccumulator::new(grids);
        let mut h0 = 0;
        while h0 < hours {
            let nb = block.min(hours - h0);
            let mut t = vec![0.0; points * nb];
            for i in 0..points {
                for h in 0..nb {
                    t[i * nb + h] = series[i][h0 + h];
                }
            }
            acc.add_block(&daylight[h0..h0 + nb], &t);
            h0 += nb;
        }
        acc.finish()
    }

    /// Twenty points, eight hours of which four are daylight hours, by hand:
    /// - hours 0 and 1: every point at 800 lx (every level's both criteria);
    /// - hour 2: 10 points at 500 lx (exactly E_T of medium over exactly half: counts), 9 at
    ///   300 and one at 99.9 (E_TM of minimum over 19 of 20 = 95 %: counts; 100 lx is not
    ///   reached by the last point);
    /// - hour 3: 9 points at 750, 11 at 0 (no criterion);
    /// - hours 4–7 (not daylight hours): 0, to be skipped.
    ///
    /// Minimum: E_T 300 over ≥ 10 points in hours 0, 1, 2 (3 of 4); E_TM 100 over ≥ 19 points
    /// in hours 0, 1, 2 (3 of 4): met. Medium: E_T 500 in 0, 1, 2 (3 of 4); E_TM 300 over ≥ 19
    /// in 0, 1, 2 (hour 2 has 19 at ≥ 300): met. High: E_T 750 in 0, 1 (hour 3 has 9 < 10):
    /// 2 of 4, exactly half: counts; E_TM 500 over ≥ 19 in 0, 1 (2 of 4): met.
    #[test]
    fn hand_made_hours() {
        let hours = 8;
        let daylight: Vec<bool> = (0..hours).map(|h| h < 4).collect();
        let series: Vec<Vec<f64>> = (0..20)
            .map(|i| {
                let h2 = if i < 10 {
                    500.0
                } else if i < 19 {
                    300.0
                } else {
                    99.9
                };
                let h3 = if i < 9 { 750.0 } else { 0.0 };
                vec![800.0, 800.0, h2, h3, 0.0, 0.0, 0.0, 0.0]
            })
            .collect();
        for block in [1, 3, 8] {
            let p = run(std::iter::once(0..20).collect(), &daylight, &series, block);
            assert_eq!(p.len(), 1);
            let p = &p[0];
            assert_eq!(p.daylight_hours, 4);
            assert_eq!(p.shares, [[0.75, 0.75], [0.75, 0.75], [0.5, 0.5]]);
            assert_eq!(p.level, Some(2));
            assert_eq!(p.level_name(), "high");
        }
        // Hour 1 darker: high's E_T then holds in 1 hour of 4, not met; medium still is.
        let mut dim = series.clone();
        for s in &mut dim {
            s[1] = 600.0;
        }
        let p = &run(std::iter::once(0..20).collect(), &daylight, &dim, 5)[0];
        assert_eq!(p.shares[2], [0.25, 0.5]);
        assert_eq!(p.level, Some(1));
        // Two grids. The first ten points: high's E_T (750 over 5) in hours 0, 1, 3, its
        // E_TM (500 over all 10) in hours 0, 1, 2 (hour 3 has 9 of 10 < 95 %).
        let p = run(vec![0..10, 10..20], &daylight, &series, 2);
        assert_eq!(p[0].shares[2], [0.75, 0.75]);
        assert_eq!(p[0].level, Some(2));
        // The other ten: in hour 2 nine at 300 and one at 99.9, so minimum's E_T holds in
        // hours 0–2 and its E_TM (100 over all 10) in hours 0 and 1 only: exactly half.
        assert_eq!(p[1].shares[0], [0.75, 0.5]);
        assert_eq!(p[1].shares[2], [0.5, 0.5]);
        assert_eq!(p[1].level, Some(2));
        // One more dark daylight hour (hour 4 made a daylight hour): 2 of 5 < half.
        let mut five = daylight.clone();
        five[4] = true;
        let p = run(std::iter::once(10..20).collect(), &five, &series, 3);
        assert_eq!(p[0].daylight_hours, 5);
        assert_eq!(p[0].shares[0], [0.6, 0.4]);
        assert_eq!(p[0].level, None);
        // No daylight hour: nothing met.
        let none = run(std::iter::once(0..20).collect(), &[false; 8], &series, 8);
        assert_eq!(none[0].level, None);
        assert_eq!(none[0].level_name(), "not met");
    }

    /// The daylight hours are the brighter half, ties and NaN in hour order.
    #[test]
    fn daylight_hours_are_the_brighter_half() {
        let d = [5.0, 1.0, 7.0, 1.0, f64::NAN, 9.0, 1.0, 0.0];
        assert_eq!(
            daylight_hours(&d),
            [true, true, true, false, false, true, false, false]
        );
        assert_eq!(daylight_hours(&[3.0; 5]), [true, true, false, false, false]);
        assert!(daylight_hours(&[]).is_empty());
    }
}

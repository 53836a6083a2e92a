//! Climate-based daylight metrics from hourly illuminance at points.
//!
//! - **Spatial daylight autonomy** sDA₃₀₀/₅₀% (IES LM-83-12, "Approved method: IES spatial
//!   daylight autonomy (sDA) and annual sunlight exposure (ASE)"): the share of points whose
//!   illuminance is at least 300 lx for at least 50 % of the occupied hours. Each point's
//!   share of occupied hours at or above 300 lx is its daylight autonomy DA₃₀₀ (Reinhart &
//!   Walkenhorst 2001).
//! - **Annual sunlight exposure** ASE₁₀₀₀,₂₅₀ (LM-83-12): the share of points that receive at
//!   least 1000 lx of *direct sunlight* (no sky, no interreflection: the caller passes that
//!   series apart) for more than 250 occupied hours.
//! - **Useful daylight illuminance** (Nabil & Mardaljevic 2005, with the upper limit raised
//!   to 3000 lx by Mardaljevic, Andersen, Roy & Christoffersen 2012): per point, the shares
//!   of occupied hours that *fell short* (E < 100 lx), are *supplementary* (100 ≤ E < 300),
//!   *autonomous* (300 ≤ E ≤ 3000) and *exceeded* (E > 3000); *useful* is supplementary plus
//!   autonomous (100…3000 lx). The four shares of a point sum to 1.
//!
//! The thresholds are [`MetricParams`]; occupancy is [`Occupancy`] (LM-83's 8:00–18:00 local
//! standard time every day of the year by default, 3,650 hours). Counting is in whole hours
//! per point, so the result does not depend on how the hours are split into blocks or over
//! threads.

use super::DaylightError;
use rayon::prelude::*;

/// Which hours count: those whose middle lies in `start..end` hours of local standard time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Occupancy {
    /// First occupied hour of the day (0…24).
    pub start: f64,
    /// End of the occupied period (0…24, after `start`).
    pub end: f64,
}

impl Default for Occupancy {
    /// 8:00 to 18:00 (IES LM-83-12).
    fn default() -> Self {
        Occupancy {
            start: 8.0,
            end: 18.0,
        }
    }
}

impl Occupancy {
    /// Whether an hour whose middle is `mid_hour` (local standard time) is occupied.
    pub fn occupied(&self, mid_hour: f64) -> bool {
        mid_hour >= self.start && mid_hour < self.end
    }

    /// Check the hours are in order within a day.
    pub fn validate(&self) -> Result<(), DaylightError> {
        if !(0.0..=24.0).contains(&self.start)
            || !(0.0..=24.0).contains(&self.end)
            || self.start >= self.end
        {
            return Err(DaylightError::Parameter(format!(
                "the occupied hours {}–{} are not a period within a day",
                self.start, self.end
            )));
        }
        Ok(())
    }
}

/// An occupancy schedule of `hours` hours from `text` (the file `name`, for errors): one
/// line an hour, in the weather file's order, whose last comma-separated field is 1
/// (occupied) or 0 (`1`, or `month,day,hour,1` as DAYSIM's files have it); blank lines and
/// lines starting with `#` are skipped, and so is a first line that is not numbers (a
/// header). Errors name the file and line: a value other than 0 or 1, a field that is not a
/// number, more hours than `hours` (refused at the first one too many), or fewer.
pub fn parse_schedule(text: &str, name: &str, hours: usize) -> Result<Vec<bool>, DaylightError> {
    let mut out = Vec::with_capacity(hours.min(text.len() / 2 + 1));
    let mut first = true;
    for (k, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let numbers: Option<Vec<f64>> = fields.iter().map(|f| f.parse::<f64>().ok()).collect();
        let Some(numbers) = numbers else {
            if first {
                first = false;
                continue;
            }
            return Err(super::invalid(
                name,
                k + 1,
                format!("{line:?} is not numbers (an hour's occupancy, 0 or 1, last)"),
            ));
        };
        first = false;
        let v = numbers[numbers.len() - 1];
        if v != 0.0 && v != 1.0 {
            return Err(super::invalid(
                name,
                k + 1,
                format!("occupancy {v}: must be 0 or 1"),
            ));
        }
        if out.len() == hours {
            return Err(super::invalid(
                name,
                k + 1,
                format!("more than the weather file's {hours} hours"),
            ));
        }
        out.push(v == 1.0);
    }
    if out.len() != hours {
        return Err(DaylightError::Parameter(format!(
            "{name}: {} hours of occupancy, the weather file has {hours}",
            out.len()
        )));
    }
    Ok(out)
}

/// The metrics' thresholds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetricParams {
    /// Daylight autonomy's illuminance, lx (300).
    pub sda_illuminance: f64,
    /// Share of occupied hours a point must reach it to count in sDA (0.5).
    pub sda_fraction: f64,
    /// ASE's direct-sun illuminance, lx (1000).
    pub ase_illuminance: f64,
    /// ASE's hours: a point counts when *more* than these occupied hours reach it (250).
    pub ase_hours: u32,
    /// UDI: below this fell short, lx (100).
    pub udi_low: f64,
    /// UDI: from this on autonomous, lx (300).
    pub udi_autonomous: f64,
    /// UDI: above this exceeded, lx (3000).
    pub udi_high: f64,
}

impl Default for MetricParams {
    fn default() -> Self {
        MetricParams {
            sda_illuminance: 300.0,
            sda_fraction: 0.5,
            ase_illuminance: 1000.0,
            ase_hours: 250,
            udi_low: 100.0,
            udi_autonomous: 300.0,
            udi_high: 3000.0,
        }
    }
}

impl MetricParams {
    /// Check the thresholds are finite, positive and in order.
    pub fn validate(&self) -> Result<(), DaylightError> {
        let ok = [self.sda_illuminance, self.ase_illuminance, self.udi_low]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0)
            && self.sda_fraction > 0.0
            && self.sda_fraction <= 1.0
            && self.udi_low <= self.udi_autonomous
            && self.udi_autonomous <= self.udi_high
            && self.udi_high.is_finite();
        if !ok {
            return Err(DaylightError::Parameter(format!(
                "the daylight metric thresholds are not positive and in order: {self:?}"
            )));
        }
        Ok(())
    }
}

/// Hour counts of one point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PointCounts {
    /// Occupied hours at or above the daylight-autonomy illuminance.
    pub autonomous_hours: u32,
    /// Occupied hours with direct sun at or above ASE's illuminance.
    pub sun_hours: u32,
    /// Occupied hours in UDI's bins: fell short, supplementary, autonomous, exceeded.
    pub udi_hours: [u32; 4],
}

/// The metrics of one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointMetrics {
    /// Daylight autonomy: the share of occupied hours at or above 300 lx.
    pub daylight_autonomy: f64,
    /// Occupied hours with at least 1000 lx of direct sun.
    pub sun_hours: u32,
    /// Shares of occupied hours fell short, supplementary, autonomous, exceeded.
    pub udi: [f64; 4],
    /// Whether the point counts in sDA.
    pub in_sda: bool,
    /// Whether the point counts in ASE.
    pub in_ase: bool,
}

/// The metrics of a grid of points.
#[derive(Clone, Debug, PartialEq)]
pub struct Metrics {
    /// Occupied hours counted.
    pub occupied_hours: u32,
    /// Per point.
    pub points: Vec<PointMetrics>,
    /// sDA: share of points (0…1).
    pub sda: f64,
    /// ASE: share of points (0…1).
    pub ase: f64,
    /// UDI: the points' mean shares (fell short, supplementary, autonomous, exceeded).
    pub udi: [f64; 4],
}

/// Hour counts per point, fed a block of hours at a time.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulator {
    params: MetricParams,
    counts: Vec<PointCounts>,
    occupied_hours: u32,
}

impl Accumulator {
    /// Counts for `points` points.
    pub fn new(points: usize, params: MetricParams) -> Accumulator {
        Accumulator {
            params,
            counts: vec![PointCounts::default(); points],
            occupied_hours: 0,
        }
    }

    /// Count the occupied hours of a block of `occupied.len()` hours: `total[i * hours + h]`
    /// is point i's illuminance in hour h, `sun[h * points + i]` its direct-sun illuminance
    /// (lx); hours whose `occupied` is false are skipped.
    pub fn add_block(&mut self, occupied: &[bool], total: &[f64], sun: &[f64]) {
        let hours = occupied.len();
        let points = self.counts.len();
        assert_eq!(total.len(), points * hours);
        assert_eq!(sun.len(), points * hours);
        let p = self.params;
        self.counts.par_iter_mut().enumerate().for_each(|(i, c)| {
            for h in (0..hours).filter(|&h| occupied[h]) {
                let e = total[i * hours + h];
                if e >= p.sda_illuminance {
                    c.autonomous_hours += 1;
                }
                if sun[h * points + i] >= p.ase_illuminance {
                    c.sun_hours += 1;
                }
                let bin = if e < p.udi_low {
                    0
                } else if e < p.udi_autonomous {
                    1
                } else if e <= p.udi_high {
                    2
                } else {
                    3
                };
                c.udi_hours[bin] += 1;
            }
        });
        self.occupied_hours += occupied.iter().filter(|&&o| o).count() as u32;
    }

    /// The counts so far.
    pub fn counts(&self) -> &[PointCounts] {
        &self.counts
    }

    /// The metrics from the counts (all shares 0 when no hour was occupied).
    pub fn finish(&self) -> Metrics {
        let p = &self.params;
        let n = self.occupied_hours.max(1) as f64;
        let points: Vec<PointMetrics> = self
            .counts
            .iter()
            .map(|c| PointMetrics {
                daylight_autonomy: c.autonomous_hours as f64 / n,
                sun_hours: c.sun_hours,
                udi: c.udi_hours.map(|h| h as f64 / n),
                in_sda: self.occupied_hours > 0
                    && c.autonomous_hours as f64 >= p.sda_fraction * self.occupied_hours as f64,
                in_ase: c.sun_hours > p.ase_hours,
            })
            .collect();
        let m = points.len().max(1) as f64;
        let share =
            |f: &dyn Fn(&PointMetrics) -> bool| points.iter().filter(|q| f(q)).count() as f64 / m;
        let mut udi = [0.0; 4];
        for q in &points {
            for k in 0..4 {
                udi[k] += q.udi[k] / m;
            }
        }
        Metrics {
            occupied_hours: self.occupied_hours,
            sda: share(&|q| q.in_sda),
            ase: share(&|q| q.in_ase),
            udi,
            points,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Feed per-point hourly series in blocks of `block` hours.
    fn run(series: &[Vec<f64>], sun: &[Vec<f64>], block: usize) -> Metrics {
        let points = series.len();
        let hours = series[0].len();
        let mut acc = Accumulator::new(points, MetricParams::default());
        let mut h0 = 0;
        while h0 < hours {
            let nb = block.min(hours - h0);
            let mut t = vec![0.0; points * nb];
            let mut s = vec![0.0; points * nb];
            for i in 0..points {
                for h in 0..nb {
                    t[i * nb + h] = series[i][h0 + h];
                    s[h * points + i] = sun[i][h0 + h];
                }
            }
            acc.add_block(&vec![true; nb], &t, &s);
            h0 += nb;
        }
        acc.finish()
    }

    #[test]
    fn hand_made_series() {
        // 10 occupied hours, three points:
        // p0: 5 hours at 300 (exactly the threshold), 5 at 50 → DA 0.5, in sDA.
        // p1: 4 at 3000 (autonomous: ≤ 3000), 1 at 3001 (exceeded), 5 at 150 → DA 0.5.
        // p2: 10 at 299.9 → DA 0, all supplementary.
        let p0: Vec<f64> = [300.0; 5].into_iter().chain([50.0; 5]).collect();
        let p1: Vec<f64> = [3000.0; 4]
            .into_iter()
            .chain([3001.0])
            .chain([150.0; 5])
            .collect();
        let p2 = vec![299.9; 10];
        let zero = vec![0.0; 10];
        for block in [1, 3, 10] {
            let m = run(
                &[p0.clone(), p1.clone(), p2.clone()],
                &[zero.clone(), zero.clone(), zero.clone()],
                block,
            );
            assert_eq!(m.occupied_hours, 10);
            assert_eq!(m.points[0].daylight_autonomy, 0.5);
            assert!(m.points[0].in_sda && m.points[1].in_sda && !m.points[2].in_sda);
            assert!((m.sda - 2.0 / 3.0).abs() < 1e-15);
            assert_eq!(m.points[0].udi, [0.5, 0.0, 0.5, 0.0]);
            assert_eq!(m.points[1].udi, [0.0, 0.5, 0.4, 0.1]);
            assert_eq!(m.points[2].udi, [0.0, 1.0, 0.0, 0.0]);
            let mean = [0.5 / 3.0, 1.5 / 3.0, 0.9 / 3.0, 0.1 / 3.0];
            for k in 0..4 {
                assert!((m.udi[k] - mean[k]).abs() < 1e-15);
            }
            assert_eq!(m.ase, 0.0);
        }
    }

    #[test]
    fn ase_counts_more_than_250_hours_of_direct_sun() {
        // 400 hours; p0 has 250 hours of 1000 lx direct sun (not more than 250: out), p1 has
        // 251 (in), p2 has 400 hours of 5000 lx total but only 999 lx of it direct (out).
        let hours = 400;
        let mk = |n: usize, v: f64| -> Vec<f64> {
            (0..hours).map(|h| if h < n { v } else { 0.0 }).collect()
        };
        let total = vec![mk(250, 1000.0), mk(251, 1200.0), mk(400, 5000.0)];
        let sun = vec![mk(250, 1000.0), mk(251, 1000.0), mk(400, 999.0)];
        let m = run(&total, &sun, 64);
        assert_eq!(m.points[0].sun_hours, 250);
        assert!(!m.points[0].in_ase && m.points[1].in_ase && !m.points[2].in_ase);
        assert!((m.ase - 1.0 / 3.0).abs() < 1e-15);
    }

    #[test]
    fn occupancy_schedules_are_read_or_refused_on_one_line() {
        let one = "1\n0\n\n# comment\n1\n";
        assert_eq!(
            parse_schedule(one, "s.csv", 3).unwrap(),
            [true, false, true]
        );
        let daysim = "month,day,hour,occupancy\n1,1,0.5,0\n1,1,1.5,1.0\n";
        assert_eq!(parse_schedule(daysim, "d.csv", 2).unwrap(), [false, true]);
        let err = |text: &str, hours: usize| {
            parse_schedule(text, "s.csv", hours)
                .unwrap_err()
                .to_string()
        };
        assert_eq!(err("1\n0.5\n", 2), "s.csv:2: occupancy 0.5: must be 0 or 1");
        assert_eq!(err("1\nNaN\n", 2), "s.csv:2: occupancy NaN: must be 0 or 1");
        assert_eq!(
            err("1\nyes\n", 2),
            "s.csv:2: \"yes\" is not numbers (an hour's occupancy, 0 or 1, last)"
        );
        assert_eq!(
            err("1\n1\n1\n", 2),
            "s.csv:3: more than the weather file's 2 hours"
        );
        assert_eq!(
            err("1\n", 2),
            "s.csv: 1 hours of occupancy, the weather file has 2"
        );
        assert_eq!(
            err("", 1),
            "s.csv: 0 hours of occupancy, the weather file has 1"
        );
    }

    #[test]
    fn occupancy_and_parameters() {
        let o = Occupancy::default();
        // EPW hours 9…18 (mid-hours 8.5…17.5) are occupied: 10 a day.
        let n = (1..=24).filter(|&h| o.occupied(h as f64 - 0.5)).count();
        assert_eq!(n, 10);
        assert!(o.validate().is_ok());
        assert!(Occupancy {
            start: 18.0,
            end: 8.0
        }
        .validate()
        .is_err());
        assert!(MetricParams::default().validate().is_ok());
        let bad = MetricParams {
            udi_high: 50.0,
            ..Default::default()
        };
        assert!(bad.validate().is_err());
    }
}

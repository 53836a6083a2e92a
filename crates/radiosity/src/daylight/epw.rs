//! EnergyPlus Weather (EPW) files: the site and the hourly records a daylight year needs.
//!
//! The format (EnergyPlus *Auxiliary Programs*, "EnergyPlus Weather File (EPW) Data
//! Dictionary"): comma-separated text, eight header lines and then one line an hour.
//!
//! - `LOCATION,City,State,Country,Source,WMO,Latitude,Longitude,TimeZone,Elevation` must be the
//!   first line: latitude in degrees north (−90…90), longitude in degrees east (west negative,
//!   −180…180), the time zone in hours from GMT (east positive, −12…14), elevation in metres.
//! - `HOLIDAYS/DAYLIGHT SAVINGS,LeapYearObserved,...`: `Yes` in its first field lets February
//!   have 29 days in the data periods' count.
//! - `DATA PERIODS,N,RecordsPerHour,Name,StartDay,Start,End[,Name,StartDay,Start,End…]`: only
//!   hourly files (one record an hour) are read; the periods' dates (`M/D`) give the number of
//!   records the file must hold, checked at its end.
//! - The other header lines (`DESIGN CONDITIONS`, `TYPICAL/EXTREME PERIODS`, `GROUND
//!   TEMPERATURES`, `COMMENTS 1`, `COMMENTS 2`) are skipped.
//! - Each data line: 1 year, 2 month, 3 day, 4 hour (1…24, the hour *ending* then, local
//!   standard time), 5 minute, 6 source flags, 7 dry-bulb and 8 dew-point temperature (°C),
//!   …, 14 global horizontal, 15 direct normal and 16 diffuse horizontal irradiance (W/m², the
//!   energy of the hour ending then divided by an hour), 17 global horizontal, 18 direct
//!   normal and 19 diffuse horizontal illuminance (lx), 20 zenith luminance (cd/m²), and more
//!   fields not read here. At least the first 16 fields must be present.
//!
//! The dictionary's "missing" codes read as `None`: 99.9 for the dew point, 9999 for an
//! irradiance, 999999 for an illuminance (anything at or above the code). Records must follow
//! each other hour by hour and day by day; at most [`MAX_RECORDS`] are read, so no file sizes
//! an allocation beyond a leap year's hours. Every problem is one line naming the file and the
//! line.

use super::{invalid, DaylightError};
use crate::photometry::{self, Lines};
use std::path::Path;

/// The most hourly records a file may hold: a leap year.
pub const MAX_RECORDS: usize = 8784;

/// The highest irradiance accepted, W/m² (the solar constant is 1361 W/m²; ground
/// measurements above 1,600 are instrument faults, not weather).
pub const MAX_IRRADIANCE: f64 = 1600.0;

/// The highest illuminance accepted, lx (direct sun outside the atmosphere is about 133 klx).
pub const MAX_ILLUMINANCE: f64 = 200_000.0;

/// The weather station.
#[derive(Clone, Debug, PartialEq)]
pub struct Location {
    /// The city field.
    pub city: String,
    /// Degrees north.
    pub latitude: f64,
    /// Degrees east (west negative).
    pub longitude: f64,
    /// Hours from GMT, east positive (the standard-time meridian is 15° × this).
    pub time_zone: f64,
    /// Metres above sea level.
    pub elevation: f64,
}

/// One hour of weather.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// The file's line (1-based), for messages.
    pub line: usize,
    /// The year field (typical-year files mix years from month to month).
    pub year: i32,
    /// 1…12.
    pub month: u32,
    /// 1…31.
    pub day: u32,
    /// 1…24: the hour ending then, local standard time.
    pub hour: u32,
    /// Dew-point temperature, °C.
    pub dew_point: Option<f64>,
    /// Global horizontal irradiance, W/m².
    pub global_horizontal: Option<f64>,
    /// Direct normal irradiance, W/m².
    pub direct_normal: Option<f64>,
    /// Diffuse horizontal irradiance, W/m².
    pub diffuse_horizontal: Option<f64>,
    /// Global horizontal illuminance, lx.
    pub global_illuminance: Option<f64>,
    /// Direct normal illuminance, lx.
    pub direct_illuminance: Option<f64>,
    /// Diffuse horizontal illuminance, lx.
    pub diffuse_illuminance: Option<f64>,
}

impl Record {
    /// The middle of the hour this record covers, hours of local standard time (0…24): the
    /// record of hour `h` covers `h − 1 … h`.
    pub fn mid_hour(&self) -> f64 {
        self.hour as f64 - 0.5
    }
}

/// A weather file: its site and its hours in order.
#[derive(Clone, Debug, PartialEq)]
pub struct Epw {
    /// The file's name, for messages.
    pub name: String,
    /// The station.
    pub location: Location,
    /// The hourly records in the file's order.
    pub records: Vec<Record>,
}

/// Read an EPW file (see the module documentation).
pub fn read_epw(path: &Path) -> Result<Epw, DaylightError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string());
    let bytes = crate::io::read_input(path).map_err(|source| DaylightError::Io {
        file: name.clone(),
        source,
    })?;
    parse_epw(&photometry::decode(&bytes), &name)
}

/// Days in `month` (1…12), February as `february` days.
fn days_in(month: u32, february: u32) -> u32 {
    match month {
        2 => february,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

/// Day of the year (1-based) of `month`/`day`, February as `february` days.
fn day_of_year(month: u32, day: u32, february: u32) -> u32 {
    (1..month).map(|m| days_in(m, february)).sum::<u32>() + day
}

/// A field as a finite number.
fn number(field: &str, what: &str) -> Result<f64, String> {
    photometry::number(field.trim(), what)
}

/// A field as a whole number in `lo..=hi`.
fn whole(field: &str, what: &str, lo: i64, hi: i64) -> Result<i64, String> {
    let v = number(field, what)?;
    if v.fract() != 0.0 || v < lo as f64 || v > hi as f64 {
        return Err(format!(
            "{what} {v} is not a whole number from {lo} to {hi}"
        ));
    }
    Ok(v as i64)
}

/// A measured value with a "missing" code: `None` at or above `missing`, else a number in
/// `lo..=hi`.
fn measured(
    field: &str,
    what: &str,
    lo: f64,
    hi: f64,
    missing: f64,
) -> Result<Option<f64>, String> {
    let v = number(field, what)?;
    if v >= missing {
        return Ok(None);
    }
    if v < lo || v > hi {
        return Err(format!("{what} {v} is outside {lo}…{hi}"));
    }
    Ok(Some(v))
}

/// `M/D` of a data period's start or end.
fn month_day(field: &str, february: u32) -> Result<(u32, u32), String> {
    let text = field.trim();
    let (m, d) = text
        .split_once('/')
        .ok_or_else(|| format!("date '{}' is not M/D", photometry::shown(text)))?;
    let m = whole(m, "month", 1, 12)? as u32;
    let d = whole(d, "day", 1, 31)? as u32;
    if d > days_in(m, february) {
        return Err(format!("{m}/{d} is not a date"));
    }
    Ok((m, d))
}

/// Parse an EPW file's text; `name` names it in messages.
pub fn parse_epw(text: &str, name: &str) -> Result<Epw, DaylightError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = Lines::new(text);
    let location = match lines.next() {
        Some((line, content)) => parse_location(content).map_err(|m| invalid(name, line, m))?,
        None => {
            return Err(invalid(
                name,
                1,
                "the file is empty: expected a LOCATION line",
            ))
        }
    };
    let mut february = 28;
    // The records the data periods announce (None until the DATA PERIODS line).
    let mut expected: Option<usize> = None;
    let mut records: Vec<Record> = Vec::new();
    let mut last_line = 1;
    for (line, content) in lines {
        last_line = line;
        let at = |m: String| invalid(name, line, m);
        if content.trim().is_empty() {
            continue;
        }
        let head = content.split(',').next().unwrap_or("").trim();
        if expected.is_none() {
            let keyword = head.to_ascii_uppercase();
            if keyword == "HOLIDAYS/DAYLIGHT SAVINGS" {
                let leap = content.split(',').nth(1).unwrap_or("").trim();
                if leap.eq_ignore_ascii_case("yes") {
                    february = 29;
                }
            } else if keyword == "DATA PERIODS" {
                expected = Some(parse_periods(content, february).map_err(at)?);
            } else if keyword == "LOCATION" {
                return Err(at("a second LOCATION line".into()));
            } else if head.parse::<f64>().is_ok() {
                return Err(at("a data record before the DATA PERIODS line".into()));
            }
            // Any other header line (design conditions, periods, ground temperatures,
            // comments) is not needed here.
            continue;
        }
        if records.len() == MAX_RECORDS {
            return Err(at(format!(
                "more than {MAX_RECORDS} hourly records (a leap year's hours)"
            )));
        }
        let record = parse_record(content, line, february).map_err(at)?;
        if let Some(previous) = records.last() {
            follows(previous, &record, february).map_err(at)?;
        }
        records.push(record);
    }
    let Some(expected) = expected else {
        return Err(invalid(name, last_line, "no DATA PERIODS line"));
    };
    if records.len() != expected {
        return Err(invalid(
            name,
            last_line,
            format!(
                "{} hourly records, but the data periods cover {} hours",
                records.len(),
                expected
            ),
        ));
    }
    Ok(Epw {
        name: name.to_string(),
        location,
        records,
    })
}

fn parse_location(content: &str) -> Result<Location, String> {
    let fields: Vec<&str> = content.split(',').take(11).collect();
    if !fields[0].trim().eq_ignore_ascii_case("LOCATION") {
        return Err("the first line is not a LOCATION line".into());
    }
    if fields.len() < 10 {
        return Err(format!(
            "LOCATION has {} fields, expected 10 (…, latitude, longitude, time zone, elevation)",
            fields.len()
        ));
    }
    let latitude = number(fields[6], "latitude")?;
    let longitude = number(fields[7], "longitude")?;
    let time_zone = number(fields[8], "time zone")?;
    let elevation = number(fields[9], "elevation")?;
    if latitude.abs() > 90.0 {
        return Err(format!("latitude {latitude} is outside −90…90 degrees"));
    }
    if longitude.abs() > 180.0 {
        return Err(format!("longitude {longitude} is outside −180…180 degrees"));
    }
    if !(-12.0..=14.0).contains(&time_zone) {
        return Err(format!("time zone {time_zone} is outside −12…14 hours"));
    }
    if !(-1000.0..=9000.0).contains(&elevation) {
        return Err(format!("elevation {elevation} is outside −1000…9000 m"));
    }
    Ok(Location {
        city: fields[1].trim().to_string(),
        latitude,
        longitude,
        time_zone,
        elevation,
    })
}

/// The hours the data periods cover.
fn parse_periods(content: &str, february: u32) -> Result<usize, String> {
    let fields: Vec<&str> = content.split(',').collect();
    if fields.len() < 3 {
        return Err("DATA PERIODS needs the number of periods and the records per hour".into());
    }
    let periods = whole(fields[1], "number of data periods", 1, 366)? as usize;
    let per_hour = whole(fields[2], "records per hour", 1, 60)?;
    if per_hour != 1 {
        return Err(format!(
            "{per_hour} records per hour: only hourly weather files are read"
        ));
    }
    if fields.len() < 3 + 4 * periods {
        return Err(format!(
            "DATA PERIODS announces {periods} periods but has fields for {}",
            (fields.len() - 3) / 4
        ));
    }
    let mut hours = 0;
    for k in 0..periods {
        let start = month_day(fields[3 + 4 * k + 2], february)?;
        let end = month_day(fields[3 + 4 * k + 3], february)?;
        let (a, b) = (
            day_of_year(start.0, start.1, february),
            day_of_year(end.0, end.1, february),
        );
        let year = 337 + february;
        let days = if b >= a { b - a + 1 } else { year - a + 1 + b };
        hours += 24 * days as usize;
    }
    Ok(hours)
}

fn parse_record(content: &str, line: usize, february: u32) -> Result<Record, String> {
    // The first 20 fields; the rest (wind, cloud, snow…) are not needed.
    let mut fields = [""; 20];
    let mut n = 0;
    for field in content.split(',').take(20) {
        fields[n] = field;
        n += 1;
    }
    if n < 16 {
        return Err(format!(
            "{n} fields, expected at least 16 (to the diffuse horizontal irradiance)"
        ));
    }
    let year = whole(fields[0], "year", -9999, 9999)? as i32;
    let month = whole(fields[1], "month", 1, 12)? as u32;
    let day = whole(fields[2], "day", 1, 31)? as u32;
    // Leap-day records appear in files whose header does not say so; take February's 29th.
    if day > days_in(month, february.max(29)) {
        return Err(format!("{month}/{day} is not a date"));
    }
    let hour = whole(fields[3], "hour", 1, 24)? as u32;
    let irradiance = |k: usize, what: &str| measured(fields[k], what, 0.0, MAX_IRRADIANCE, 9999.0);
    let illuminance = |k: usize, what: &str| -> Result<Option<f64>, String> {
        if k < n && !fields[k].trim().is_empty() {
            measured(fields[k], what, 0.0, MAX_ILLUMINANCE, 999_999.0)
        } else {
            Ok(None)
        }
    };
    Ok(Record {
        line,
        year,
        month,
        day,
        hour,
        dew_point: measured(fields[7], "dew point", -90.0, 70.0, 99.9)?,
        global_horizontal: irradiance(13, "global horizontal irradiance")?,
        direct_normal: irradiance(14, "direct normal irradiance")?,
        diffuse_horizontal: irradiance(15, "diffuse horizontal irradiance")?,
        global_illuminance: illuminance(16, "global horizontal illuminance")?,
        direct_illuminance: illuminance(17, "direct normal illuminance")?,
        diffuse_illuminance: illuminance(18, "diffuse horizontal illuminance")?,
    })
}

/// Whether `next` is the hour after `previous`.
fn follows(previous: &Record, next: &Record, february: u32) -> Result<(), String> {
    let expected_hour = previous.hour % 24 + 1;
    if next.hour != expected_hour {
        return Err(format!(
            "hour {} follows hour {} (records must be hourly and in order)",
            next.hour, previous.hour
        ));
    }
    let (m, d) = (previous.month, previous.day);
    let same = (next.month, next.day) == (m, d);
    if previous.hour < 24 {
        if !same {
            return Err(format!(
                "{}/{} hour {} follows {m}/{d} hour {}",
                next.month, next.day, next.hour, previous.hour
            ));
        }
        return Ok(());
    }
    // A new day: the next date, February's 29th optional.
    let next_day = |feb: u32| {
        if d < days_in(m, feb) {
            (m, d + 1)
        } else {
            (m % 12 + 1, 1)
        }
    };
    let ok = (next.month, next.day) == next_day(february)
        || (next.month, next.day) == next_day(29)
        || (m == 2 && d == 29 && (next.month, next.day) == (3, 1));
    if !ok {
        return Err(format!(
            "{}/{} follows {m}/{d}: days must follow each other",
            next.month, next.day
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One day (21 June) of a hand-written EPW in the dictionary's layout; the values of hour
    /// 13 are the ones checked.
    pub(crate) fn june_day() -> String {
        let mut s = String::new();
        s.push_str("LOCATION,Golden,CO,USA,Hand,724666,39.74,-105.18,-7.0,1829.0\n");
        s.push_str("DESIGN CONDITIONS,0\n");
        s.push_str("TYPICAL/EXTREME PERIODS,0\n");
        s.push_str("GROUND TEMPERATURES,0\n");
        s.push_str("HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\n");
        s.push_str("COMMENTS 1,written by hand for the reader's test\n");
        s.push_str("COMMENTS 2,\n");
        s.push_str("DATA PERIODS,1,1,Data,Sunday, 6/21, 6/21\n");
        for hour in 1..=24 {
            let (ghi, dni, dhi, gil, dnil, dhil) = match hour {
                13 => (1010, 905, 115, 108000, 88000, 14000),
                7..=20 => (300, 400, 100, 33000, 36000, 12000),
                _ => (0, 0, 0, 0, 0, 0),
            };
            s.push_str(&format!(
                "1999,6,21,{hour},60,?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9,\
                 24.5,{dew},30,82000,1300,1360,400,{ghi},{dni},{dhi},{gil},{dnil},{dhil},\
                 9999,200,3.5,2,1,16.1,77777,9,999999999,10,0.05,0,88,0.2,0,0\n",
                dew = if hour == 13 { "6.2" } else { "99.9" },
            ));
        }
        s
    }

    #[test]
    fn reads_the_site_and_the_hours() {
        let epw = parse_epw(&june_day(), "golden.epw").unwrap();
        let loc = &epw.location;
        assert_eq!(loc.city, "Golden");
        assert_eq!(
            (loc.latitude, loc.longitude, loc.time_zone, loc.elevation),
            (39.74, -105.18, -7.0, 1829.0)
        );
        assert_eq!(epw.records.len(), 24);
        let r = epw.records[12];
        assert_eq!(
            (r.line, r.year, r.month, r.day, r.hour),
            (21, 1999, 6, 21, 13)
        );
        assert_eq!(r.mid_hour(), 12.5);
        assert_eq!(r.dew_point, Some(6.2));
        assert_eq!(r.global_horizontal, Some(1010.0));
        assert_eq!(r.direct_normal, Some(905.0));
        assert_eq!(r.diffuse_horizontal, Some(115.0));
        assert_eq!(r.global_illuminance, Some(108000.0));
        assert_eq!(r.direct_illuminance, Some(88000.0));
        assert_eq!(r.diffuse_illuminance, Some(14000.0));
        // 99.9 is the dictionary's "missing" dew point.
        assert_eq!(epw.records[0].dew_point, None);
    }

    #[test]
    fn crlf_and_a_byte_order_mark_read_the_same() {
        let plain = parse_epw(&june_day(), "a.epw").unwrap();
        let dos = format!("\u{feff}{}", june_day().replace('\n', "\r\n"));
        assert_eq!(parse_epw(&dos, "a.epw").unwrap(), plain);
    }

    /// `text` with line `line` cut to its first `fields` fields.
    fn truncated(text: &str, line: usize, fields: usize) -> String {
        text.lines()
            .enumerate()
            .map(|(k, l)| {
                if k + 1 == line {
                    format!(
                        "{}\n",
                        l.split(',').take(fields).collect::<Vec<_>>().join(",")
                    )
                } else {
                    format!("{l}\n")
                }
            })
            .collect()
    }

    fn error(text: &str) -> String {
        parse_epw(text, "w.epw").unwrap_err().to_string()
    }

    #[test]
    fn bad_input_is_one_located_line() {
        let good = june_day();
        let cases: Vec<(String, &str)> = vec![
            (String::new(), "w.epw:1: the file is empty"),
            (
                good.replacen("LOCATION", "PLACE", 1),
                "w.epw:1: the first line",
            ),
            (good.replacen("39.74", "95", 1), "w.epw:1: latitude 95"),
            (
                good.replacen("39.74", "NaN", 1),
                "w.epw:1: latitude 'NaN' is not a finite",
            ),
            (
                good.replacen("DATA PERIODS,1,1", "DATA PERIODS,1,4", 1),
                "w.epw:8: 4 records per hour",
            ),
            (
                good.replacen(" 6/21, 6/21", " 6/21, 6/22", 1),
                "w.epw:32: 24 hourly records, but the data periods cover 48",
            ),
            (
                good.replacen("1999,6,21,13,", "1999,6,21,14,", 1),
                "w.epw:21: hour 14 follows hour 12",
            ),
            (
                good.replacen("1999,6,21,13,60,", "1999,6,31,13,60,", 1),
                "w.epw:21: 6/31 is not a date",
            ),
            (
                good.replacen(",905,", ",-905,", 1),
                "w.epw:21: direct normal irradiance -905 is outside",
            ),
            (
                good.replacen(",905,", ",x,", 1),
                "w.epw:21: direct normal irradiance 'x' is not a number",
            ),
            (
                good.replace("DATA PERIODS,1,1,Data,Sunday, 6/21, 6/21\n", ""),
                "w.epw:8: a data record before the DATA PERIODS line",
            ),
            (
                truncated(&good, 21, 8),
                "w.epw:21: 8 fields, expected at least 16",
            ),
        ];
        for (text, want) in cases {
            let got = error(&text);
            assert!(got.starts_with(want), "got '{got}', want '{want}…'");
            assert!(!got.contains('\n'));
        }
    }

    #[test]
    fn missing_irradiance_reads_as_none() {
        let text = june_day().replacen(",905,", ",9999,", 1);
        let epw = parse_epw(&text, "w.epw").unwrap();
        assert_eq!(epw.records[12].direct_normal, None);
    }

    #[test]
    fn a_year_of_records_is_counted_and_bounded() {
        // A whole (non-leap) year generated in the format: 8,760 records read; one more is
        // refused at its line, before any allocation beyond a leap year.
        let mut s = june_day()
            .lines()
            .take(7)
            .map(|l| format!("{l}\n"))
            .collect::<String>();
        s.push_str("DATA PERIODS,1,1,Data,Sunday, 1/ 1,12/31\n");
        let mut n = 0;
        for month in 1..=12 {
            for day in 1..=days_in(month, 28) {
                for hour in 1..=24 {
                    s.push_str(&format!(
                        "2001,{month},{day},{hour},0,x,1,2,3,4,5,6,7,8,9,10\n"
                    ));
                    n += 1;
                }
            }
        }
        assert_eq!(n, 8760);
        let epw = parse_epw(&s, "y.epw").unwrap();
        assert_eq!(epw.records.len(), 8760);
        let mut t = s.clone();
        for hour in 1..=24 {
            t.push_str(&format!("2001,1,1,{hour},0,x,1,2,3,4,5,6,7,8,9,10\n"));
        }
        let e = error(&t);
        assert!(
            e.contains("hourly records, but the data periods cover 8760"),
            "{e}"
        );
        // Over a leap year's hours: refused at the line that goes over.
        let mut u = s.replacen(
            "DATA PERIODS,1,1,Data,Sunday, 1/ 1,12/31",
            "DATA PERIODS,2,1,A,Sunday, 1/ 1,12/31,B,Monday,1/1,12/31",
            1,
        );
        for _ in 0..2 {
            for month in 1..=12 {
                for day in 1..=days_in(month, 28) {
                    for hour in 1..=24 {
                        u.push_str(&format!(
                            "2001,{month},{day},{hour},0,x,1,2,3,4,5,6,7,8,9,10\n"
                        ));
                    }
                }
            }
        }
        let e = parse_epw(&u, "u.epw").unwrap_err().to_string();
        assert!(e.contains("more than 8784 hourly records"), "{e}");
    }

    #[test]
    fn mutated_files_never_panic() {
        // Every single-byte deletion and a few substitutions of the excerpt: an error or a
        // file, never a panic.
        let good = june_day();
        let bytes = good.as_bytes();
        let step = 7;
        for i in (0..bytes.len()).step_by(step) {
            for replacement in [None, Some(b','), Some(b'9'), Some(b'\n'), Some(b'-')] {
                let mut m = bytes.to_vec();
                match replacement {
                    None => {
                        m.remove(i);
                    }
                    Some(b) => m[i] = b,
                }
                let text = String::from_utf8_lossy(&m);
                if let Err(e) = parse_epw(&text, "m.epw") {
                    assert!(!e.to_string().contains('\n'));
                }
            }
        }
    }
}

//! `radiosity lighting --weather --annual`: a year of daylight over an open floor, and bad
//! annual input.

use crate::common::*;
use radiosity::daylight::perez::Condition;
use radiosity::daylight::solar::{solar_position, Site};
use std::path::Path;

/// A synthetic EPW year at latitude, longitude 0 (time zone 0): no direct sun, a constant
/// diffuse horizontal irradiance `dhi` W/m² in the hours ending 7…18 (the sun is up through
/// all of them on the equator) and none otherwise; dew point 8 °C.
fn year_epw(dhi: f64) -> String {
    let mut s = String::from(
        "LOCATION,Equator,,,test,0,0,0,0,10\nDESIGN CONDITIONS,0\nTYPICAL/EXTREME PERIODS,0\n\
         GROUND TEMPERATURES,0\nHOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\nCOMMENTS 1,\nCOMMENTS 2,\n\
         DATA PERIODS,1,1,Data,Sunday, 1/ 1,12/31\n",
    );
    let days = [31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31];
    for month in 1..=12u32 {
        for day in 1..=days[month as usize - 1] {
            for hour in 1..=24 {
                let d = if (7..=18).contains(&hour) { dhi } else { 0.0 };
                s.push_str(&format!(
                    "2005,{month},{day},{hour},60,x,20,8,50,100000,0,0,0,{d},0,{d}\n"
                ));
            }
        }
    }
    s
}

/// A 10 × 10 m floor facing up with nothing above it, and five points 0.5 m over it facing up.
fn open_floor(dir: &Path) {
    write(
        dir,
        "floor.obj",
        "mtllib floor.mtl\nusemtl grey\nv 0 0 0\nv 10 0 0\nv 10 10 0\nv 0 10 0\nf 1 2 3 4\n",
    );
    write(dir, "floor.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
    write(
        dir,
        "points.pts",
        "5 5 0.5 0 0 1\n1 1 0.5 0 0 1\n9 9 0.5 0 0 1\n2 8 0.5 0 0 1\n7 3 0.5 0 0 1\n",
    );
}

/// The Perez diffuse illuminance of each hour of `year_epw(dhi)`, lx (0 for the dark hours):
/// the model's E_d = DHI × the diffuse efficacy at the sun's mid-hour altitude.
fn expected(dhi: f64) -> Vec<f64> {
    let site = Site {
        latitude: 0.0,
        longitude: 0.0,
        time_zone: 0.0,
    };
    let days = [31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31];
    let mut out = Vec::new();
    let mut doy = 0;
    for month in 1..=12u32 {
        for day in 1..=days[month as usize - 1] {
            doy += 1;
            for hour in 1..=24u32 {
                if !(7..=18).contains(&hour) {
                    out.push(0.0);
                    continue;
                }
                let pos = solar_position(&site, 2005, month, day, hour as f64 - 0.5);
                let c = Condition::new(0.0, dhi, pos.altitude, doy, 8.0);
                out.push(dhi * c.diffuse_efficacy());
            }
        }
    }
    out
}

/// Runs the year for `dhi` and checks every hour at every point against the Perez diffuse
/// illuminance; returns the metrics CSV's rows and the largest relative error.
fn year(dir: &Path, dhi: f64) -> (Vec<String>, Vec<Vec<String>>, f64, String) {
    write(dir, "year.epw", &year_epw(dhi));
    let stdout = run_ok(
        &[
            "lighting",
            "floor.obj",
            "--weather",
            "year.epw",
            "--grid",
            "points.pts",
            "--annual",
            "annual.csv",
            "--hourly",
            "hourly.csv",
            "--summary",
            "summary.json",
            "--patches",
            "4",
        ],
        dir,
    );
    let want = expected(dhi);
    let (header, rows) = read_csv(&dir.join("hourly.csv"));
    assert_eq!(header.len(), 3 + 5);
    assert_eq!(rows.len(), 8760);
    let mut worst = 0.0f64;
    for (h, row) in rows.iter().enumerate() {
        for v in &row[3..] {
            let e: f64 = v.parse().unwrap();
            if want[h] == 0.0 {
                assert_eq!(e, 0.0, "hour {h}: a dark hour gives {e} lx");
            } else {
                // The hourly file has 0.1 lx steps.
                worst = worst.max(((e - want[h]).abs() - 0.05).max(0.0) / want[h]);
            }
        }
    }
    let (mh, mrows) = read_csv(&dir.join("annual.csv"));
    (mh, mrows, worst, stdout)
}

#[test]
fn an_open_floor_gets_the_weather_files_diffuse_illuminance_every_hour() {
    let dir = scratch("annual-open-floor");
    open_floor(&dir);
    // Every hour sees the whole sky and no ground (the points face up): the patches'
    // luminances are normalised so that an unobstructed horizontal surface gets exactly
    // E_d, and the coefficients are each patch's cosine-weighted solid angle integrated by
    // 16,384 stratified rays; patch edges cut strata, an error of order N^(−3/4) ≈ 7·10⁻⁴
    // relative per edge, averaging down over 145 patches: 0.5 % bounds it.
    for (dhi, bright) in [(100.0, true), (1.0, false)] {
        let (h, rows, worst, stdout) = year(&dir, dhi);
        eprintln!("DHI {dhi} W/m²: largest relative error {worst:.2e}");
        assert!(worst < 5e-3, "DHI {dhi}: {worst}");
        let e = expected(dhi);
        let lit: Vec<f64> = e.iter().copied().filter(|&v| v > 0.0).collect();
        let (lo, hi) = lit
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        let (da, sun, short, supp, auto, exc, in_sda, in_ase) = (
            column(&h, "daylight_autonomy"),
            column(&h, "sun_hours"),
            column(&h, "udi_fell_short"),
            column(&h, "udi_supplementary"),
            column(&h, "udi_autonomous"),
            column(&h, "udi_exceeded"),
            column(&h, "in_sda"),
            column(&h, "in_ase"),
        );
        assert_eq!(rows.len(), 5);
        for r in &rows {
            assert_eq!(r[sun], "0", "no direct sun");
            assert_eq!(r[in_ase], "0");
            if bright {
                // 100 W/m² of diffuse light is far above 3000 lx in every hour.
                assert!(lo > 3000.0 * 1.01, "{lo}");
                assert_eq!((&*r[da], &*r[in_sda], &*r[exc]), ("1.0000", "1", "1.0000"));
            } else {
                // 1 W/m² is supplementary (100–300 lx) in every hour: sDA 0.
                assert!(lo > 100.0 * 1.01 && hi < 300.0 * 0.99, "{lo}…{hi}");
                assert_eq!((&*r[da], &*r[in_sda], &*r[supp]), ("0.0000", "0", "1.0000"));
                assert_eq!((&*r[short], &*r[auto]), ("0.0000", "0.0000"));
            }
        }
        let sda = if bright {
            "sDA300/50% 100.0 %"
        } else {
            "sDA300/50% 0.0 %"
        };
        assert!(stdout.contains(sda), "{stdout}");
        assert!(stdout.contains("ASE1000,250 0.0 %"), "{stdout}");
        let summary: serde_json::Value = serde_json::from_str(&read(&dir, "summary.json")).unwrap();
        let g = &summary["annual"]["grids"][0];
        assert_eq!(g["points"], 5);
        assert_eq!(g["sda"], if bright { 1.0 } else { 0.0 });
        assert_eq!(g["ase"], 0.0);
        // Occupied 8:00–18:00: ten hours a day, all lit.
        assert_eq!(summary["annual"]["occupied_hours"], 3650);
        assert_eq!(summary["annual"]["lit_hours"], 12 * 365);
        // EN 17037: the daylight hours are the brighter half of the year, here exactly the
        // 4,380 lit hours. At 100 W/m² every point is far above 750 lx in each: every level's
        // both criteria in every daylight hour, the high level. At 1 W/m² (100–300 lx) no
        // hour reaches 300 lx over half the points, every hour 100 lx over all: not met.
        let en = &g["en17037"];
        assert_eq!(en["daylight_hours"], 4380);
        let share = |level: &str, which: &str| en["levels"][level][which].as_f64().unwrap();
        if bright {
            assert_eq!(en["level"], "high");
            for level in ["minimum", "medium", "high"] {
                assert_eq!(share(level, "target_hours_share"), 1.0);
                assert_eq!(share(level, "minimum_hours_share"), 1.0);
            }
            assert!(
                stdout.contains("EN 17037    points.pts: daylight provision high"),
                "{stdout}"
            );
        } else {
            assert_eq!(en["level"], "not met");
            assert_eq!(share("minimum", "target_hours_share"), 0.0);
            assert_eq!(share("minimum", "minimum_hours_share"), 1.0);
            assert_eq!(share("medium", "minimum_hours_share"), 0.0);
            assert!(stdout.contains("daylight provision not met"), "{stdout}");
        }
    }
}

#[test]
fn bad_annual_input_is_refused_on_one_line() {
    let dir = scratch("annual-bad");
    open_floor(&dir);
    let keep = ["floor.obj", "floor.mtl", "points.pts", "year.epw"];
    let base = ["lighting", "floor.obj", "--grid", "points.pts"];
    let with = |extra: &[&'static str]| -> Vec<&'static str> {
        base.iter().chain(extra).copied().collect()
    };
    fails(
        &with(&["--annual", "annual.csv"]),
        &dir,
        &["--annual", "--weather"],
        &keep,
    );
    fails(
        &with(&["--weather", "missing.epw", "--annual", "annual.csv"]),
        &dir,
        &["missing.epw"],
        &keep,
    );
    write(&dir, "year.epw", &year_epw(100.0));
    fails(
        &with(&["--weather", "year.epw", "--annual", "annual.txt"]),
        &dir,
        &["annual.txt", "csv"],
        &keep,
    );
    fails(
        &with(&[
            "--weather",
            "year.epw",
            "--annual",
            "a.csv",
            "--sky-patches",
            "0",
        ]),
        &dir,
        &["--sky-patches"],
        &keep,
    );
    fails(
        &with(&[
            "--weather",
            "year.epw",
            "--annual",
            "a.csv",
            "--sky",
            "uniform",
        ]),
        &dir,
        &["--sky"],
        &keep,
    );
    // A malformed weather file: its line named, nothing written.
    let bad = year_epw(100.0).replacen(
        "2005,1,1,12,60,x,20,8,50,100000,0,0,0,100,0,100",
        "2005,1,1,12,60,x,20,8,50,100000,0,0,0,100,0,abc",
        1,
    );
    write(&dir, "year.epw", &bad);
    fails(
        &with(&[
            "--weather",
            "year.epw",
            "--annual",
            "a.csv",
            "--hourly",
            "h.csv",
        ]),
        &dir,
        &["year.epw:20"],
        &keep,
    );
}

/// `year_epw(100)` with direct sun too: a direct normal irradiance of 300 W/m² in the hours
/// ending 12 and 13 of the first 200 days (400 hours, the sun at 66°–90° on the equator),
/// none otherwise.
fn sunny_epw() -> String {
    let mut doy = 0;
    let mut last = (0, 0);
    year_epw(100.0)
        .lines()
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            if f.len() < 16 || f[0] != "2005" {
                return format!("{line}\n");
            }
            let (m, d, h): (u32, u32, u32) = (
                f[1].parse().unwrap(),
                f[2].parse().unwrap(),
                f[3].parse().unwrap(),
            );
            if (m, d) != last {
                doy += 1;
                last = (m, d);
            }
            if doy <= 200 && (h == 12 || h == 13) {
                let mut g = f.clone();
                g[14] = "300";
                format!("{}\n", g.join(","))
            } else {
                format!("{line}\n")
            }
        })
        .collect()
}

/// Runs the open floor's year of `sunny_epw` with `extra` flags; the metrics CSV's header,
/// rows, and the summary.
fn sunny_year(dir: &Path, extra: &[&str]) -> (Vec<String>, Vec<Vec<String>>, serde_json::Value) {
    let mut args = vec![
        "lighting",
        "floor.obj",
        "--weather",
        "sunny.epw",
        "--grid",
        "points.pts",
        "--annual",
        "annual.csv",
        "--summary",
        "summary.json",
        "--patches",
        "4",
    ];
    args.extend_from_slice(extra);
    run_ok(&args, dir);
    let (h, rows) = read_csv(&dir.join("annual.csv"));
    let summary = serde_json::from_str(&read(dir, "summary.json")).unwrap();
    (h, rows, summary)
}

/// The annual flags against hand counts on the open floor (points facing up, nothing above:
/// every lit hour has E_d ≈ 12 klx of sky, the sunny hours E_n sin α ≈ 25–35 klx more):
/// - ASE: the sun's patch term exceeds 1000 lx in exactly the 400 sunny hours (all occupied
///   8–18), so `--ase-hours 399` puts every point in ASE and `--ase-hours 400` none ("more
///   than"); `--ase-threshold 100000` (above any hour) leaves no sun hour;
/// - `--occupancy 12-13`: only the hour ending 13 counts, 365 hours, 200 of them sunny;
/// - `--occupancy 6-20`: the hours ending 7…20, 14 a day, 5,110, of which the 12 lit ones
///   reach 300 lx: daylight autonomy 12/14 = 0.8571, in sDA with `--sda-fraction 0.85`, out
///   of it with 0.9;
/// - `--sda-threshold 100000 --udi-range 50,200000`: no hour reaches 100 klx (autonomy 0),
///   every occupied hour lies in 50 lx…100 klx (UDI supplementary 1).
#[test]
fn the_annual_flags_change_the_metrics_as_counted_by_hand() {
    let dir = scratch("annual-flags");
    open_floor(&dir);
    write(&dir, "sunny.epw", &sunny_epw());
    let every = |h: &[String], rows: &[Vec<String>], col: &str, want: &str| {
        let c = column(h, col);
        for r in rows {
            assert_eq!(r[c], want, "{col}");
        }
    };
    let (h, rows, s) = sunny_year(&dir, &["--ase-hours", "399"]);
    every(&h, &rows, "sun_hours", "400");
    every(&h, &rows, "in_ase", "1");
    assert_eq!(s["annual"]["grids"][0]["ase"], 1.0);
    assert_eq!(s["annual"]["thresholds"]["ase_hours"], 399);
    let (h, rows, s) = sunny_year(&dir, &["--ase-hours", "400"]);
    every(&h, &rows, "sun_hours", "400");
    every(&h, &rows, "in_ase", "0");
    assert_eq!(s["annual"]["grids"][0]["ase"], 0.0);
    let (h, rows, _) = sunny_year(&dir, &["--ase-threshold", "100000"]);
    every(&h, &rows, "sun_hours", "0");

    let (h, rows, s) = sunny_year(&dir, &["--occupancy", "12-13"]);
    assert_eq!(s["annual"]["occupied_hours"], 365);
    every(&h, &rows, "sun_hours", "200");
    every(&h, &rows, "daylight_autonomy", "1.0000");
    let by_period = read(&dir, "annual.csv");
    // The same hours from a schedule file, plain and DAYSIM's month,day,hour,value with a
    // header and a comment: the same metrics, byte for byte.
    let plain: String = (0..365 * 24)
        .map(|k| if k % 24 == 12 { "1\n" } else { "0\n" })
        .collect();
    let daysim: String =
        std::iter::once("month,day,hour,occupancy\n# hours ending 13\n".to_string())
            .chain((0..365 * 24).map(|k| format!("1,1,{}.5,{}\n", k % 24, (k % 24 == 12) as u8)))
            .collect();
    for (name, text) in [("plain.csv", plain), ("daysim.csv", daysim)] {
        write(&dir, name, &text);
        let (_, _, s) = sunny_year(&dir, &["--occupancy-schedule", name]);
        assert_eq!(s["annual"]["occupied_hours"], 365);
        assert_eq!(s["annual"]["occupancy"], name);
        assert_eq!(read(&dir, "annual.csv"), by_period, "{name}");
    }

    for (fraction, inside) in [("0.85", "1"), ("0.9", "0")] {
        let (h, rows, s) = sunny_year(&dir, &["--occupancy", "6-20", "--sda-fraction", fraction]);
        assert_eq!(s["annual"]["occupied_hours"], 5110);
        every(&h, &rows, "daylight_autonomy", "0.8571");
        every(&h, &rows, "udi_fell_short", "0.1429");
        every(&h, &rows, "in_sda", inside);
    }

    let (h, rows, s) = sunny_year(
        &dir,
        &["--sda-threshold", "100000", "--udi-range", "50,200000"],
    );
    every(&h, &rows, "daylight_autonomy", "0.0000");
    every(&h, &rows, "udi_supplementary", "1.0000");
    every(&h, &rows, "udi_exceeded", "0.0000");
    assert_eq!(s["annual"]["grids"][0]["sda"], 0.0);
    assert_eq!(s["annual"]["thresholds"]["udi"][2], 200000.0);
}

#[test]
fn bad_annual_flags_are_refused_on_one_line() {
    let dir = scratch("annual-bad-flags");
    open_floor(&dir);
    write(&dir, "year.epw", &year_epw(1.0));
    write(&dir, "half.csv", "occupancy\n1\n0.5\n");
    write(&dir, "short.csv", "1\n0\n");
    let keep = [
        "floor.obj",
        "floor.mtl",
        "points.pts",
        "year.epw",
        "half.csv",
        "short.csv",
    ];
    let annual = [
        "lighting",
        "floor.obj",
        "--grid",
        "points.pts",
        "--weather",
        "year.epw",
        "--annual",
        "a.csv",
    ];
    let with = |extra: &[&'static str]| -> Vec<&'static str> {
        annual.iter().chain(extra).copied().collect()
    };
    for (extra, words) in [
        (&["--occupancy", "18-8"][..], &["--occupancy 18-8"][..]),
        (&["--occupancy", "eight"], &["--occupancy", "START-END"]),
        (&["--udi-range", "300"], &["--udi-range", "LOW,HIGH"]),
        (&["--udi-range", "3000,100"], &["--udi-range", "LOW < HIGH"]),
        (
            &["--udi-range", "400,3000"],
            &["--udi-range", "sDA threshold"],
        ),
        (&["--sda-fraction", "0"], &["--sda-fraction"]),
        (&["--sda-threshold", "0"], &["--sda-threshold"]),
        (&["--ase-threshold", "nan"], &["--ase-threshold"]),
        (
            &["--occupancy-schedule", "half.csv"],
            &[
                "--occupancy-schedule half.csv",
                "half.csv:3: occupancy 0.5: must be 0 or 1",
            ],
        ),
        (
            &["--occupancy-schedule", "short.csv"],
            &[
                "--occupancy-schedule short.csv",
                "2 hours of occupancy",
                "8760",
            ],
        ),
        (
            &["--occupancy-schedule", "none.csv"],
            &["--occupancy-schedule none.csv", "cannot be read"],
        ),
        (
            &["--occupancy-schedule", "short.csv", "--occupancy", "8-18"],
            &["--occupancy and --occupancy-schedule"],
        ),
        (
            &["--occupancy-schedule", "points.pts"],
            &["--occupancy-schedule points.pts", "is not numbers"],
        ),
    ] {
        fails(&with(extra), &dir, words, &keep);
    }
    // Without a year they mean nothing.
    fails(
        &[
            "lighting",
            "floor.obj",
            "--grid",
            "points.pts",
            "--sky",
            "uniform",
            "--out",
            "g.csv",
            "--occupancy",
            "8-18",
        ],
        &dir,
        &["--occupancy", "--weather"],
        &keep,
    );
}

/// `--sun-method exact` on the open floor (points facing up, nothing above, so the sun's
/// interreflection is nil): every sunny hour is the Perez diffuse illuminance plus the sun's
/// E_n sin α exactly (E_n = DNI × the Perez direct efficacy, computed here from
/// `daylight::perez` and `daylight::solar`), within the sky patches' 5e-3 of the diffuse
/// part (see the first test; the sun's part is shadow rays, exact here); the 400 sunny hours
/// are ASE's sun hours. The printed sky line and the summary name the method.
#[test]
fn the_exact_sun_adds_e_n_sin_alpha_at_an_unobstructed_point() {
    let dir = scratch("annual-exact-sun");
    open_floor(&dir);
    write(&dir, "sunny.epw", &sunny_epw());
    let (h, rows, s) = sunny_year(&dir, &["--sun-method", "exact", "--hourly", "hourly.csv"]);
    assert_eq!(s["annual"]["sun"], "exact");
    let c = column(&h, "sun_hours");
    for r in &rows {
        assert_eq!(r[c], "400");
    }
    let site = Site {
        latitude: 0.0,
        longitude: 0.0,
        time_zone: 0.0,
    };
    let (_, hourly) = read_csv(&dir.join("hourly.csv"));
    let days = [31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31];
    let (mut doy, mut row, mut worst, mut sunny) = (0, 0, 0.0f64, 0);
    for month in 1..=12u32 {
        for day in 1..=days[month as usize - 1] {
            doy += 1;
            for hour in 1..=24u32 {
                let r = &hourly[row];
                row += 1;
                if !(doy <= 200 && (hour == 12 || hour == 13)) {
                    continue;
                }
                sunny += 1;
                let pos = solar_position(&site, 2005, month, day, hour as f64 - 0.5);
                let c = Condition::new(300.0, 100.0, pos.altitude, doy, 8.0);
                let want =
                    100.0 * c.diffuse_efficacy() + 300.0 * c.direct_efficacy() * pos.altitude.sin();
                for v in &r[3..] {
                    let e: f64 = v.parse().unwrap();
                    worst = worst.max((e - want).abs() / want);
                }
            }
        }
    }
    assert_eq!(sunny, 400);
    assert!(worst < 5e-3, "{worst}");
}

/// `--sun-method` defaults to `exact`: with no flag the hourly file is byte for byte the
/// explicit exact run's (same seed) and the summary says `exact`; `--sun-method patch` is
/// still there and says `patch`.
#[test]
fn the_sun_method_defaults_to_exact() {
    let dir = scratch("annual-sun-default");
    open_floor(&dir);
    write(&dir, "sunny.epw", &sunny_epw());
    let (_, _, s) = sunny_year(&dir, &["--hourly", "default.csv"]);
    assert_eq!(s["annual"]["sun"], "exact");
    let (_, _, s) = sunny_year(&dir, &["--sun-method", "exact", "--hourly", "exact.csv"]);
    assert_eq!(s["annual"]["sun"], "exact");
    assert_eq!(
        read_bytes(&dir, "default.csv"),
        read_bytes(&dir, "exact.csv")
    );
    let (_, _, s) = sunny_year(&dir, &["--sun-method", "patch"]);
    assert_eq!(s["annual"]["sun"], "patch");
}

/// `--pictures` in an annual run: each grid's daylight-autonomy map. On the open floor under
/// 100 W/m² of diffuse light every occupied hour is above 300 lx, so DA = 100 % at every
/// point of a 4 × 4 lattice and the map is one colour, the legend's colour of 100 %; a
/// folder that is a file is refused before any work.
#[test]
fn an_annual_run_draws_its_daylight_autonomy() {
    use radiosity::lighting::{SensorPoint, Up};
    use radiosity_cli::false_colour::grid::{map_scale, GridPictures};
    use radiosity_cli::false_colour::Bands;
    use std::path::PathBuf;
    let dir = scratch("annual-pictures");
    open_floor(&dir);
    write(&dir, "year.epw", &year_epw(100.0));
    let mut pts = String::new();
    let mut points = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            let (x, y) = (2.0 + 2.0 * i as f64, 2.0 + 2.0 * j as f64);
            pts += &format!("{x} {y} 0.5 0 0 1\n");
            points.push(SensorPoint::new([x, y, 0.5], [0.0, 0.0, 1.0]).unwrap());
        }
    }
    write(&dir, "desk.pts", &pts);
    write(&dir, "taken", "a file\n");
    let args = |pictures: &'static str| {
        [
            "lighting",
            "floor.obj",
            "--weather",
            "year.epw",
            "--grid",
            "desk.pts",
            "--annual",
            "annual.csv",
            "--pictures",
            pictures,
            "--patches",
            "4",
            "--sky-rays",
            "256",
        ]
    };
    fails(
        &args("taken/pics"),
        &dir,
        &["--pictures taken/pics", "not a folder"],
        &[
            "floor.obj",
            "floor.mtl",
            "points.pts",
            "year.epw",
            "desk.pts",
            "taken",
        ],
    );
    let text = run_ok(&args("pics"), &dir);
    assert!(text.contains("desk-daylight-autonomy.png"), "{text}");
    let (h, rows) = read_csv(&dir.join("annual.csv"));
    let da = column(&h, "daylight_autonomy");
    assert!(rows.iter().all(|r| r[da] == "1.0000"));
    let pics = dir.join("pics");
    let layout = GridPictures::prepare(
        &pics,
        &[("desk.pts".to_string(), 0..16)],
        &[PathBuf::from("desk.pts")],
        &points,
        Up::Z,
        "m",
    )
    .unwrap();
    let (_, plane, frame) = layout.frames().remove(0);
    let img = image::open(pics.join("desk-daylight-autonomy.png"))
        .unwrap()
        .to_rgb8();
    let bands = Bands::new(100.0, 100.0, map_scale(100.0, 100.0, false));
    let want = bands.colour(bands.band(100.0));
    for p in &points {
        let (x, y) = frame.pixel(plane.project(p.position));
        assert_eq!(img.get_pixel(x as u32, y as u32).0, want);
    }
    let svg = read(&pics, "desk-daylight-autonomy.svg");
    assert!(svg.contains("daylight autonomy") && svg.contains("sDA"));
}

/// `--hourly h.npy` writes NumPy's format: a `(8760, points)` float32 matrix whose values are
/// the CSV's (to its 0.1 lx steps), hour for hour and point for point.
#[test]
fn hourly_npy_holds_the_csvs_values() {
    let dir = scratch("annual-npy");
    open_floor(&dir);
    let (_, _, _, _) = year(&dir, 100.0);
    let (_, rows) = read_csv(&dir.join("hourly.csv"));
    run_ok(
        &[
            "lighting",
            "floor.obj",
            "--weather",
            "year.epw",
            "--grid",
            "points.pts",
            "--annual",
            "annual2.csv",
            "--hourly",
            "hourly.npy",
            "--patches",
            "4",
        ],
        &dir,
    );
    let bytes = std::fs::read(dir.join("hourly.npy")).unwrap();
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let dict = std::str::from_utf8(&bytes[10..10 + len]).unwrap();
    let points = rows[0].len() - 3;
    assert!(
        dict.contains(&format!("'shape': (8760, {points})")) && dict.contains("'<f4'"),
        "{dict}"
    );
    let data: Vec<f32> = bytes[10 + len..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    assert_eq!(data.len(), 8760 * points);
    for (h, row) in rows.iter().enumerate() {
        for (i, v) in row[3..].iter().enumerate() {
            let csv: f64 = v.parse().unwrap();
            let npy = data[h * points + i] as f64;
            assert!(
                (csv - npy).abs() <= 0.05 + 1e-6 * npy,
                "hour {h}, point {i}: {csv} {npy}"
            );
        }
    }
}

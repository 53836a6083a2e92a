use super::*;
use crate::daylight::epw::parse_epw;
use crate::daylight::patches::SkyPatches;

/// The same sky every hour.
struct Constant {
    patches: SkyPatches,
    sky: Vec<f64>,
    hours: usize,
}

impl SkySource for Constant {
    fn patches(&self) -> &SkyPatches {
        &self.patches
    }
    fn hours(&self) -> usize {
        self.hours
    }
    fn sky(&self, h: usize, _: bool, out: &mut [f64]) -> Result<HourLight, DaylightError> {
        out.copy_from_slice(&self.sky);
        Ok(HourLight {
            occupied: Occupancy::default().occupied((h % 24) as f64 + 0.5),
            lit: true,
            ..Default::default()
        })
    }
}

/// A deterministic pseudo-random number in [0, 1) (a 64-bit LCG's high bits).
fn hash(i: u64) -> f64 {
    let x = i
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let x = (x ^ (x >> 29)).wrapping_mul(0xbf58476d1ce4e5b9);
    (x >> 11) as f64 / (1u64 << 53) as f64
}

/// Collect every hour's illuminance, hour-major.
fn run_collect(
    skies: &dyn SkySource,
    d: &DaylightMatrix,
    sun: Sun,
    params: &AnnualParams,
) -> (Annual, Vec<Vec<f64>>) {
    let mut hours: Vec<Vec<f64>> = Vec::new();
    let mut sink = |b: &HourBlock| -> Result<(), DaylightError> {
        for h in 0..b.hours {
            hours.push((0..b.points).map(|i| b.total[i * b.hours + h]).collect());
        }
        Ok(())
    };
    let a = annual(skies, d, sun, params, Some(&mut sink)).unwrap();
    (a, hours)
}

#[test]
fn a_year_of_an_unchanging_sky_gives_its_illuminance_every_hour() {
    // A uniform sky of 1000/π cd/m² gives exactly 1000 lx on an unobstructed horizontal
    // point (πL), every hour; a CIE overcast sky of zenith luminance L_z, its patches at
    // their exact means L_z (1 + (sin θ₀ + sin θ₁))/3, gives Σ_p mean_p ∫_p sin θ dω
    // (within 0.5 % of the continuous sky's 7πL_z/9: the cosine weighting varies inside a
    // patch). A point of random coefficients gets Σ D_p L_p every hour, as a plain loop
    // computes it.
    let patches = SkyPatches::tregenza();
    let n = patches.len();
    let mut uniform = vec![1000.0 / PI; n];
    uniform[patches.ground()] = 0.0;
    let lz = 3000.0;
    let mut overcast = vec![0.0; n];
    patches.sky_means(&|d| lz * (1.0 + 2.0 * d[2]) / 3.0, 4, &mut overcast);
    let flat = DaylightMatrix::unobstructed_horizontal(&patches, 1);
    let d = DaylightMatrix::from_fn(3, n, |i, p| match i {
        0 => patches.cosine_solid_angle(p),
        _ => hash((i * 1000 + p) as u64),
    });
    let discrete: f64 = (0..patches.sky_count())
        .map(|p| {
            let ([lo, hi], _) = patches.bounds(p);
            lz * (1.0 + lo.sin() + hi.sin()) / 3.0 * patches.cosine_solid_angle(p)
        })
        .sum();
    assert!((discrete / (7.0 * PI * lz / 9.0) - 1.0).abs() < 5e-3);
    for (sky, want) in [(uniform, 1000.0), (overcast, discrete)] {
        let source = Constant {
            patches: patches.clone(),
            sky: sky.clone(),
            hours: 8760,
        };
        let (a, hours) = run_collect(&source, &d, Sun::InPatch, &AnnualParams::default());
        assert_eq!(hours.len(), 8760);
        assert_eq!(a.metrics.occupied_hours, 3650);
        let random: Vec<f64> = (1..3)
            .map(|i| (0..n).map(|p| d.row(i)[p] * sky[p]).sum::<f64>())
            .collect();
        for e in &hours {
            assert!((e[0] / want - 1.0).abs() < 1e-12, "{} vs {want}", e[0]);
            assert_eq!(e[0], hours[0][0]);
            for i in 1..3 {
                assert!((e[i] / random[i - 1] - 1.0).abs() < 1e-13);
            }
        }
        let one = run_collect(&source, &flat, Sun::InPatch, &AnnualParams::default()).1;
        assert!(one.iter().all(|e| e[0] == hours[0][0]));
        if want == 1000.0 {
            assert!((hours[0][0] - 1000.0).abs() < 1e-9);
            // 1000 lx every occupied hour: daylight autonomy 1, useful (autonomous) UDI.
            let m = &a.metrics;
            assert_eq!((m.sda, m.ase), (1.0, 0.0));
            assert_eq!(m.points[0].udi, [0.0, 0.0, 1.0, 0.0]);
        }
    }
}

#[test]
fn blocks_and_threads_do_not_change_the_result() {
    let patches = SkyPatches::reinhart(2).unwrap();
    let n = patches.len();
    let points = 70; // more than two chunks of 32, not a multiple
    let d = DaylightMatrix::from_fn(points, n, |i, p| hash((i * n + p) as u64));
    // A sky that changes every hour.
    struct Varying(SkyPatches);
    impl SkySource for Varying {
        fn patches(&self) -> &SkyPatches {
            &self.0
        }
        fn hours(&self) -> usize {
            500
        }
        fn sky(&self, h: usize, _: bool, out: &mut [f64]) -> Result<HourLight, DaylightError> {
            for (p, v) in out.iter_mut().enumerate() {
                *v = 100.0 * hash((h * 7919 + p) as u64);
            }
            Ok(HourLight {
                occupied: h % 3 != 0,
                lit: h % 5 != 0,
                ..Default::default()
            })
        }
    }
    let source = Varying(patches.clone());
    let reference: Vec<Vec<f64>> = (0..500)
        .map(|h| {
            let mut sky = vec![0.0; n];
            let l = source.sky(h, false, &mut sky).unwrap();
            (0..points)
                .map(|i| {
                    if l.lit {
                        (0..n).map(|p| d.row(i)[p] * sky[p]).sum()
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let mut results = Vec::new();
    for (threads, block) in [(1, 1), (1, 168), (2, 7), (2, 500), (3, 64)] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let params = AnnualParams {
            block_hours: block,
            ..Default::default()
        };
        let (a, hours) = pool.install(|| run_collect(&source, &d, Sun::InPatch, &params));
        for (h, e) in hours.iter().enumerate() {
            for i in 0..points {
                let r = reference[h][i];
                assert!(
                    (e[i] - r).abs() <= 1e-12 * r.abs().max(1.0),
                    "hour {h} point {i}"
                );
            }
        }
        results.push((a, hours));
    }
    // Bit for bit the same whatever the threads and blocks.
    for r in &results[1..] {
        assert_eq!(r, &results[0]);
    }
}

/// A year of EPW text at a site, its irradiance given by `f(month, day, hour)`.
fn year_epw(site: (f64, f64, f64), f: impl Fn(u32, u32, u32) -> (f64, f64)) -> String {
    let mut s = format!(
        "LOCATION,Somewhere,,,test,0,{},{},{},100\nDESIGN CONDITIONS,0\nTYPICAL/EXTREME PERIODS,0\n\
         GROUND TEMPERATURES,0\nHOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\nCOMMENTS 1,\nCOMMENTS 2,\n\
         DATA PERIODS,1,1,Data,Sunday, 1/ 1,12/31\n",
        site.0, site.1, site.2
    );
    let days = [31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31];
    for month in 1..=12u32 {
        for day in 1..=days[month as usize - 1] {
            for hour in 1..=24 {
                let (dni, dhi) = f(month, day, hour);
                s.push_str(&format!(
                    "2005,{month},{day},{hour},60,x,20,8,50,100000,0,0,0,{},{dni},{dhi}\n",
                    dni + dhi
                ));
            }
        }
    }
    s
}

#[test]
fn an_unobstructed_point_gets_the_weather_files_illuminance() {
    // At an unobstructed horizontal point, every hour's illuminance is E_d + E_n sin α, the
    // Perez efficacies applied to the file's irradiance, whether the sun is put into its
    // patch or kept exact (the patches' normalisation and the sun's patch luminance are made
    // to keep the horizontal illuminance); dark hours give 0.
    let text = year_epw((40.0, -105.0, -7.0), |_, _, hour| match hour {
        6..=19 => (500.0 + 10.0 * hour as f64, 80.0 + hour as f64),
        _ => (0.0, 0.0),
    });
    let epw = parse_epw(&text, "year.epw").unwrap();
    let patches = SkyPatches::tregenza();
    let params = AnnualParams::default();
    let skies = EpwSkies::new(&epw, &patches, &params);
    let d = DaylightMatrix::unobstructed_horizontal(&patches, 2);
    let flat = |s: [f64; 3], out: &mut [f64]| out.iter_mut().for_each(|v| *v = s[2].max(0.0));
    let (in_patch, hours_a) = run_collect(&skies, &d, Sun::InPatch, &params);
    let (exact, hours_b) = run_collect(&skies, &d, Sun::Exact(&flat), &params);
    let site = Site {
        latitude: 40.0,
        longitude: -105.0,
        time_zone: -7.0,
    };
    let mut lit = 0;
    let mut sunny_occupied = 0;
    let mut diffuse = vec![0.0; epw.records.len()];
    let mut totals = vec![0.0; epw.records.len()];
    for (h, r) in epw.records.iter().enumerate() {
        let pos = solar_position(&site, 2005, r.month, r.day, r.mid_hour());
        let (dni, dhi) = (r.direct_normal.unwrap(), r.diffuse_horizontal.unwrap());
        let want = if dhi > 0.0 {
            lit += 1;
            let c = Condition::new(
                dni,
                dhi,
                pos.altitude,
                day_of_year(2005, r.month, r.day),
                8.0,
            );
            let e_n = dni * c.direct_efficacy() * pos.altitude.sin().max(0.0);
            if e_n >= 1000.0 && Occupancy::default().occupied(r.mid_hour()) {
                sunny_occupied += 1;
            }
            diffuse[h] = dhi * c.diffuse_efficacy();
            dhi * c.diffuse_efficacy() + e_n
        } else {
            0.0
        };
        totals[h] = want;
        // The daylight hours' measure: the sky's diffuse horizontal illuminance, as the hour's
        // sky is scaled to it.
        assert_eq!(
            skies.diffuse_illuminance(h).unwrap(),
            diffuse[h],
            "hour {h}"
        );
        for e in [hours_a[h][0], hours_a[h][1], hours_b[h][0]] {
            assert!(
                (e - want).abs() <= 1e-9 * want.max(1.0),
                "hour {h}: {e} vs {want}"
            );
        }
    }
    assert_eq!(in_patch.lit_hours, lit);
    assert_eq!(exact.lit_hours, lit);
    // ASE counts direct sun ≥ 1000 lx for more than 250 hours: with the exact sun its hours
    // are the ones counted here.
    assert_eq!(exact.metrics.points[0].sun_hours, sunny_occupied);
    assert_eq!(in_patch.metrics.points[0].sun_hours, sunny_occupied);
    // EN 17037 over the two (equal) points as one grid, recounted here: the 4,380 hours of
    // most diffuse light (of 5,110 lit), and in each whether the points reach E_T and E_TM.
    let mut order: Vec<usize> = (0..diffuse.len()).collect();
    order.sort_by(|&a, &b| diffuse[b].total_cmp(&diffuse[a]));
    let day = &order[..diffuse.len() / 2];
    assert!(day.iter().all(|&h| diffuse[h] > 0.0));
    let p = &exact.provision[0];
    assert_eq!(p.daylight_hours as usize, day.len());
    for (k, &(_, target, minimum)) in super::super::provision::LEVELS.iter().enumerate() {
        let share =
            |e: f64| day.iter().filter(|&&h| totals[h] >= e).count() as f64 / day.len() as f64;
        assert_eq!(p.shares[k], [share(target), share(minimum)], "level {k}");
    }
    // (Every daylight hour here is above 750 lx: the thresholds themselves are checked in
    // `provision`'s tests.)
    assert_eq!(p.level, Some(2));
}

#[test]
fn missing_irradiance_and_mismatched_inputs_are_refused() {
    let text = year_epw((40.0, -105.0, -7.0), |m, d, h| {
        if (m, d, h) == (3, 2, 12) {
            (9999.0, 100.0)
        } else {
            (0.0, 50.0)
        }
    });
    let epw = parse_epw(&text, "gap.epw").unwrap();
    let patches = SkyPatches::tregenza();
    let params = AnnualParams::default();
    let skies = EpwSkies::new(&epw, &patches, &params);
    let d = DaylightMatrix::unobstructed_horizontal(&patches, 1);
    let e = annual(&skies, &d, Sun::InPatch, &params, None)
        .unwrap_err()
        .to_string();
    // 8 header lines, then Jan (744) + Feb (672) + 1 March day (24) + 12 hours.
    let line = 8 + 744 + 672 + 24 + 12;
    assert_eq!(
        e,
        format!("gap.epw:{line}: the direct normal irradiance is missing (9999)")
    );
    let wrong = DaylightMatrix::unobstructed_horizontal(&SkyPatches::reinhart(2).unwrap(), 1);
    assert!(annual(&skies, &wrong, Sun::InPatch, &params, None).is_err());
    assert!(DaylightMatrix::new(2, 3, vec![0.0; 5]).is_err());
    assert!(DaylightMatrix::new(1, 2, vec![0.0, f64::NAN]).is_err());
    let bad = AnnualParams {
        ground_reflectance: 1.5,
        ..Default::default()
    };
    assert!(annual(&skies, &d, Sun::InPatch, &bad, None).is_err());
}

#[test]
fn csv_outputs() {
    let patches = SkyPatches::tregenza();
    let mut sky = vec![1000.0 / PI; patches.len()];
    sky[patches.ground()] = 0.0;
    let source = Constant {
        patches: patches.clone(),
        sky,
        hours: 48,
    };
    let d = DaylightMatrix::unobstructed_horizontal(&patches, 2);
    let dir = std::env::temp_dir().join(format!("radiosity-daylight-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("hourly.csv");
    let a =
        annual_with_hourly_csv(&path, &source, &d, Sun::InPatch, &AnnualParams::default()).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 49);
    assert_eq!(lines[0], "month,day,hour,p0,p1");
    assert_eq!(lines[1], "0,0,0,1000.0,1000.0");
    let mut out = Vec::new();
    write_metrics_csv(
        &mut out,
        &a.metrics,
        Some(&[[1.0, 2.0, 0.8], [1.5, 2.0, 0.8]]),
    )
    .unwrap();
    let text = String::from_utf8(out).unwrap();
    assert_eq!(
        text.lines().nth(1).unwrap(),
        "0,1,2,0.8,1.0000,0,0.0000,0.0000,1.0000,0.0000,1,0"
    );
    // A failed run leaves no file.
    let bad = dir.join("bad.csv");
    let params = AnnualParams {
        block_hours: 0,
        ..Default::default()
    };
    assert!(annual_with_hourly_csv(&bad, &source, &d, Sun::InPatch, &params).is_err());
    assert!(!bad.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The hourly CSV's number formatting equals `{:.1}` but at half-tenth ties (where the
/// product by 10 may round the other way), on a million values from 0 to 10⁶ lx and beyond
/// the integer fast path.
#[test]
fn tenths_print_as_the_formatter_does() {
    let mut diff = 0;
    for k in 0..1_000_000u64 {
        let v = match k % 4 {
            0 => hash(k) * 1e6,
            1 => hash(k) * 100.0,
            2 => (k / 4) as f64 * 0.05,
            _ => -hash(k) * 10.0,
        };
        let mut out = Vec::new();
        super::push_tenths(&mut out, v);
        let got = String::from_utf8(out).unwrap();
        let want = format!("{v:.1}");
        if got != want {
            let frac = (v.abs() * 10.0).fract();
            let tie = (frac - 0.5).abs() < 1e-6;
            let zero = want == "-0.0" && got == "0.0";
            assert!(tie || zero, "{v}: {got} against {want}");
            diff += 1;
        }
    }
    assert!(diff < 100_000, "{diff} ties");
    for v in [1e20, -3e17, f64::NAN, f64::INFINITY] {
        let mut out = Vec::new();
        super::push_tenths(&mut out, v);
        assert_eq!(String::from_utf8(out).unwrap(), format!("{v:.1}"));
    }
}

/// The `.npy` hourly matrix: NumPy's version 1.0 header (magic, length, the dict padded to a
/// multiple of 64 bytes ending in a newline) and the rows as little-endian `float32`.
#[test]
fn hourly_npy_is_numpys_format() {
    let total = [1.0, 2.5, 3.25, 4.0, 5.0, 6.0]; // 2 points × 3 hours, point-major
    let b = HourBlock {
        first: 0,
        hours: 3,
        points: 2,
        total: &total,
    };
    let mut out = Vec::new();
    super::write_hourly_npy_header(&mut out, 3, 2).unwrap();
    super::write_hourly_npy_rows(&mut out, &b).unwrap();
    assert_eq!(&out[..8], b"\x93NUMPY\x01\x00");
    let len = u16::from_le_bytes([out[8], out[9]]) as usize;
    assert_eq!((10 + len) % 64, 0);
    let dict = std::str::from_utf8(&out[10..10 + len]).unwrap();
    assert!(dict.starts_with("{'descr': '<f4', 'fortran_order': False, 'shape': (3, 2), }"));
    assert!(dict.ends_with('\n'));
    let data: Vec<f32> = out[10 + len..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    // Hour-major rows: hour 0 is (point 0, point 1) = (1.0, 4.0).
    assert_eq!(data, [1.0, 4.0, 2.5, 5.0, 3.25, 6.0]);
}

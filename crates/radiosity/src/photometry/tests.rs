//! Tests of the photometric readers: closed forms on distributions written here as IES and
//! EULUMDAT text, the same distribution in every symmetry form of both formats, hostile input,
//! and the real files of `../shared/photometry`.

use super::*;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::PathBuf;

// ---------------------------------------------------------------------------------------------
// Writers of test files.

/// An IES file's fields, written out by [`Ies::text`].
#[derive(Clone)]
struct Ies {
    header: &'static str,
    labels: &'static str,
    tilt: String,
    lamps: f64,
    lumens: f64,
    multiplier: f64,
    kind: u8,
    units: u8,
    dims: [f64; 3],
    ballast: f64,
    future: f64,
    vertical: Vec<f64>,
    horizontal: Vec<f64>,
    /// Horizontal-major: all vertical angles of the first horizontal angle, then …
    candela: Vec<f64>,
}

impl Ies {
    /// A type C file of `f(C, γ)` on the given angles, 1 lamp of 1,000 lm, metres.
    fn of(horizontal: &[f64], vertical: &[f64], f: impl Fn(f64, f64) -> f64) -> Ies {
        let candela = horizontal
            .iter()
            .flat_map(|&h| vertical.iter().map(move |&v| (h, v)))
            .map(|(h, v)| f(h, v))
            .collect();
        Ies {
            header: "IESNA:LM-63-2002",
            labels: "[TEST] unit test\n[MANUFAC] radiosity\n",
            tilt: "TILT=NONE\n".into(),
            lamps: 1.0,
            lumens: 1000.0,
            multiplier: 1.0,
            kind: 1,
            units: 2,
            dims: [0.0, 0.0, 0.0],
            ballast: 1.0,
            future: 1.0,
            vertical: vertical.to_vec(),
            horizontal: horizontal.to_vec(),
            candela,
        }
    }

    fn text(&self) -> String {
        let mut s = String::new();
        if !self.header.is_empty() {
            writeln!(s, "{}", self.header).unwrap();
        }
        s.push_str(self.labels);
        s.push_str(&self.tilt);
        let [w, l, h] = self.dims;
        writeln!(
            s,
            "{} {} {} {} {} {} {} {w} {l} {h}",
            self.lamps,
            self.lumens,
            self.multiplier,
            self.vertical.len(),
            self.horizontal.len(),
            self.kind,
            self.units
        )
        .unwrap();
        writeln!(s, "{} {} 40", self.ballast, self.future).unwrap();
        wrapped(&mut s, &self.vertical, 8);
        wrapped(&mut s, &self.horizontal, 8);
        for plane in self.candela.chunks(self.vertical.len()) {
            wrapped(&mut s, plane, 7);
        }
        s
    }
}

/// `values` on lines of `per_line`, the shortest text that reads back exactly.
fn wrapped(s: &mut String, values: &[f64], per_line: usize) {
    for line in values.chunks(per_line) {
        let words: Vec<String> = line.iter().map(|v| format!("{v}")).collect();
        writeln!(s, "{}", words.join(" ")).unwrap();
    }
}

/// An EULUMDAT file of `f(C, γ)` candela on `mc` C-planes evenly spaced and the γ angles
/// `gamma`, storing the planes Isym `isym` stores, for one lamp set of `flux` lm (`lamps`
/// lamps; negative for absolute photometry) and a light output ratio of `lorl` %.
fn ldt_text(
    isym: u8,
    mc: usize,
    gamma: &[f64],
    f: impl Fn(f64, f64) -> f64,
    flux: f64,
    lamps: i32,
    lorl: f64,
) -> String {
    let dc = 360.0 / mc as f64;
    let c: Vec<f64> = (0..mc).map(|k| k as f64 * dc).collect();
    let stored: Vec<f64> = match isym {
        0 => c.clone(),
        1 => vec![0.0],
        2 => c[..=mc / 2].to_vec(),
        3 => c[mc / 4..=mc / 4 + mc / 2].to_vec(),
        4 => c[..=mc / 4].to_vec(),
        _ => unreachable!(),
    };
    let mut s = String::new();
    let header = [
        "Radiosity test data".to_string(),
        (if isym == 1 { "1" } else { "3" }).to_string(),
        isym.to_string(),
        mc.to_string(),
        format!("{dc}"),
        gamma.len().to_string(),
        format!("{}", gamma[1] - gamma[0]),
        "RPT-1".into(),
        "Test luminaire".into(),
        "T-1".into(),
        "test.ldt".into(),
        "2024-01-01 tester".into(),
        "600".into(),
        "600".into(),
        "80".into(),
        "500".into(),
        "300".into(),
        "10".into(),
        "10".into(),
        "20".into(),
        "20".into(),
        "100".into(),
        format!("{lorl}"),
        "1.0".into(),
        "0".into(),
        "1".into(),
        lamps.to_string(),
        "LED 4000 K".into(),
        format!("{flux}"),
        "4000".into(),
        "80".into(),
        "40".into(),
    ];
    for line in header {
        write!(s, "{line}\r\n").unwrap();
    }
    for _ in 0..10 {
        s.push_str("0.5\r\n");
    }
    for v in c.iter().chain(gamma) {
        write!(s, "{v}\r\n").unwrap();
    }
    for &cc in &stored {
        for &g in gamma {
            write!(s, "{}\r\n", f(cc, g) * 1000.0 / flux).unwrap();
        }
    }
    s
}

/// `n + 1` angles from `a` to `b`.
fn steps(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|k| a + (b - a) * k as f64 / n as f64).collect()
}

fn ies(text: &str) -> Photometry {
    parse_ies(text, "t.ies").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn ldt(text: &str) -> Photometry {
    parse_ldt(text, "t.ldt").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300)
}

/// The message of an error at a line of `name`, checked to be one line of the form
/// `name:line: problem`.
fn located(result: Result<Photometry, PhotometryError>, name: &str) -> String {
    let e = match result {
        Ok(_) => panic!("{name}: expected an error"),
        Err(e) => e,
    };
    let msg = e.to_string();
    assert!(
        !msg.contains('\n') && !msg.contains('\r'),
        "two lines: {msg:?}"
    );
    let rest = msg
        .strip_prefix(&format!("{name}:"))
        .unwrap_or_else(|| panic!("does not start with the file name: {msg}"));
    let (line, problem) = rest
        .split_once(": ")
        .unwrap_or_else(|| panic!("no line: {msg}"));
    let line: usize = line
        .parse()
        .unwrap_or_else(|_| panic!("no line number: {msg}"));
    assert!(line >= 1 && !problem.is_empty(), "{msg}");
    assert_eq!(e.line(), Some(line));
    msg
}

/// The error `text` gives, read as `name` (by its extension); checked as by [`located`].
fn error_of(text: &str, name: &str) -> String {
    located(parse_bytes(text.as_bytes(), name), name)
}

// ---------------------------------------------------------------------------------------------
// Distributions with each symmetry, and the grid they are compared on.

/// No symmetry.
fn asymmetric(c: f64, g: f64) -> f64 {
    let (c, g) = (c.to_radians(), g.to_radians());
    (500.0 + 200.0 * c.cos() + 120.0 * c.sin() + 60.0 * (2.0 * c).cos() + 30.0 * (3.0 * c).sin())
        * (1.2 + g.cos())
}

/// Symmetric about the C0–C180 plane: I(C) = I(−C).
fn about_c0(c: f64, g: f64) -> f64 {
    let (c, g) = (c.to_radians(), g.to_radians());
    (500.0 + 200.0 * c.cos() + 60.0 * (2.0 * c).cos()) * (1.2 + g.cos())
}

/// Symmetric about the C90–C270 plane: I(C) = I(180° − C).
fn about_c90(c: f64, g: f64) -> f64 {
    let (c, g) = (c.to_radians(), g.to_radians());
    (500.0 + 200.0 * c.sin() + 60.0 * (2.0 * c).cos()) * (1.2 + g.cos())
}

/// Symmetric about both planes.
fn quadrant(c: f64, g: f64) -> f64 {
    let (c, g) = (c.to_radians(), g.to_radians());
    (500.0 + 150.0 * (2.0 * c).cos() + 40.0 * (4.0 * c).cos()) * (1.2 + g.cos())
}

/// Rotationally symmetric.
fn rotational(_c: f64, g: f64) -> f64 {
    700.0 * (1.2 + g.to_radians().cos()) + 50.0 * (3.0 * g.to_radians()).sin().abs()
}

/// Query angles: off the 15° × 10° table and on it, C past both ends of the circle.
fn grid() -> impl Iterator<Item = (f64, f64)> {
    let cs = (-8..=80).map(|k| k as f64 * 5.0 - 1.25);
    cs.flat_map(|c| (0..=72).map(move |k| (c, k as f64 * 2.5)))
}

fn same_distribution(a: &Photometry, b: &Photometry, what: &str) {
    for (c, g) in grid() {
        let (x, y) = (a.intensity(c, g), b.intensity(c, g));
        assert!(close(x, y, 1e-12), "{what}: I({c}, {g}) {x} vs {y}");
    }
    assert!(
        close(a.flux(), b.flux(), 1e-12),
        "{what}: flux {} vs {}",
        a.flux(),
        b.flux()
    );
}

// ---------------------------------------------------------------------------------------------
// Closed forms.

#[test]
fn an_isotropic_source_sends_four_pi_i0() {
    let i0 = 1234.5;
    let p = ies(&Ies::of(&[0.0], &steps(0.0, 180.0, 36), |_, _| i0).text());
    assert!(close(p.flux(), 4.0 * PI * i0, 1e-12), "{}", p.flux());
    // The rule is exact for a constant on any grid, uneven steps included.
    let uneven = [0.0, 1.0, 7.5, 30.0, 31.0, 90.0, 100.0, 170.0, 180.0];
    let p = ies(&Ies::of(&[0.0, 10.0, 45.0, 90.0], &uneven, |_, _| i0).text());
    assert!(close(p.flux(), 4.0 * PI * i0, 1e-12), "{}", p.flux());
    let p = ldt(&ldt_text(
        1,
        24,
        &steps(0.0, 180.0, 18),
        |_, _| i0,
        3000.0,
        1,
        100.0,
    ));
    assert!(close(p.flux(), 4.0 * PI * i0, 1e-12), "{}", p.flux());
}

#[test]
fn a_lambertian_downlight_sends_pi_i0() {
    // I = I0 cos γ below the horizon, nothing above: flux π I0. The flux rule is the
    // trapezoid rule in cos γ, exact for a cosine law whatever the step (here 5° and an
    // uneven grid); a rule linear in γ would be off by about Δγ²/12 ≈ 0.06 % at 5°.
    let i0 = 2000.0;
    let lambert = |_: f64, g: f64| i0 * g.to_radians().cos().max(0.0);
    let p = ies(&Ies::of(&[0.0], &steps(0.0, 90.0, 18), lambert).text());
    assert!(close(p.flux(), PI * i0, 1e-12), "{}", p.flux());
    let p = ies(&Ies::of(&[0.0, 90.0], &[0.0, 3.0, 20.0, 65.0, 90.0, 180.0], lambert).text());
    assert!(close(p.flux(), PI * i0, 1e-12), "{}", p.flux());
    let p = ldt(&ldt_text(
        1,
        36,
        &steps(0.0, 90.0, 18),
        lambert,
        2000.0 * PI,
        1,
        100.0,
    ));
    assert!(close(p.flux(), PI * i0, 1e-12), "{}", p.flux());
    assert!(p.warnings.is_empty(), "{:?}", p.warnings);
    // Above the table (0..90) the intensity is 0.
    assert_eq!(p.intensity(0.0, 90.5), 0.0);
    assert!(close(p.intensity(33.0, 60.0), i0 / 2.0, 1e-12));
}

#[test]
fn flux_is_close_to_integrating_the_interpolated_intensity() {
    // flux() is exact for the cos γ-linear interpolant; intensity() is γ-linear: the two
    // integrals differ by O(Δγ²), well under 0.1 % at 10° steps for this smooth distribution.
    let p = ies(&Ies::of(&steps(0.0, 360.0, 24), &steps(0.0, 180.0, 18), asymmetric).text());
    let brute = brute_flux(&p, 720, 720);
    assert!(close(p.flux(), brute, 1e-3), "{} vs {brute}", p.flux());
}

/// The integral of `intensity()` over the sphere by the midpoint rule on `nc` × `ng` cells.
fn brute_flux(p: &Photometry, nc: usize, ng: usize) -> f64 {
    let (dc, dg) = (360.0 / nc as f64, 180.0 / ng as f64);
    let mut total = 0.0;
    for j in 0..ng {
        let (g0, g1) = (j as f64 * dg, (j + 1) as f64 * dg);
        let omega = (g0.to_radians().cos() - g1.to_radians().cos()) * dc.to_radians();
        let g = 0.5 * (g0 + g1);
        for i in 0..nc {
            total += p.intensity((i as f64 + 0.5) * dc, g) * omega;
        }
    }
    total
}

#[test]
fn at_tabulated_angles_the_intensity_is_the_table() {
    let h = steps(0.0, 360.0, 24);
    let v = steps(0.0, 180.0, 18);
    let mut seed = 7u64;
    let table: Vec<f64> = (0..h.len() * v.len())
        .map(|_| (lcg(&mut seed) % 100_000) as f64 / 10.0)
        .collect();
    let mut file = Ies::of(&h, &v, |_, _| 0.0);
    file.candela = table.clone();
    // C = 360 repeats C = 0 in this table.
    for j in 0..v.len() {
        file.candela[(h.len() - 1) * v.len() + j] = file.candela[j];
    }
    let p = ies(&file.text());
    assert_eq!(p.c_angles, h);
    for (i, &c) in h.iter().enumerate() {
        for (j, &g) in v.iter().enumerate() {
            assert_eq!(
                p.intensity(c, g),
                file.candela[i * v.len() + j],
                "C {c} γ {g}"
            );
            assert_eq!(p.plane(i)[j], file.candela[i * v.len() + j]);
        }
    }
}

#[test]
fn interpolation_stays_between_the_neighbours() {
    let h = steps(0.0, 360.0, 12);
    let v = [0.0, 5.0, 30.0, 32.0, 90.0, 135.0, 180.0];
    let mut seed = 11u64;
    let mut file = Ies::of(&h, &v, |_, _| 0.0);
    for x in &mut file.candela {
        // Spiky on purpose: zeros next to large values.
        *x = if lcg(&mut seed) % 3 == 0 {
            0.0
        } else {
            (lcg(&mut seed) % 1_000_000) as f64
        };
    }
    let p = ies(&file.text());
    for _ in 0..20_000 {
        let c = (lcg(&mut seed) % 3_600_000) as f64 / 10_000.0;
        let g = (lcg(&mut seed) % 1_800_000) as f64 / 10_000.0;
        let i = p
            .c_angles
            .partition_point(|&a| a <= c)
            .clamp(1, p.c_angles.len() - 1)
            - 1;
        let j = v.partition_point(|&a| a <= g).clamp(1, v.len() - 1) - 1;
        let corners = [
            p.plane(i)[j],
            p.plane(i)[j + 1],
            p.plane(i + 1)[j],
            p.plane(i + 1)[j + 1],
        ];
        let lo = corners.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = corners.iter().copied().fold(0.0, f64::max);
        let x = p.intensity(c, g);
        assert!(lo <= x && x <= hi, "I({c}, {g}) = {x} outside {lo}..{hi}");
    }
}

/// A small linear congruential generator (Knuth's MMIX constants), high bits.
fn lcg(state: &mut u64) -> u64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    *state >> 33
}

// ---------------------------------------------------------------------------------------------
// One distribution, every symmetry form of both formats.

#[test]
fn every_symmetry_form_reads_as_the_full_table() {
    let gamma = steps(0.0, 180.0, 18);
    let full = steps(0.0, 360.0, 24);
    type Form = (&'static str, fn(f64, f64) -> f64, Vec<f64>, u8);
    let forms: [Form; 5] = [
        ("rotational", rotational, vec![0.0], 1),
        ("bilateral 0-180", about_c0, steps(0.0, 180.0, 12), 2),
        ("bilateral 90-270", about_c90, steps(90.0, 270.0, 12), 3),
        ("quadrant", quadrant, steps(0.0, 90.0, 6), 4),
        ("none", asymmetric, full.clone(), 0),
    ];
    for (what, f, horizontal, isym) in forms {
        let reference = ies(&Ies::of(&full, &gamma, f).text());
        let from_ies = ies(&Ies::of(&horizontal, &gamma, f).text());
        let from_ldt = ldt(&ldt_text(isym, 24, &gamma, f, 2000.0, 1, 100.0));
        if isym != 1 {
            assert_eq!(from_ies.c_angles, full, "{what}: IES planes");
        }
        same_distribution(&reference, &from_ies, &format!("{what}: IES"));
        same_distribution(
            &reference,
            &from_ldt,
            &format!("{what}: EULUMDAT Isym {isym}"),
        );
        // The tabulated values are the function's: the expansion put each plane where it
        // belongs, not merely somewhere consistent.
        for (i, &c) in from_ldt.c_angles.iter().enumerate() {
            for (j, &g) in gamma.iter().enumerate() {
                let want = f(c, g);
                assert!(
                    close(from_ldt.plane(i)[j], want, 1e-12),
                    "{what}: C {c} γ {g}"
                );
            }
        }
        assert!(close(from_ies.flux(), from_ldt.flux(), 1e-12));
    }
}

#[test]
fn an_open_circle_of_planes_is_closed_across_c0() {
    // Planes 30, 150, 270: the gap 270..390 (= 30) is closed by planes at 0 and 360
    // interpolated the way intensity() would, a quarter of the way from 30 back to 270.
    let (c, rows) = expand(Symmetry::None, &[30.0, 150.0, 270.0], &[1.0, 2.0, 3.0], 1);
    assert_eq!(c, [0.0, 30.0, 150.0, 270.0, 360.0]);
    assert_eq!(rows, [1.5, 1.0, 2.0, 3.0, 1.5]);
    // Planes from 0 to 330: the plane at 0 closes the circle at 360.
    let gamma = steps(0.0, 90.0, 9);
    let file = Ies::of(&steps(0.0, 330.0, 11), &gamma, |c, _| 100.0 + c);
    let p = ies(&file.text());
    assert_eq!(p.c_angles.first(), Some(&0.0));
    assert_eq!(p.c_angles.last(), Some(&360.0));
    // Between 330 (430 cd) and 360 ≡ 0 (100 cd).
    assert!(close(p.intensity(345.0, 10.0), 265.0, 1e-12));
    let mut shifted = Ies::of(&[0.0], &gamma, |_, _| 0.0);
    shifted.horizontal = steps(30.0, 330.0, 10);
    shifted.candela = shifted
        .horizontal
        .iter()
        .flat_map(|&c| gamma.iter().map(move |_| c))
        .collect();
    // 30..330 is not a horizontal range LM-63 allows.
    let msg = error_of(&shifted.text(), "s.ies");
    assert!(msg.contains("horizontal angles run 30..330"), "{msg}");
}

// ---------------------------------------------------------------------------------------------
// Multipliers, lumens, openings, header forms.

#[test]
fn absolute_photometry_multiplier_and_ballast_factor_apply() {
    let gamma = steps(0.0, 90.0, 9);
    let mut file = Ies::of(&[0.0], &gamma, |_, g| 1000.0 * g.to_radians().cos());
    file.lumens = -1.0;
    file.multiplier = 0.4597;
    file.ballast = 0.9;
    let p = ies(&file.text());
    assert_eq!(p.lumens, None);
    assert_eq!(p.rated_flux, None);
    assert_eq!(p.flux_mismatch(), None);
    assert!(close(p.intensity(0.0, 0.0), 1000.0 * 0.4597 * 0.9, 1e-12));
    assert!(close(p.flux(), PI * 1000.0 * 0.4597 * 0.9, 1e-12));
    assert!(p.warnings.is_empty(), "{:?}", p.warnings);

    // Relative: 2 lamps of 1,570.796 lm ≈ π·1000 lm, the flux of the table as written; the
    // ballast factor scales both the intensities and the stated flux.
    file.lumens = 1570.796;
    file.lamps = 2.0;
    file.multiplier = 1.0;
    file.ballast = 0.5;
    let p = ies(&file.text());
    assert_eq!(p.lumens, Some(2.0 * 1570.796));
    assert!(close(p.intensity(0.0, 0.0), 500.0, 1e-12));
    assert!(close(p.rated_flux.unwrap(), 1570.796, 1e-12));
    assert!(p.flux_mismatch().unwrap() < 1e-6);
    assert!(p.warnings.is_empty(), "{:?}", p.warnings);
    // The multiplier scales the intensities (a unit change), not the stated flux.
    file.multiplier = 2.0;
    let p = ies(&file.text());
    assert!(close(p.intensity(0.0, 0.0), 1000.0, 1e-12));
    assert!(close(p.flux_mismatch().unwrap(), 1.0, 1e-6));

    // EULUMDAT absolute photometry: a negative number of lamps, the luminaire's flux.
    let text = ldt_text(
        1,
        1,
        &gamma,
        |_, g| 900.0 * g.to_radians().cos(),
        900.0 * PI,
        -1,
        100.0,
    );
    let p = ldt(&text);
    assert!(close(p.intensity(0.0, 0.0), 900.0, 1e-12));
    assert!(close(p.lumens.unwrap(), 900.0 * PI, 1e-12));
    assert!(p.flux_mismatch().unwrap() < 1e-9, "{:?}", p.flux_mismatch());
    // The light output ratio is part of the stated luminaire flux.
    let text = ldt_text(
        1,
        1,
        &gamma,
        |_, g| 900.0 * g.to_radians().cos(),
        900.0 * PI / 0.8,
        1,
        80.0,
    );
    let p = ldt(&text);
    assert!(close(p.rated_flux.unwrap(), 900.0 * PI, 1e-12));
    assert!(p.flux_mismatch().unwrap() < 1e-9);
}

#[test]
fn the_ballast_lamp_factor_applies_only_to_the_1986_and_1991_formats() {
    let gamma = steps(0.0, 90.0, 9);
    let mut file = Ies::of(&[0.0], &gamma, |_, _| 100.0);
    file.future = 0.5;
    for (header, labels, want) in [
        ("IESNA91", "[TEST] t\n", 50.0),
        ("", "an old label line\nanother\n", 50.0),
        ("IESNA:LM-63-1995", "[TEST] t\n", 100.0),
        ("IESNA:LM-63-2002", "[TEST] t\n", 100.0),
        ("IES:LM-63-2019", "[TEST] t\n[TESTLAB] l\n", 100.0),
        ("IESNA95", "", 100.0),
    ] {
        file.header = header;
        file.labels = labels;
        let p = ies(&file.text());
        assert!(close(p.intensity(10.0, 10.0), want, 1e-12), "{header:?}");
    }
    // A 1986 file may start at its TILT line.
    file.header = "";
    file.labels = "";
    assert!(close(ies(&file.text()).intensity(0.0, 0.0), 50.0, 1e-12));
}

#[test]
fn openings_in_feet_metres_millimetres_and_round() {
    let gamma = steps(0.0, 90.0, 9);
    let mut file = Ies::of(&[0.0], &gamma, |_, _| 1.0);
    file.units = 1;
    file.dims = [2.0, 4.0, 0.5];
    let o = ies(&file.text()).opening;
    assert!(close(o.width_m, 0.6096, 1e-12) && close(o.length_m, 1.2192, 1e-12));
    assert!(close(o.height_m, 0.1524, 1e-12) && !o.round);
    file.units = 2;
    file.dims = [-0.3, -0.3, 0.0];
    let o = ies(&file.text()).opening;
    assert!(o.round && close(o.width_m, 0.3, 1e-12) && close(o.length_m, 0.3, 1e-12));
    assert_eq!(o.height_m, 0.0);
    // EULUMDAT: luminous area 500 × 300 mm, heights 10, 10, 20, 20 mm.
    let o = ldt(&ldt_text(1, 1, &gamma, |_, _| 1.0, 1000.0, 1, 100.0)).opening;
    assert!(!o.round && close(o.length_m, 0.5, 1e-12) && close(o.width_m, 0.3, 1e-12));
    assert!(close(o.height_m, 0.015, 1e-12));
    // A luminous width of 0 is a round area of the given diameter.
    let text = ldt_text(1, 1, &gamma, |_, _| 1.0, 1000.0, 1, 100.0).replacen(
        "\r\n300\r\n",
        "\r\n0\r\n",
        1,
    );
    let o = ldt(&text).opening;
    assert!(o.round && close(o.width_m, 0.5, 1e-12) && close(o.length_m, 0.5, 1e-12));
}

#[test]
fn an_included_tilt_table_is_read_and_kept_for_the_installed_luminaire() {
    let f = |c: f64, g: f64| about_c0(c, g);
    let plain = Ies::of(&steps(0.0, 180.0, 6), &steps(0.0, 180.0, 18), f);
    let mut tilted = plain.clone();
    tilted.tilt = "TILT=INCLUDE\n1\n7\n0 15 30 45\n60 75 90\n1.0 .95 .94 .90\n.88 .87 .94\n".into();
    let (a, b) = (ies(&plain.text()), ies(&tilted.text()));
    // The table is the luminaire as measured; the factor belongs to the installed one.
    same_distribution(&a, &b, "tilt");
    assert!(
        !b.warnings.iter().any(|w| w.contains("tilt")),
        "{:?}",
        b.warnings
    );
    assert_eq!(a.tilt, None);
    let t = b.tilt.as_ref().unwrap();
    assert_eq!(t.geometry, LampGeometry::Vertical);
    assert_eq!(t.angles, steps(0.0, 90.0, 6));
    assert_eq!(t.factors, vec![1.0, 0.95, 0.94, 0.90, 0.88, 0.87, 0.94]);
    // Linear between the angles, the end values outside (and said so).
    assert_eq!(t.factor(15.0), (0.95, true));
    assert!((t.factor(37.5).0 - 0.92).abs() < 1e-15);
    assert_eq!(t.factor(120.0), (0.94, false));
    assert_eq!(t.factor(-1.0), (1.0, false));
    for (geometry, g) in [
        (1, LampGeometry::Vertical),
        (2, LampGeometry::AlongC0),
        (3, LampGeometry::AcrossC0),
    ] {
        let mut other = tilted.clone();
        let text = format!("TILT=INCLUDE\n{geometry}\n2\n0 90\n1 0.5\n");
        other.tilt = text;
        assert_eq!(ies(&other.text()).tilt.unwrap().geometry, g);
    }
    // Broken tilt tables are refused at their line.
    tilted.tilt = "TILT=INCLUDE\n1\n7\n0 15 30 45\n60 50 90\n1.0 .95 .94 .90\n.88 .87 .94\n".into();
    let msg = error_of(&tilted.text(), "tilt.ies");
    assert!(msg.starts_with("tilt.ies:8: tilt angle 50"), "{msg}");
    tilted.tilt = "TILT=INCLUDE\n4\n".into();
    let msg = error_of(&tilted.text(), "tilt.ies");
    assert!(msg.contains("geometry 4"), "{msg}");
}

#[test]
fn crlf_latin1_commas_and_decimal_commas_are_read() {
    let file = Ies::of(&steps(0.0, 90.0, 3), &steps(0.0, 90.0, 9), quadrant);
    let reference = ies(&file.text());
    let mut bytes: Vec<u8> = Vec::new();
    for line in file.text().lines() {
        let line = if line.starts_with("[MANUFAC]") {
            // "Lumière 120°" in Latin-1.
            b"[MANUFAC] Lumi\xe8re 120\xb0".to_vec()
        } else {
            line.replace(' ', ",").into_bytes()
        };
        bytes.extend_from_slice(&line);
        bytes.extend_from_slice(b"\r\n");
    }
    assert!(std::str::from_utf8(&bytes).is_err());
    let p = parse_bytes(&bytes, "Lamp.IES").unwrap();
    assert_eq!(p.source, "Lamp.IES");
    same_distribution(&reference, &p, "CRLF, Latin-1, commas");
    // Old Macintosh line ends.
    let cr = file.text().replace('\n', "\r");
    same_distribution(&reference, &ies(&cr), "CR");

    let gamma = steps(0.0, 90.0, 9);
    let text = ldt_text(4, 24, &gamma, quadrant, 2000.0, 1, 99.5);
    let comma = text.replace("\r\n99.5\r\n", "\r\n99,5\r\n");
    assert_ne!(text, comma);
    let (a, b) = (ldt(&text), ldt(&comma));
    same_distribution(&a, &b, "decimal comma");
    assert_eq!(a.rated_flux, b.rated_flux);
}

#[test]
fn a_flux_far_from_the_stated_one_is_noted() {
    let gamma = steps(0.0, 180.0, 18);
    // 100 cd everywhere: 400π ≈ 1,256.6 lm.
    let mut file = Ies::of(&[0.0], &gamma, |_, _| 100.0);
    file.lumens = 1256.0;
    let p = ies(&file.text());
    assert!(p.flux_mismatch().unwrap() < 0.001 && p.warnings.is_empty());
    file.lumens = 2000.0;
    let p = ies(&file.text());
    assert!(close(
        p.flux_mismatch().unwrap(),
        1.0 - 400.0 * PI / 2000.0,
        1e-12
    ));
    assert!(
        p.warnings
            .iter()
            .any(|w| w.contains("1257 lm") && w.contains("2000 lm")),
        "{:?}",
        p.warnings
    );
}

#[test]
fn directions_map_to_c_and_gamma() {
    let approx = |d: [f64; 3], c: f64, g: f64| {
        let (a, b) = Photometry::angles(d).unwrap();
        assert!(
            (a - c).abs() < 1e-9 && (b - g).abs() < 1e-9,
            "{d:?}: ({a}, {b})"
        );
    };
    approx([0.0, 0.0, -1.0], 0.0, 0.0);
    approx([1.0, 0.0, 0.0], 0.0, 90.0);
    approx([0.0, 2.0, 0.0], 90.0, 90.0);
    approx([-1.0, 0.0, 0.0], 180.0, 90.0);
    approx([0.0, -1.0, 0.0], 270.0, 90.0);
    approx([0.0, 0.0, 5.0], 0.0, 180.0);
    approx([1.0, 1.0, -2f64.sqrt()], 45.0, 45.0);
    assert_eq!(Photometry::angles([0.0; 3]), None);
    assert_eq!(Photometry::angles([f64::NAN, 0.0, 1.0]), None);

    let p = ies(&Ies::of(&steps(0.0, 360.0, 24), &steps(0.0, 180.0, 18), asymmetric).text());
    assert_eq!(p.intensity_dir([0.0; 3]), 0.0);
    assert_eq!(p.intensity(f64::NAN, 3.0), 0.0);
    for (c, g) in grid() {
        let d = Photometry::direction(c, g);
        let (x, y) = (p.intensity_dir(d), p.intensity(c, g));
        assert!(
            close(x, y, 1e-9) || g == 0.0 || g == 180.0,
            "({c}, {g}): {x} vs {y}"
        );
        let scaled = d.map(|v| 3.5 * v);
        assert!(close(p.intensity_dir(scaled), x, 1e-12));
    }
}

// ---------------------------------------------------------------------------------------------
// Hostile input.

#[test]
fn empty_and_blank_files_are_refused_at_line_1() {
    for name in ["e.ies", "e.ldt"] {
        for text in ["", "   ", "\r\n\n  \t\n"] {
            let msg = error_of(text, name);
            assert!(msg.ends_with(":1: empty file"), "{msg}");
        }
    }
}

#[test]
fn wrong_counts_are_named() {
    let v = steps(0.0, 180.0, 36);
    let file = Ies::of(&steps(0.0, 90.0, 4), &v, quadrant);
    // One vertical angle fewer than declared (the data as for 36).
    let short = Ies::of(&steps(0.0, 90.0, 4), &v[..36], quadrant);
    let text = short.text().replacen(" 36 5 1 2 ", " 37 5 1 2 ", 1);
    let msg = error_of(&text, "lamp.ies");
    assert!(
        msg.contains("expected 37 vertical angles, found 36"),
        "{msg}"
    );
    // The line where the angles stop increasing (the horizontal angles' line, 12).
    assert!(msg.starts_with("lamp.ies:12:"), "{msg}");
    // One horizontal angle fewer than declared.
    let text = file.text().replacen(" 37 5 1 2 ", " 37 6 1 2 ", 1);
    let msg = error_of(&text, "lamp.ies");
    assert!(
        msg.contains("expected 6 horizontal angles, found 5"),
        "{msg}"
    );
    // Candela values missing at the end.
    let text = file.text();
    let cut = text.trim_end().rsplit_once(' ').unwrap().0;
    let msg = error_of(cut, "lamp.ies");
    assert!(msg.contains("expected 185 candela values"), "{msg}");
    assert!(msg.contains("found 184"), "{msg}");
    // More numbers than declared.
    let msg = error_of(&format!("{text}1 2 3\n"), "lamp.ies");
    assert!(
        msg.contains("3 more number(s) after the candela table"),
        "{msg}"
    );
    // Words that are not numbers after the table: ignored, noted.
    let p = ies(&format!("{text}\u{1a}\n"));
    assert!(p.warnings.iter().any(|w| w.contains("ignored")));
    // Counts that are not whole numbers.
    let msg = error_of(&text.replacen(" 37 5 1 2 ", " 37.5 5 1 2 ", 1), "lamp.ies");
    assert!(msg.contains("'37.5' is not a whole number"), "{msg}");

    // EULUMDAT: Mc and Ng against the data.
    let gamma = steps(0.0, 180.0, 18);
    let text = ldt_text(0, 12, &gamma, asymmetric, 1000.0, 1, 100.0);
    let more = text.replacen("\r\n12\r\n", "\r\n13\r\n", 1);
    let msg = error_of(&more, "x.ldt");
    assert!(msg.contains("expected 247 intensities"), "{msg}");
    let fewer = text.replacen("\r\n12\r\n", "\r\n11\r\n", 1);
    let msg = error_of(&fewer, "x.ldt");
    assert!(msg.contains("γ angle 330 is outside 0..180"), "{msg}");
    let msg = error_of(&format!("{text}7\r\n"), "x.ldt");
    assert!(
        msg.contains("1 more number(s) after the intensities"),
        "{msg}"
    );
}

#[test]
fn non_numbers_nan_and_negative_values_are_refused_at_their_line() {
    let file = Ies::of(&[0.0, 90.0], &steps(0.0, 90.0, 6), quadrant);
    let text = file.text();
    let lines: Vec<&str> = text.lines().collect();
    // The first candela line is line 9 (header, two keywords, TILT, two count lines, two
    // angle lines).
    assert!(lines[8].starts_with(&format!("{}", quadrant(0.0, 0.0))));
    for (bad, what) in [
        ("abc", "candela value 'abc' is not a number"),
        ("NaN", "candela value 'NaN' is not a finite number"),
        ("inf", "is not a finite number"),
        ("-5", "candela value -5 is negative"),
        ("1e999", "is not a finite number"),
    ] {
        let changed = text.replacen(lines[8].split(' ').next().unwrap(), bad, 1);
        let msg = error_of(&changed, "lamp.ies");
        assert!(
            msg.starts_with("lamp.ies:9: ") && msg.contains(what),
            "{msg}"
        );
    }
    let msg = error_of(&text.replacen("1000", "lots", 1), "lamp.ies");
    assert!(
        msg.starts_with("lamp.ies:5: the lumens per lamp 'lots' is not a number"),
        "{msg}"
    );

    let gamma = steps(0.0, 90.0, 6);
    let text = ldt_text(1, 1, &gamma, |_, _| 250.0, 1000.0, 1, 100.0);
    let lines: Vec<&str> = text.lines().collect();
    let first_intensity = lines.len() - gamma.len() + 1;
    for (bad, what) in [
        ("abc", "intensity 'abc' is not a number"),
        ("NaN", "is not a finite number"),
        ("-1", "intensity -1 is negative"),
    ] {
        let mut changed: Vec<&str> = lines.clone();
        changed[first_intensity - 1] = bad;
        let msg = error_of(&changed.join("\r\n"), "x.ldt");
        assert!(
            msg.starts_with(&format!("x.ldt:{first_intensity}: ")) && msg.contains(what),
            "{msg}"
        );
    }
    let msg = error_of(&text.replacen("\r\n1000\r\n", "\r\n-1000\r\n", 1), "x.ldt");
    assert!(
        msg.starts_with("x.ldt:29: lamp flux -1000 lm is not positive"),
        "{msg}"
    );
    let msg = error_of(
        &text.replacen("\r\n1\r\n1\r\n1\r\n", "\r\n1\r\n7\r\n1\r\n", 1),
        "x.ldt",
    );
    assert!(
        msg.starts_with("x.ldt:3: symmetry indicator Isym 7"),
        "{msg}"
    );
}

#[test]
fn huge_counts_are_refused_before_allocating() {
    let file = Ies::of(&[0.0], &steps(0.0, 90.0, 6), |_, _| 1.0);
    let text = file.text();
    for (counts, what) in [
        (" 100000000 1 1 2 ", "more than 10000000"),
        (" 100000 100000 1 2 ", "more than 10000000 candela values"),
        (" 18446744073709551616 1 1 2 ", "more than 10000000"),
        (
            " 9000000 1 1 2 ",
            "expected 9000000 vertical angles, found 7",
        ),
        (" -3 1 1 2 ", "at least 2 needed"),
    ] {
        let msg = error_of(&text.replacen(" 7 1 1 2 ", counts, 1), "big.ies");
        assert!(msg.starts_with("big.ies:") && msg.contains(what), "{msg}");
    }
    let gamma = steps(0.0, 90.0, 6);
    let text = ldt_text(1, 1, &gamma, |_, _| 1.0, 1000.0, 1, 100.0);
    let msg = error_of(
        &text.replacen("\r\n1\r\n360\r\n", "\r\n99999999\r\n360\r\n", 1),
        "big.ldt",
    );
    assert!(
        msg.starts_with("big.ldt:4: ") && msg.contains("more than"),
        "{msg}"
    );
    let huge = text
        .replacen("\r\n1\r\n360\r\n", "\r\n9000\r\n360\r\n", 1)
        .replacen("\r\n7\r\n", "\r\n9000\r\n", 1)
        .replacen("\r\n1\r\n1\r\n", "\r\n1\r\n0\r\n", 1);
    let msg = error_of(&huge, "big.ldt");
    assert!(msg.contains("more than 10000000 intensities"), "{msg}");
    let many = text.replacen("\r\n1\r\n360\r\n", "\r\n9000\r\n360\r\n", 1);
    let msg = error_of(&many, "big.ldt");
    assert!(msg.contains("expected 9000 C angles, found"), "{msg}");
}

#[test]
fn unsupported_forms_are_refused_in_one_line() {
    let file = Ies::of(&[0.0], &steps(0.0, 90.0, 6), |_, _| 1.0);
    let msg = error_of(
        &file.text().replace("TILT=NONE", "TILT=lamp.tlt"),
        "lamp.ies",
    );
    assert!(
        msg.starts_with("lamp.ies:4: TILT=lamp.tlt: tilt data in another file is not supported"),
        "{msg}"
    );
    let msg = error_of(&file.text().replace("TILT=NONE", "TILT="), "lamp.ies");
    assert!(msg.starts_with("lamp.ies:4: TILT= names nothing"), "{msg}");
    let msg = error_of(&file.text().replace("TILT=NONE\n", ""), "lamp.ies");
    assert!(msg.contains("no TILT= line"), "{msg}");

    // Types B and A are read; a broken one is reported as broken.
    let mut b = Ies::of(&steps(-90.0, 90.0, 4), &steps(-90.0, 90.0, 6), |_, _| 5.0);
    b.kind = 2;
    assert_eq!(ies(&b.text()).kind, PhotometricType::B);
    b.kind = 3;
    assert_eq!(ies(&b.text()).kind, PhotometricType::A);
    b.candela[3] = -1.0;
    assert!(error_of(&b.text(), "a.ies").contains("is negative"));
    b.kind = 4;
    assert!(error_of(&b.text(), "a.ies").contains("photometric type 4"));

    let mut units = file.clone();
    units.units = 3;
    assert!(error_of(&units.text(), "u.ies").contains("units type 3"));
    let h = Ies::of(&[0.0, 45.0], &steps(0.0, 90.0, 6), |_, _| 1.0);
    assert!(error_of(&h.text(), "h.ies").contains("horizontal angles run 0..45"));
    let v = Ies::of(&[0.0], &steps(-10.0, 90.0, 5), |_, _| 1.0);
    assert!(error_of(&v.text(), "v.ies").contains("vertical angle -10 is outside 0..180"));

    let gamma = steps(0.0, 90.0, 6);
    // Isym 2 with an odd number of planes has no C180 among them at Mc/2 + 1.
    let odd = ldt_text(0, 5, &gamma, about_c0, 1000.0, 1, 100.0).replacen(
        "\r\n0\r\n5\r\n",
        "\r\n2\r\n5\r\n",
        1,
    );
    let msg = error_of(&odd, "odd.ldt");
    assert!(
        msg.starts_with("odd.ldt:3: Isym 2 stores the C-planes 0..180"),
        "{msg}"
    );
    let six = ldt_text(0, 6, &gamma, about_c90, 1000.0, 1, 100.0).replacen(
        "\r\n0\r\n6\r\n",
        "\r\n3\r\n6\r\n",
        1,
    );
    let msg = error_of(&six, "six.ldt");
    assert!(msg.contains("Isym 3 stores the C-planes 90..270"), "{msg}");

    assert!(matches!(
        parse_bytes(b"x", "lamp.txt"),
        Err(PhotometryError::UnknownExtension { .. })
    ));
}

#[test]
fn every_truncation_of_a_valid_file_is_an_error_or_loses_only_the_last_number() {
    let ies_text = Ies::of(&[0.0, 90.0], &steps(0.0, 90.0, 4), quadrant).text();
    let ldt_text = ldt_text(4, 4, &steps(0.0, 90.0, 4), quadrant, 1000.0, 1, 100.0);
    for (text, name) in [
        (ies_text.as_str(), "cut.ies"),
        (ldt_text.as_str(), "cut.ldt"),
    ] {
        let last_word = text.trim_end().rfind(|c: char| c.is_whitespace()).unwrap() + 1;
        for cut in 0..text.len() {
            if !text.is_char_boundary(cut) {
                continue;
            }
            match parse_bytes(&text.as_bytes()[..cut], name) {
                Ok(_) => assert!(cut > last_word, "{name} cut at {cut} read"),
                Err(e) => {
                    located(Err(e), name);
                }
            }
        }
    }
}

#[test]
fn binary_garbage_is_refused_at_a_line() {
    let mut seed = 3u64;
    for round in 0..200 {
        let len = 1 + (lcg(&mut seed) % 3000) as usize;
        let mut bytes: Vec<u8> = (0..len).map(|_| lcg(&mut seed) as u8).collect();
        if round % 2 == 0 {
            // A plausible start, then garbage.
            let mut start = b"IESNA:LM-63-2002\r\nTILT=NONE\r\n1 1000 1 ".to_vec();
            start.append(&mut bytes);
            bytes = start;
        }
        for name in ["g.ies", "g.ldt"] {
            let r = parse_bytes(&bytes, name);
            located(r, name);
        }
    }
}

#[test]
fn any_word_replaced_by_anything_never_panics() {
    // Every word of a small valid file of each format, replaced in turn by awkward values:
    // the reader answers Ok or an error at a line, and never panics or allocates wildly.
    let awkward = [
        "-1",
        "0",
        "-0",
        "1e308",
        "-1e308",
        "NaN",
        "inf",
        "abc",
        "4294967296",
        "2",
        "3",
        "90",
        "180",
        "270",
        "360",
        "1e-300",
        "0.5",
        "",
    ];
    let ies_text = Ies::of(&steps(0.0, 90.0, 2), &steps(0.0, 180.0, 4), quadrant).text();
    let ldt_text = ldt_text(4, 8, &steps(0.0, 180.0, 4), quadrant, 1000.0, 1, 100.0);
    for (text, name, sep) in [
        (ies_text.as_str(), "w.ies", ' '),
        (ldt_text.as_str(), "w.ldt", '\n'),
    ] {
        let lines: Vec<&str> = text.split('\n').collect();
        for (i, line) in lines.iter().enumerate() {
            let words: Vec<&str> = line.split(sep).collect();
            for k in 0..words.len() {
                for bad in awkward {
                    let mut changed = words.clone();
                    changed[k] = bad;
                    let mut all = lines.clone();
                    let joined = changed.join(&sep.to_string());
                    all[i] = &joined;
                    if let Err(e) = parse_bytes(all.join("\n").as_bytes(), name) {
                        located(Err(e), name);
                    }
                }
            }
        }
    }
}

#[test]
fn read_goes_by_extension_and_names_the_file() {
    let dir = std::env::temp_dir().join(format!("radiosity-photometry-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let gamma = steps(0.0, 90.0, 6);
    let ies_path = dir.join("Lamp.IES");
    std::fs::write(&ies_path, Ies::of(&[0.0], &gamma, |_, _| 10.0).text()).unwrap();
    let ldt_path = dir.join("lamp.Ldt");
    std::fs::write(
        &ldt_path,
        ldt_text(1, 1, &gamma, |_, _| 10.0, 1000.0, 1, 100.0),
    )
    .unwrap();
    let a = read(&ies_path).unwrap();
    let b = read(&ldt_path).unwrap();
    assert_eq!(a.source, "Lamp.IES");
    same_distribution(&a, &b, "read");
    let txt = dir.join("lamp.txt");
    std::fs::write(&txt, "x").unwrap();
    let e = read(&txt).unwrap_err();
    assert_eq!(
        e.to_string(),
        "lamp.txt: not a photometric file name (expected the extension .ies or .ldt)"
    );
    let e = read(&dir.join("missing.ies")).unwrap_err();
    assert!(matches!(e, PhotometryError::Io { .. }) && e.to_string().contains("missing.ies"));
    let bad = dir.join("bad.ldt");
    std::fs::write(&bad, "LEDVANCE\r\n2\r\nfive\r\n").unwrap();
    assert_eq!(
        read(&bad).unwrap_err().to_string(),
        "bad.ldt:3: the symmetry indicator Isym 'five' is not a number"
    );
    std::fs::remove_dir_all(&dir).ok();
}

// ---------------------------------------------------------------------------------------------
// Types B and A.

/// Unit direction of type B angles (H, V), degrees, written from the definitions (module
/// documentation): the polar axis is y, V turns the plane about it from −z towards +x, H is
/// the angle out of that plane towards −y.
fn dir_b(h: f64, v: f64) -> [f64; 3] {
    let (h, v) = (h.to_radians(), v.to_radians());
    [h.cos() * v.sin(), -h.sin(), -h.cos() * v.cos()]
}

/// Unit direction of type A angles (H, V): the polar axis is x, H turns the plane about it
/// from −z towards −y, V is the elevation out of that plane towards +x.
fn dir_a(h: f64, v: f64) -> [f64; 3] {
    let (h, v) = (h.to_radians(), v.to_radians());
    [v.sin(), -v.cos() * h.sin(), -v.cos() * h.cos()]
}

/// A type B (`kind` 2) or A (3) IES file of `f(direction)` on the given angles, absolute
/// photometry (so that no flux is stated to differ from).
fn ies_ba(kind: u8, horizontal: &[f64], vertical: &[f64], f: impl Fn([f64; 3]) -> f64) -> Ies {
    let dir = if kind == 2 { dir_b } else { dir_a };
    let mut file = Ies::of(horizontal, vertical, |h, v| f(dir(h, v)));
    file.kind = kind;
    file.lumens = -1.0;
    file
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A random unit direction (uniform on the sphere).
fn random_dir(seed: &mut u64) -> [f64; 3] {
    let u = |seed: &mut u64| (lcg(seed) % 1_000_000_000) as f64 / 1e9;
    let z = 2.0 * u(seed) - 1.0;
    let phi = 2.0 * PI * u(seed);
    let r = (1.0 - z * z).max(0.0).sqrt();
    [r * phi.cos(), r * phi.sin(), z]
}

#[test]
fn type_b_and_a_angles_sit_on_the_documented_axes() {
    let b = ies(&ies_ba(2, &steps(-90.0, 90.0, 6), &steps(-90.0, 90.0, 6), |_| 1.0).text());
    let a = ies(&ies_ba(3, &steps(-90.0, 90.0, 6), &steps(-90.0, 90.0, 6), |_| 1.0).text());
    let near = |x: [f64; 3], y: [f64; 3]| (0..3).all(|k| (x[k] - y[k]).abs() < 1e-12);
    for p in [&b, &a] {
        // The beam along −z, V = 90° up (+x), H = 90° to the right of the beam seen from
        // behind: (−z) × (+x) = −y.
        assert!(near(p.table_direction(0.0, 0.0), [0.0, 0.0, -1.0]));
        assert!(near(p.table_direction(0.0, 90.0), [1.0, 0.0, 0.0]));
        assert!(near(p.table_direction(90.0, 0.0), [0.0, -1.0, 0.0]));
        assert!(near(p.table_direction(-90.0, 0.0), [0.0, 1.0, 0.0]));
    }
    // Off those two circles the systems differ: B's H is a latitude about y, A's V one
    // about x.
    let s = 0.5f64.sqrt();
    assert!(near(b.table_direction(45.0, 45.0), [0.5, -s, -0.5]));
    assert!(near(a.table_direction(45.0, 45.0), [s, -0.5, -0.5]));
    // Angles and directions are inverse, the written-out definitions agree, and the
    // length of a direction does not matter.
    let mut seed = 3u64;
    for _ in 0..2000 {
        let h = (lcg(&mut seed) % 180_000) as f64 / 1000.0 - 90.0;
        let v = (lcg(&mut seed) % 360_000) as f64 / 1000.0 - 180.0;
        for (p, (hh, vv), want) in [(&b, (h, v), dir_b(h, v)), (&a, (v, h), dir_a(v, h))] {
            assert!(near(p.table_direction(hh, vv), want), "{hh} {vv}");
            let (x, y) = p.table_angles(want.map(|c| 4.0 * c)).unwrap();
            assert!(
                (x - hh).abs() < 1e-9 && (y - vv).abs() < 1e-9,
                "({hh}, {vv}) → ({x}, {y})"
            );
        }
    }
    assert_eq!(b.table_angles([0.0; 3]), None);
    assert_eq!(a.table_angles([f64::NAN, 0.0, 1.0]), None);
    assert_eq!(a.intensity_dir([0.0; 3]), 0.0);
}

/// One distribution over the lower hemisphere (the side of the photometric axis −z),
/// tabulated as type C (C 0..360, γ 0..90), B and A (H, V −90..90), all at a step Δ = 5°:
///
///   f(e) = 100 + 60 (e·a) + 40 (e·b)²,   a, b unit.
///
/// Bilinear interpolation on a cell of sides Δ errs by at most (Δ²/8)(max|f_uu| + max|f_vv|)
/// in the table's angles u, v (radians). Along any coordinate line of the three systems a
/// unit direction moves on a circle of radius ≤ 1 at a rate ≤ 1, so |e'| ≤ 1, |e''| ≤ 1 and
/// |f''| ≤ 60 + 40·2·(1 + 1) = 220: each table is within E = 55 Δ² = 0.42 cd of f, two
/// tables within 2E of each other. Past the hemisphere all three send nothing.
///
/// The flux: f integrates over the hemisphere to 200π + 60π (a·(−z)) + 40·2π/3 (∫ e dΩ = π
/// times the axis, ∫ e eᵀ dΩ = 2π/3 I over a hemisphere). B and A integrate their
/// interpolant exactly, within 2π E of it; type C's rule (trapezoid in C and cos γ) is second
/// order too and is held to the same bound.
#[test]
fn one_distribution_as_type_c_b_and_a_gives_the_same_light() {
    let norm = |v: [f64; 3]| {
        let l = dot3(v, v).sqrt();
        v.map(|c| c / l)
    };
    let (a, b) = (norm([0.3, -0.5, -0.8]), norm([0.7, 0.2, 0.4]));
    let f = |e: [f64; 3]| 100.0 + 60.0 * dot3(e, a) + 40.0 * dot3(e, b).powi(2);
    let step = 5.0f64;
    let bound = 55.0 * step.to_radians().powi(2);
    let c = ies(
        &Ies::of(&steps(0.0, 360.0, 72), &steps(0.0, 90.0, 18), |c, g| {
            f(Photometry::direction(c, g))
        })
        .text(),
    );
    let full = steps(-90.0, 90.0, 36);
    let b_table = ies(&ies_ba(2, &full, &full, f).text());
    let a_table = ies(&ies_ba(3, &full, &full, f).text());
    assert!(b_table.warnings.is_empty() && a_table.warnings.is_empty());
    let mut seed = 17u64;
    let mut worst = 0.0f64;
    for _ in 0..20_000 {
        let e = random_dir(&mut seed);
        let values = [
            c.intensity_dir(e),
            b_table.intensity_dir(e),
            a_table.intensity_dir(e),
        ];
        if e[2] > 0.0 {
            assert_eq!(values, [0.0; 3], "{e:?}: light above the table");
            continue;
        }
        let want = f(e);
        for (x, what) in values.iter().zip(["C", "B", "A"]) {
            worst = worst.max((x - want).abs());
            assert!((x - want).abs() <= bound, "{what} {e:?}: {x} vs f = {want}");
        }
        assert!((values[1] - values[2]).abs() <= 2.0 * bound);
        assert!((values[0] - values[1]).abs() <= 2.0 * bound);
    }
    assert!(
        worst > 0.01 * bound,
        "the tables are not exercised off their nodes"
    );
    let exact = 200.0 * PI + 60.0 * PI * -a[2] + 40.0 * 2.0 * PI / 3.0;
    for (p, what) in [(&c, "C"), (&b_table, "B"), (&a_table, "A")] {
        let flux = p.flux();
        assert!(
            (flux - exact).abs() <= 2.0 * PI * bound,
            "{what}: flux {flux} vs {exact} (bound {})",
            2.0 * PI * bound
        );
    }
    assert_eq!(
        b_table.max_intensity(),
        b_table.candela.iter().copied().fold(0.0, f64::max)
    );
}

/// Closed forms of the B and A flux rule, which integrates the interpolated table exactly:
/// a constant I over the front hemisphere sends 2π I on any grid; I = a + b|φ| in the
/// latitude φ (B's H, A's V; a node at 0, so the table is that function exactly) sends
/// π ∫ (a + b|φ|) cos φ dφ = π (2a + b(π − 2)); and the cosine lobe I₀ cos H cos V = I₀ (e·axis)
/// sends π I₀, within 2π (Δ²/8)(I₀ + I₀) of its interpolant.
#[test]
fn type_b_and_a_flux_closed_forms() {
    let full = steps(-90.0, 90.0, 18);
    let uneven = [-90.0, -71.0, -40.0, -3.0, 0.0, 2.5, 30.0, 88.0, 90.0];
    for kind in [2u8, 3] {
        for (h, v) in [
            (&full[..], &full[..]),
            (&uneven[..], &full[..]),
            (&full[..], &uneven[..]),
        ] {
            let p = ies(&ies_ba(kind, h, v, |_| 321.0).text());
            assert!(
                close(p.flux(), 2.0 * PI * 321.0, 1e-12),
                "{kind}: {}",
                p.flux()
            );
        }
        let (a, b) = (200.0, 150.0);
        let latitude = |e: [f64; 3]| {
            if kind == 2 {
                (-e[1]).asin()
            } else {
                e[0].asin()
            }
        };
        for grid in [&full[..], &uneven[..]] {
            let p = ies(&ies_ba(kind, grid, grid, |e| a + b * latitude(e).abs()).text());
            let want = PI * (2.0 * a + b * (PI - 2.0));
            assert!(
                close(p.flux(), want, 1e-12),
                "{kind}: {} vs {want}",
                p.flux()
            );
        }
        let i0 = 1000.0;
        let step = 2.5f64;
        let grid = steps(-90.0, 90.0, 72);
        let p = ies(&ies_ba(kind, &grid, &grid, |e| i0 * -e[2]).text());
        let bound = 2.0 * PI * step.to_radians().powi(2) / 8.0 * 2.0 * i0;
        assert!(
            (p.flux() - PI * i0).abs() <= bound,
            "{kind}: {} vs {}",
            p.flux(),
            PI * i0
        );
        assert!(
            (p.flux() - PI * i0).abs() > 1e-6 * bound,
            "the lobe is not interpolated"
        );
    }
}

/// Every LM-63 form of a type B or A file reads as the full table: horizontal angles 0..90
/// (lateral symmetry, mirrored) as −90..90 of a distribution symmetric about the vertical
/// plane y = 0; vertical angles 0..90 as the −90..90 table above V = 0 and nothing below.
#[test]
fn every_type_b_and_a_form_reads_as_the_full_table() {
    let lateral = |e: [f64; 3]| 300.0 + 80.0 * e[0] + 50.0 * e[2] * e[2] + 40.0 * e[1] * e[1];
    let (full, half) = (steps(-90.0, 90.0, 24), steps(0.0, 90.0, 12));
    let mut seed = 29u64;
    for kind in [2u8, 3] {
        let reference = ies(&ies_ba(kind, &full, &full, lateral).text());
        for (what, h, v) in [
            ("H 0..90", &half, &full),
            ("V 0..90", &full, &half),
            ("H and V 0..90", &half, &half),
        ] {
            let p = ies(&ies_ba(kind, h, v, lateral).text());
            assert!(p.warnings.is_empty(), "{kind} {what}: {:?}", p.warnings);
            assert_eq!(p.c_angles, full, "{kind} {what}: the mirrored angles");
            for _ in 0..5000 {
                let e = random_dir(&mut seed);
                let (x, y) = (p.intensity_dir(e), reference.intensity_dir(e));
                let below = reference.table_angles(e).unwrap().1 < 0.0;
                if v[0] == 0.0 && below {
                    assert_eq!(x, 0.0, "{kind} {what}: {e:?} below V = 0");
                } else {
                    assert!(close(x, y, 1e-12), "{kind} {what}: {e:?}: {x} vs {y}");
                }
            }
            if v[0] == 0.0 {
                // The flux of V ≥ 0 and of V ≤ 0 add up to the whole (each rule exact on
                // its cells).
                let below = ies(&ies_ba(kind, &full, &steps(-90.0, 0.0, 12), lateral).text());
                assert!(
                    close(p.flux() + below.flux(), reference.flux(), 1e-12),
                    "{kind} {what}"
                );
            } else {
                assert!(close(p.flux(), reference.flux(), 1e-12), "{kind} {what}");
            }
        }
        // Other ranges the geometry allows are read with a warning, nothing outside them.
        let narrow = ies(&ies_ba(kind, &steps(-60.0, 60.0, 8), &full, lateral).text());
        assert!(narrow
            .warnings
            .iter()
            .any(|w| w.contains("horizontal angles run -60..60")));
        assert_eq!(narrow.intensity(61.0, 0.0), 0.0);
        assert!(close(
            narrow.intensity(60.0, 0.0),
            reference.intensity(60.0, 0.0),
            1e-12
        ));
    }
}

#[test]
fn type_b_and_a_interpolation_stays_between_the_neighbours() {
    let h = [-90.0, -50.0, -49.0, 0.0, 10.0, 90.0];
    let v = steps(-90.0, 90.0, 9);
    let mut seed = 5u64;
    for kind in [2u8, 3] {
        let mut file = ies_ba(kind, &h, &v, |_| 0.0);
        for x in &mut file.candela {
            *x = if lcg(&mut seed) % 3 == 0 {
                0.0
            } else {
                (lcg(&mut seed) % 100_000) as f64
            };
        }
        let p = ies(&file.text());
        for _ in 0..20_000 {
            let e = random_dir(&mut seed);
            let Some((x, y)) = p.table_angles(e) else {
                continue;
            };
            let x_val = p.intensity_dir(e);
            if e[2] > 0.0 && x_val == 0.0 {
                continue;
            }
            let i = h.partition_point(|&a| a <= x).clamp(1, h.len() - 1) - 1;
            let j = v.partition_point(|&a| a <= y).clamp(1, v.len() - 1) - 1;
            let corners = [
                p.plane(i)[j],
                p.plane(i)[j + 1],
                p.plane(i + 1)[j],
                p.plane(i + 1)[j + 1],
            ];
            let lo = corners.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = corners.iter().copied().fold(0.0, f64::max);
            assert!(
                lo <= x_val && x_val <= hi,
                "{kind}: I({x}, {y}) = {x_val} outside {lo}..{hi}"
            );
        }
        assert!(p.max_intensity() >= p.candela.iter().copied().fold(0.0, f64::max));
    }
}

#[test]
fn hostile_type_b_and_a_files_are_refused_at_their_line() {
    // Line 5 holds the counts, 6 the ballast, 7.. the vertical angles (8 a line), then the
    // horizontal angles, then the candela (7 a line).
    let (h, v) = (steps(-90.0, 90.0, 4), steps(-90.0, 90.0, 6));
    let base = ies_ba(2, &h, &v, |_| 10.0);
    // A latitude past the pole: B's horizontal, A's vertical angle.
    let mut bad = base.clone();
    bad.horizontal[4] = 120.0;
    let msg = error_of(&bad.text(), "b.ies");
    assert!(
        msg.starts_with("b.ies:8: type B horizontal angle 120 is outside -90..90"),
        "{msg}"
    );
    let mut bad = base.clone();
    bad.kind = 3;
    bad.vertical[0] = -100.0;
    let msg = error_of(&bad.text(), "a.ies");
    assert!(
        msg.starts_with("a.ies:7: type A vertical angle -100 is outside -90..90"),
        "{msg}"
    );
    // A longitude past ±180.
    let mut bad = base.clone();
    bad.vertical[6] = 200.0;
    let msg = error_of(&bad.text(), "b.ies");
    assert!(
        msg.starts_with("b.ies:7: vertical angle 200 is outside -180..180"),
        "{msg}"
    );
    // Angles that do not increase.
    let mut bad = base.clone();
    bad.horizontal[2] = -60.0;
    let msg = error_of(&bad.text(), "b.ies");
    assert!(
        msg.starts_with("b.ies:8: horizontal angle -60 does not increase"),
        "{msg}"
    );
    // One horizontal angle: no rotational symmetry in B or A.
    for kind in [2u8, 3] {
        let one = ies_ba(kind, &[0.0], &v, |_| 10.0);
        let msg = error_of(&one.text(), "one.ies");
        assert!(
            msg.starts_with("one.ies:5: 1 horizontal angle: type"),
            "{msg}"
        );
    }
    // A negative or non-numeric candela value, at its line (the first candela line is 9).
    let mut bad = base.clone();
    bad.candela[8] = -3.0;
    let msg = error_of(&bad.text(), "b.ies");
    assert!(
        msg.starts_with("b.ies:10: candela value -3 is negative"),
        "{msg}"
    );
    let text = base.text().replacen("10 10 10", "10 x 10", 1);
    let msg = error_of(&text, "b.ies");
    assert!(
        msg.starts_with("b.ies:9: candela value 'x' is not a number"),
        "{msg}"
    );
    // Cut short: at the end.
    let text = base.text();
    let cut = text.trim_end().rsplit_once(' ').unwrap().0;
    let msg = error_of(cut, "b.ies");
    assert!(msg.contains("expected 35 candela values"), "{msg}");
    // Every truncation of a B file with a tilt table is an error or a table, never a panic.
    let mut tilted = ies_ba(3, &steps(0.0, 90.0, 3), &v, |e| 5.0 + e[0]);
    tilted.tilt = "TILT=INCLUDE\n3\n3\n0 45 90\n1 .8 .6\n".into();
    let text = tilted.text();
    for cut in 0..text.len() {
        let _ = parse_ies(&text[..cut], "cut.ies");
    }
    assert!(ies(&text).tilt.is_some());
}

#[test]
fn the_installed_tilt_angle_follows_the_lamp_geometry() {
    let table = |geometry| Tilt {
        geometry,
        angles: vec![0.0, 90.0, 180.0],
        factors: vec![1.0, 0.5, 0.25],
    };
    let (v, along, across) = (
        table(LampGeometry::Vertical),
        table(LampGeometry::AlongC0),
        table(LampGeometry::AcrossC0),
    );
    let deg = |t: &Tilt, up: [f64; 3]| t.installed_angle(up).unwrap();
    let near = |a: f64, b: f64| (a - b).abs() < 1e-9;
    // Aimed straight down: up is the luminaire's +z; nothing is tilted.
    for t in [&v, &along, &across] {
        assert!(near(deg(t, [0.0, 0.0, 2.0]), 0.0));
        assert_eq!(t.installed_angle([0.0; 3]), None);
    }
    // Tilted 30° in the C0 plane (about y): the world's up leans towards −x in the frame.
    let (s, c) = (30f64.to_radians().sin(), 30f64.to_radians().cos());
    let up = [-s, 0.0, c];
    assert!(near(deg(&v, up), 30.0));
    assert!(near(deg(&along, up), 30.0), "a lamp along C0 tilts with it");
    assert!(
        near(deg(&across, up), 0.0),
        "a lamp along C90 stays horizontal"
    );
    // Tilted 30° about x: the other way round.
    let up = [0.0, s, c];
    assert!(near(deg(&v, up), 30.0));
    assert!(near(deg(&along, up), 0.0));
    assert!(near(deg(&across, up), 30.0));
    // Aimed straight up: the vertical lamp is base over, the horizontal ones level.
    assert!(near(deg(&v, [0.0, 0.0, -1.0]), 180.0));
    assert!(near(deg(&along, [0.0, 0.0, -1.0]), 0.0));
    // Aimed horizontally, C0 up: 90° for the vertical lamp and the one along C0.
    assert!(near(deg(&v, [1.0, 0.0, 0.0]), 90.0));
    assert!(near(deg(&along, [1.0, 0.0, 0.0]), 90.0));
    assert!(near(deg(&across, [1.0, 0.0, 0.0]), 0.0));
    assert!(near(v.factor(45.0).0, 0.75) && near(v.factor(135.0).0, 0.375));
}

// ---------------------------------------------------------------------------------------------
// The real files.

fn shared() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/photometry")
}

fn real(name: &str) -> Photometry {
    read(&shared().join(name)).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
#[ignore = "needs ../shared/photometry (run with --include-ignored, as .ci/run does)"]
fn every_real_file_reads_with_a_plausible_flux() {
    let mut names: Vec<String> = std::fs::read_dir(shared())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| Format::of(n).is_some())
        .collect();
    names.sort();
    assert_eq!(names.len(), 6, "{names:?}");
    println!(
        "{:<38} {:>6} {:>5} {:>10} {:>10} {:>10} {:>9}",
        "file", "planes", "γ", "flux lm", "lumens", "stated lm", "mismatch"
    );
    for name in &names {
        let p = real(name);
        let flux = p.flux();
        let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.0}"));
        println!(
            "{name:<38} {:>6} {:>5} {flux:>10.1} {:>10} {:>10} {:>9}",
            p.c_angles.len(),
            p.gamma_angles.len(),
            opt(p.lumens),
            opt(p.rated_flux),
            p.flux_mismatch()
                .map_or("-".to_string(), |m| format!("{:.2} %", 100.0 * m))
        );
        for w in &p.warnings {
            println!("    warning: {w}");
        }
        assert!(flux > 0.0, "{name}");
        assert_eq!(p.kind, PhotometricType::C);
        assert_eq!(p.c_angles.first(), Some(&0.0));
        assert_eq!(p.c_angles.last(), Some(&360.0));
        // The table's integral against the interpolated intensity's: within 1 %.
        let brute = brute_flux(&p, 720, 1440);
        assert!(close(flux, brute, 0.01), "{name}: {flux} vs {brute}");
        if let Some(m) = p.flux_mismatch() {
            // Measured tables are not exact; and an IES file states its lamps' lumens, not
            // the luminaire's (examp1.ies: two fluorescent lamps of 2,900 lm, of which the
            // table sends out 91 %).
            assert!(m < 0.2, "{name}: mismatch {m}");
        }
    }
}

#[test]
#[ignore = "needs ../shared/photometry (run with --include-ignored, as .ci/run does)"]
fn the_real_files_have_their_documented_shapes() {
    // Absolute photometry: no lumens in the file; 5,300 lm rated in its [LUMINAIRE] line.
    let p = real("highbay-interlight-ovni-60w.ies");
    assert_eq!(p.lumens, None);
    assert!(close(p.flux(), 5300.0, 0.10), "highbay flux {}", p.flux());
    assert_eq!(p.gamma_angles.len(), 361);
    assert_eq!(p.c_angles, vec![0.0, 360.0]);
    assert!(close(p.plane(0)[0], 4170.2998 * 0.4597, 1e-12));
    assert!(p.opening.round && close(p.opening.width_m, 0.3, 1e-12));

    let p = real("maxwell-8-t4-iesna.ies");
    assert_eq!((p.c_angles.len(), p.gamma_angles.len()), (73, 91));
    assert_eq!(p.lumens, Some(1000.0));

    let p = real("roadway-60w-lm63-2019.ies");
    assert_eq!((p.c_angles.len(), p.gamma_angles.len()), (73, 361));

    let p = real("examp1.ies");
    // 0–90 horizontal (quadrant symmetry), 73 vertical angles at 2.5°.
    assert_eq!(p.c_angles, steps(0.0, 360.0, 16));
    assert_eq!(p.gamma_angles.len(), 73);
    assert_eq!(p.lumens, Some(5800.0));
    assert!(close(p.opening.length_m, 4.04 * 0.3048, 1e-12));

    let p = real("floodlight-ledvance-600w-sym60.ldt");
    assert_eq!((p.c_angles.len(), p.gamma_angles.len()), (17, 37));
    assert_eq!(p.lumens, Some(80500.0));
    assert!(close(p.rated_flux.unwrap(), 80500.0 * 0.999, 1e-12));

    let p = real("floodlight-ledvance-900w-asym.ldt");
    assert_eq!((p.c_angles.len(), p.gamma_angles.len()), (9, 19));
    assert_eq!(p.c_angles, steps(0.0, 360.0, 8));
    assert_eq!(p.lumens, Some(123000.0));
    // The first intensity, 224.77 cd/klm of 123,000 lm.
    assert!(close(p.plane(0)[0], 224.77 * 123.0, 1e-12));
}

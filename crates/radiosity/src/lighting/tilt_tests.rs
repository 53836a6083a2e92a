//! Tests of luminaires of every photometric type placed in a scene and of their lamps' tilt
//! factors (IES `TILT=INCLUDE`), against closed forms derived by hand.

use super::*;
use crate::lighting::schedule::parse_schedule;
use crate::lighting::{direct_illuminance, SensorPoint, Up};
use crate::photometry::{parse_bytes, Photometry};

use crate::lighting::tests::ies_with as ies;

fn steps(from: f64, to: f64, step: f64) -> Vec<f64> {
    let n = ((to - from) / step).round() as usize;
    (0..=n).map(|k| from + k as f64 * step).collect()
}

fn parse(text: &str) -> Arc<Photometry> {
    Arc::new(parse_bytes(text.as_bytes(), "t.ies").unwrap_or_else(|e| panic!("{e}\n{text}")))
}

/// The tilt section of a lamp of `geometry` whose light falls linearly from 1 at 0° to 0.5 at
/// 90°.
fn halving(geometry: u8) -> String {
    format!("TILT=INCLUDE\n{geometry}\n2\n0 90\n1.0 0.5\n")
}

/// An intensity smooth and asymmetric in C and γ (C0 ≠ C180, C90 ≠ C270).
fn asym(c: f64, g: f64) -> f64 {
    let (c, g) = (c.to_radians(), g.to_radians());
    100.0 + g.sin() * (40.0 * c.cos() + 25.0 * c.sin() + 10.0 * (2.0 * c).sin()) + 20.0 * g.cos()
}

fn type_c(tilt: &str) -> Arc<Photometry> {
    parse(&ies(
        1,
        tilt,
        &steps(0.0, 360.0, 15.0),
        &steps(0.0, 180.0, 15.0),
        [0.0; 3],
        asym,
    ))
}

/// Sensors all around the origin at 1.5–4 m, their normals turned every way (those facing
/// away get nothing, from either luminaire).
fn sensors() -> Vec<SensorPoint> {
    let mut out = Vec::new();
    for k in 0..200 {
        let t = k as f64;
        let (a, b) = (t * 2.399963, (t * 0.731).sin() * 1.5);
        let r = 1.5 + 2.5 * ((t * 0.377).sin() * 0.5 + 0.5);
        let p = [r * b.cos() * a.cos(), r * b.cos() * a.sin(), r * b.sin()];
        let n = [-(t * 1.3).cos(), (t * 0.7).sin(), -(t * 0.9).sin()];
        out.push(SensorPoint::new(p, n).unwrap());
    }
    out
}

fn lux(points: &[SensorPoint], l: &Luminaire) -> Vec<f64> {
    direct_illuminance(points, std::slice::from_ref(l), None, 1.0)
        .unwrap()
        .total
}

/// The luminaire at the origin aimed along `aim` with C0 hint `c0`, its lamp tilt applied for
/// +z up.
fn placed(p: &Arc<Photometry>, aim: [f64; 3], c0: Option<[f64; 3]>) -> Luminaire {
    Luminaire::new("l", p.clone(), [0.0; 3], aim, c0, 1.0, "")
        .unwrap()
        .with_lamp_tilt([0.0, 0.0, 1.0])
        .unwrap()
}

/// Aims tilted by `deg` from straight down with their C0: in the C0 plane (about y; C0 turns
/// with the aim) and across it (about x; C0 stays +x).
fn aims(deg: f64) -> [([f64; 3], [f64; 3]); 2] {
    let (s, c) = (deg.to_radians().sin(), deg.to_radians().cos());
    [([s, 0.0, -c], [c, 0.0, s]), ([0.0, s, -c], [1.0, 0.0, 0.0])]
}

/// LM-63: the candela values are multiplied by the tilt table's factor at the installed tilt
/// angle. With factors 1 at 0° and 0.5 at 90°, linear between, a luminaire tilted by α has
/// f(α) = 1 − α/180: 0.75 at 45°, 0.5 at 90°. Its illuminance at every point around it is
/// f(α) times that of the same luminaire, same aim, with no tilt table (the distribution is
/// moved with the aim in both), to 1e-12. Which tilts count depends on the lamp:
/// geometry 1 (vertical lamp) every tilt; 2 (lamp along C0) a tilt in the C0 plane, not one
/// across it; 3 (lamp along C90) the other way round.
#[test]
fn a_tilted_lamp_scales_the_illuminance_by_the_tables_factor() {
    let points = sensors();
    let plain = type_c("TILT=NONE\n");
    for geometry in [1u8, 2, 3] {
        let tilted = type_c(&halving(geometry));
        for deg in [0.0, 45.0, 90.0] {
            let f = 1.0 - deg / 180.0;
            for (k, (aim, c0)) in aims(deg).into_iter().enumerate() {
                let want = match (geometry, k) {
                    (1, _) | (2, 0) | (3, 1) => f,
                    _ => 1.0,
                };
                let l = placed(&tilted, aim, Some(c0));
                let lamp = l.tilt.expect("a tilt table is applied");
                assert!((lamp.factor - want).abs() < 1e-12, "{geometry} {deg} {k}");
                assert!(lamp.in_table && l.warnings.is_empty());
                assert!((l.multiplier - want).abs() < 1e-12);
                let (e, e0) = (
                    lux(&points, &l),
                    lux(&points, &placed(&plain, aim, Some(c0))),
                );
                let mut lit = 0;
                for (x, x0) in e.iter().zip(&e0) {
                    assert!(
                        (x - want * x0).abs() <= 1e-12 * x0.abs(),
                        "{x} vs {want} × {x0}"
                    );
                    lit += usize::from(*x0 > 0.0);
                }
                assert!(lit > 50, "only {lit} points lit");
            }
        }
    }
    // Without a tilt table nothing changes, and a tilt is applied once only.
    let (aim, c0) = aims(45.0)[0];
    let l = placed(&plain, aim, Some(c0));
    assert_eq!((l.tilt, l.multiplier), (None, 1.0));
    let tilted = placed(&type_c(&halving(1)), aim, Some(c0));
    let again = tilted.clone().with_lamp_tilt([0.0, 0.0, 1.0]).unwrap();
    assert_eq!(again.multiplier, tilted.multiplier);
    assert_eq!(
        tilted.with_lamp_tilt([0.0, 0.0, 0.0]).unwrap_err(),
        FrameError::Up
    );
}

/// An installed tilt outside the table takes the nearer end's factor, with a warning: a
/// vertical lamp aimed 135° from straight down against a table of 0..90°.
#[test]
fn a_tilt_outside_the_table_is_clamped_with_a_warning() {
    let p = type_c(&halving(1));
    let (aim, c0) = aims(135.0)[0];
    let l = placed(&p, aim, Some(c0));
    let lamp = l.tilt.unwrap();
    assert!((lamp.angle - 135.0).abs() < 1e-9 && !lamp.in_table);
    assert_eq!(lamp.factor, 0.5);
    assert_eq!(l.warnings.len(), 1, "{:?}", l.warnings);
    let w = &l.warnings[0];
    assert!(
        w.contains("135.0°") && w.contains("0..90°") && w.contains("0.5") && !w.contains('\n'),
        "{w}"
    );
    let points = sensors();
    let plain = placed(&type_c("TILT=NONE\n"), aim, Some(c0));
    for (x, x0) in lux(&points, &l).iter().zip(lux(&points, &plain)) {
        assert!((x - 0.5 * x0).abs() <= 1e-12 * x0);
    }
}

/// The schedule applies each row's own tilt (one file, three aims: down, sideways, up, the
/// last outside the table) and shares the file; a floodlight (type B) row without C0 gets
/// the scene's up as its top.
#[test]
fn the_schedule_tilts_each_row_and_keeps_floodlights_upright() {
    let dir = std::env::temp_dir().join(format!("radiosity-tilt-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let grid = steps(-90.0, 90.0, 10.0);
    std::fs::write(
        dir.join("mh.ies"),
        ies(
            1,
            &halving(1),
            &[0.0],
            &steps(0.0, 180.0, 90.0),
            [0.0; 3],
            |_, _| 100.0,
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("flood.ies"),
        ies(2, "TILT=NONE\n", &grid, &grid, [0.0; 3], |_, _| 50.0),
    )
    .unwrap();
    let schedule = "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group\n\
        down,mh.ies,0,0,3,,,,,,,0.8,\n\
        side,mh.ies,0,0,3,1,0,0,,,,0.8,\n\
        up,mh.ies,0,0,3,0,0,1,,,,,\n\
        flood,flood.ies,0,0,3,0,1,-1,,,,,\n\
        flood-down,flood.ies,0,0,3,,,,,,,,\n\
        flood-c0,flood.ies,0,0,3,0,1,0,1,0,0,,\n";
    let lums = parse_schedule(schedule, "lights.csv", &dir, Up::Z).unwrap();
    let factors: Vec<Option<f64>> = lums.iter().map(|l| l.tilt.map(|t| t.factor)).collect();
    assert_eq!(factors, [Some(1.0), Some(0.5), Some(0.5), None, None, None]);
    assert_eq!(lums[0].multiplier, 0.8);
    assert_eq!(lums[1].multiplier, 0.4);
    assert!(Arc::ptr_eq(&lums[0].photometry, &lums[2].photometry));
    assert!(lums[0].warnings.is_empty() && lums[1].warnings.is_empty());
    assert_eq!(lums[2].warnings.len(), 1, "{:?}", lums[2].warnings);
    assert!(lums[2].warnings[0].starts_with("up: "));
    let near = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-12);
    // Aimed down-forward along +y, its top (V = 90°) is the part of +z across the beam.
    let s = 0.5f64.sqrt();
    assert!(near(lums[3].c0, [0.0, s, s]), "{:?}", lums[3].c0);
    // Aimed straight down, the type C default.
    assert!(near(lums[4].c0, [1.0, 0.0, 0.0]));
    // A given C0 is kept.
    assert!(near(lums[5].c0, [1.0, 0.0, 0.0]));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A type B floodlight aimed horizontally along +y, its top up (+z): the light a wall
/// sensor facing it receives is f(H, V) cos θ / d² with V the elevation of the sensor's
/// plane above the beam and H its angle to the right (towards −x, seen from behind looking
/// along +y); the distribution is asymmetric in both, so a swapped or mirrored axis fails.
/// The points sit on table nodes (10° steps), where the interpolation is exact.
#[test]
fn a_type_b_floodlight_lights_where_its_angles_point() {
    let f = |h: f64, v: f64| 1000.0 + 6.0 * h + 3.0 * v + 0.02 * h * v;
    let grid = steps(-90.0, 90.0, 10.0);
    let p = parse(&ies(2, "TILT=NONE\n", &grid, &grid, [0.0; 3], f));
    let l = Luminaire::new(
        "f",
        p,
        [0.0; 3],
        [0.0, 1.0, 0.0],
        Some([0.0, 0.0, 1.0]),
        1.0,
        "",
    )
    .unwrap();
    for (h, v) in [
        (0.0, 0.0),
        (30.0, 0.0),
        (-20.0, 40.0),
        (50.0, -30.0),
        (70.0, 60.0),
    ] {
        let (hr, vr) = (f64::to_radians(h), f64::to_radians(v));
        // Type B: e = cos H (sin V top + cos V beam) + sin H right, the right of a beam
        // along +y with its top +z being +x.
        let (beam, top, right) = ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
        let e: [f64; 3] = std::array::from_fn(|k| {
            hr.cos() * (vr.sin() * top[k] + vr.cos() * beam[k]) + hr.sin() * right[k]
        });
        let d = 2.0;
        let at = e.map(|c| d * c);
        let s = SensorPoint::new(at, e.map(|c| -c)).unwrap();
        let got = lux(&[s], &l)[0];
        let want = f(h, v) / (d * d);
        assert!(
            (got - want).abs() <= 1e-9 * want,
            "H {h} V {v}: {got} vs {want}"
        );
    }
}

/// The near field works for a floodlight as for a downlight: a type B Lambertian panel
/// (I₀ cos H cos V = I₀ cos of the angle off the beam; 1° table) with a 1.2 m square opening,
/// aimed at a wall 0.6 m and 1.2 m away, gives at the point facing its centre the closed form
/// of a Lambertian square (configuration factor of a parallel rectangle, Howell's catalogue,
/// times πL, L = I₀/a²) within 1 %, where the point law is 33–130 % off.
#[test]
fn a_floodlight_opening_is_integrated_in_the_near_field() {
    let (i0, a) = (1000.0, 1.2);
    let grid = steps(-90.0, 90.0, 1.0);
    let p = parse(&ies(2, "TILT=NONE\n", &grid, &grid, [a, a, 0.0], |h, v| {
        i0 * h.to_radians().cos() * v.to_radians().cos()
    }));
    let l = Luminaire::new(
        "panel",
        p,
        [0.0; 3],
        [1.0, 0.0, 0.0],
        Some([0.0, 0.0, 1.0]),
        1.0,
        "",
    )
    .unwrap();
    let closed = |h: f64| {
        let x: f64 = a / 2.0 / h;
        let q = x / (1.0 + x * x).sqrt() * (x / (1.0 + x * x).sqrt()).atan();
        4.0 * (i0 / (a * a)) / 2.0 * 2.0 * q
    };
    for h in [0.6, 1.2] {
        let s = SensorPoint::new([h, 0.0, 0.0], [-1.0, 0.0, 0.0]).unwrap();
        let e = lux(&[s], &l)[0];
        let want = closed(h);
        assert!(
            (e - want).abs() <= 0.01 * want,
            "h = {h}: {e} lux vs {want}"
        );
        assert!((i0 / (h * h) - want).abs() > 0.3 * want);
    }
}

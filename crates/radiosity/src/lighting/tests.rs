//! Tests of the lighting layer against closed forms derived by hand, with photometric files
//! written here as IES text; hostile schedules and points files.

use super::*;
use crate::accel::Bvh;
use crate::geom::Vec3;
use crate::mesh::{Mesh, MeshParams};
use crate::photometry::Photometry;
use crate::scene::{Material, Scene};
use crate::Rgb;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;

// ---------------------------------------------------------------------------------------------
// Helpers.

/// A type C IES file (absolute photometry, lumens −1, metres) of `f(C, γ)` candela on the
/// given angles. One horizontal angle (0) is rotational symmetry; 0..=360 the full circle.
pub(super) fn ies(horizontal: &[f64], vertical: &[f64], f: impl Fn(f64, f64) -> f64) -> String {
    ies_with(1, "TILT=NONE\n", horizontal, vertical, [0.0; 3], f)
}

/// An IES file (absolute photometry, metres, photometric type `kind`: 1 C, 2 B, 3 A) with the
/// tilt section `tilt` (a `TILT=` line and what follows), of `f(h, v)` candela on the given
/// angles, with a luminous opening `dims` (width, length, height).
pub(super) fn ies_with(
    kind: u8,
    tilt: &str,
    horizontal: &[f64],
    vertical: &[f64],
    dims: [f64; 3],
    f: impl Fn(f64, f64) -> f64,
) -> String {
    let mut s = format!("IESNA:LM-63-2002\n[TEST] lighting unit test\n{tilt}");
    let [w, l, h] = dims;
    writeln!(
        s,
        "1 -1 1 {} {} {kind} 2 {w} {l} {h}\n1 1 40",
        vertical.len(),
        horizontal.len()
    )
    .unwrap();
    let line = |s: &mut String, v: &[f64]| {
        let words: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
        writeln!(s, "{}", words.join(" ")).unwrap();
    };
    line(&mut s, vertical);
    line(&mut s, horizontal);
    for &hh in horizontal {
        let row: Vec<f64> = vertical.iter().map(|&v| f(hh, v)).collect();
        line(&mut s, &row);
    }
    s
}

pub(super) fn steps(from: f64, to: f64, step: f64) -> Vec<f64> {
    let n = ((to - from) / step).round() as usize;
    (0..=n).map(|k| from + k as f64 * step).collect()
}

pub(super) fn parse(text: &str, name: &str) -> Arc<Photometry> {
    Arc::new(crate::photometry::parse_bytes(text.as_bytes(), name).unwrap())
}

/// A rotationally symmetric I₀ cos γ over the lower hemisphere, 0 above, tabulated every 5°.
fn lambertian(i0: f64) -> Arc<Photometry> {
    let text = ies(&[0.0], &steps(0.0, 180.0, 5.0), |_, g| {
        if g <= 90.0 {
            (i0 * g.to_radians().cos()).max(0.0)
        } else {
            0.0
        }
    });
    parse(&text, "lambertian.ies")
}

/// The same intensity `i` in every direction.
pub(super) fn isotropic(i: f64) -> Arc<Photometry> {
    parse(&ies(&[0.0], &[0.0, 90.0, 180.0], |_, _| i), "isotropic.ies")
}

/// An intensity asymmetric in C (C0 ≠ C180, C90 ≠ C270, C45 ≠ C135 …), smooth and
/// periodic, and the same in every plane at γ = 0 and 180°.
fn asym(c: f64, g: f64) -> f64 {
    let (c, g) = (c.to_radians(), g.to_radians());
    100.0 + g.sin() * (40.0 * c.cos() + 25.0 * c.sin() + 10.0 * (2.0 * c).sin()) + 20.0 * g.cos()
}

fn asymmetric() -> Arc<Photometry> {
    let text = ies(&steps(0.0, 360.0, 15.0), &steps(0.0, 180.0, 15.0), asym);
    parse(&text, "asymmetric.ies")
}

fn sensor(position: [f64; 3], normal: [f64; 3]) -> SensorPoint {
    SensorPoint::new(position, normal).unwrap()
}

pub(super) fn down(name: &str, photometry: Arc<Photometry>, position: [f64; 3]) -> Luminaire {
    Luminaire::new(name, photometry, position, [0.0, 0.0, -1.0], None, 1.0, "").unwrap()
}

fn close(got: f64, want: f64, rel: f64) -> bool {
    (got - want).abs() <= rel * want.abs().max(f64::MIN_POSITIVE)
}

fn direct(points: &[SensorPoint], lums: &[Luminaire]) -> DirectResult {
    direct_illuminance(points, lums, None, 1.0).unwrap()
}

/// A fresh folder for one test's files.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("radiosity-lighting-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

// ---------------------------------------------------------------------------------------------
// Direct illuminance against closed forms.

/// CIE 171:2006 test case 5.2 style: a point source of I(γ) = I₀ cos γ (rotationally
/// symmetric, facing down) h = 3 m above a horizontal plane. At a point at horizontal
/// distance r, d² = h² + r², cos γ = h/d (the direction down to the point) and cos θ = h/d
/// (the plane's normal, up, against the direction back to the source), so
/// E = I₀ cos γ · cos θ / d² = I₀ h² / d⁴.
///
/// At points whose γ falls on the table's 5° angles the interpolation is exact: 1e-9
/// relative (the angle of a computed direction is off a table angle by ~1e-14°). Halfway
/// between two angles γ ± Δ/2 the linear interpolation gives the chord's midpoint,
/// (cos(γ − Δ/2) + cos(γ + Δ/2))/2 = cos γ · cos(Δ/2): exactly cos 2.5° times the closed
/// form, again to 1e-9.
#[test]
fn lambertian_source_over_a_plane() {
    let (i0, h) = (1000.0, 3.0);
    let lum = down("L", lambertian(i0), [0.0, 0.0, h]);
    for unit in [1.0, 0.001] {
        // In millimetres the same room is 1000 times the numbers.
        let s = 1.0 / unit;
        let lum = Luminaire {
            position: [0.0, 0.0, h * s],
            ..lum.clone()
        };
        let mut points = Vec::new();
        let mut want = Vec::new();
        for (k, gamma) in steps(0.0, 85.0, 2.5).into_iter().enumerate() {
            let r = h * gamma.to_radians().tan();
            let azimuth = (37.0 * k as f64).to_radians();
            points.push(sensor(
                [r * azimuth.cos() * s, r * azimuth.sin() * s, 0.0],
                [0.0, 0.0, 1.0],
            ));
            let d2 = h * h + r * r;
            let exact = i0 * h * h / (d2 * d2);
            let on_table = k % 2 == 0;
            want.push(if on_table {
                exact
            } else {
                exact * 2.5f64.to_radians().cos()
            });
        }
        let e = direct_illuminance(&points, std::slice::from_ref(&lum), None, unit).unwrap();
        assert_eq!(e.groups, vec![String::new()]);
        for (k, (got, want)) in e.total.iter().zip(&want).enumerate() {
            assert!(
                close(*got, *want, 1e-9),
                "unit {unit} point {k}: {got} vs {want}"
            );
        }
        // Under the source: I₀ / h².
        assert!(close(e.total[0], i0 / (h * h), 1e-12));
    }
}

/// An isotropic source of I candela: E = I cos θ / d² on sensors tilted every way, 0 where
/// the sensor faces away. Constant tables interpolate exactly: 1e-12.
#[test]
fn isotropic_source_on_tilted_sensors() {
    let i = 250.0;
    let at = [1.0, 2.0, 3.0];
    let lum = down("L", isotropic(i), at);
    let cases: [([f64; 3], [f64; 3]); 6] = [
        ([1.0, 2.0, 0.0], [0.0, 0.0, 1.0]),
        ([3.0, -1.0, 0.5], [0.3, -0.2, 1.0]),
        ([-2.0, 4.0, 5.0], [1.0, 0.0, 0.0]),
        ([0.0, 0.0, 0.0], [-1.0, 1.0, 2.0]),
        ([4.0, 4.0, 4.0], [-1.0, -0.5, -0.25]),
        // Facing away.
        ([1.0, 2.0, 0.0], [0.0, 0.0, -1.0]),
    ];
    let points: Vec<SensorPoint> = cases.iter().map(|&(p, n)| sensor(p, n)).collect();
    let e = direct(&points, std::slice::from_ref(&lum));
    for (k, &(p, n)) in cases.iter().enumerate() {
        let v = sub(at, p);
        let d = norm(v);
        let cos = (dot(n, v) / (norm(n) * d)).max(0.0);
        let want = i * cos / (d * d);
        assert!(
            close(e.total[k], want, 1e-12),
            "{k}: {} vs {want}",
            e.total[k]
        );
    }
    assert_eq!(e.total[5], 0.0);
}

/// A luminaire aimed sideways along +x with its C0 hint (0.5, 0, 1) made perpendicular to
/// the aim by hand: C0 = +z, C90 = C0 × nadir = z × x = +y. A local direction (C, γ) is
/// then, in the world, sin γ cos C · z + sin γ sin C · y + cos γ · x. At points in those
/// directions (γ and C on the table's 15° grid, so interpolation is exact) E must be
/// m · I(C, γ) cos θ / d² with I asymmetric in C: a mirrored or rotated frame would read
/// other planes.
#[test]
fn rotated_luminaire_matches_hand_frame() {
    let at = [1.0, 2.0, 3.0];
    let m = 0.8;
    let lum = Luminaire::new(
        "side",
        asymmetric(),
        at,
        [2.0, 0.0, 0.0],
        Some([0.5, 0.0, 1.0]),
        m,
        "g",
    )
    .unwrap();
    assert!(close_vec(lum.nadir, [1.0, 0.0, 0.0]));
    assert!(close_vec(lum.c0, [0.0, 0.0, 1.0]));
    assert!(close_vec(lum.c90, [0.0, 1.0, 0.0]));
    let world = |c: f64, g: f64| {
        let (c, g) = (c.to_radians(), g.to_radians());
        [g.cos(), g.sin() * c.sin(), g.sin() * c.cos()]
    };
    check_frame(&lum, world, m);
}

/// A luminaire tilted every way: aim (1, −2, −3), C0 hint (1, 1, 0.2). The frame by
/// Gram–Schmidt written out here: n = aim/|aim|, c0 = (h − (h·n) n)/|…|, c90 = c0 × n; a
/// local (C, γ) is sin γ cos C · c0 + sin γ sin C · c90 + cos γ · n in the world.
#[test]
fn tilted_luminaire_matches_gram_schmidt_frame() {
    let aim = [1.0, -2.0, -3.0];
    let hint = [1.0, 1.0, 0.2];
    let n = scale(aim, 1.0 / norm(aim));
    let p = sub(hint, scale(n, dot(hint, n)));
    let c0 = scale(p, 1.0 / norm(p));
    let c90 = cross(c0, n);
    let lum = Luminaire::new(
        "tilt",
        asymmetric(),
        [-1.0, 0.5, 4.0],
        aim,
        Some(hint),
        1.5,
        "",
    )
    .unwrap();
    assert!(close_vec(lum.nadir, n) && close_vec(lum.c0, c0) && close_vec(lum.c90, c90));
    // Orthonormal and right-handed: c0 × c90 = −nadir (up).
    for (a, b) in [(lum.c0, lum.c90), (lum.c0, lum.nadir), (lum.c90, lum.nadir)] {
        assert!(dot(a, b).abs() < 1e-15);
    }
    for v in [lum.c0, lum.c90, lum.nadir] {
        assert!((norm(v) - 1.0).abs() < 1e-15);
    }
    assert!(close_vec(cross(lum.c0, lum.c90), lum.up()));
    let world = |c: f64, g: f64| {
        let (c, g) = (c.to_radians(), g.to_radians());
        let mut w = [0.0; 3];
        for k in 0..3 {
            w[k] = g.sin() * c.cos() * c0[k] + g.sin() * c.sin() * c90[k] + g.cos() * n[k];
        }
        w
    };
    check_frame(&lum, world, 1.5);
}

fn close_vec(a: [f64; 3], b: [f64; 3]) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() < 1e-14)
}

/// Sensors at 2.5 units from `lum` along `world(C, γ)` for C and γ on the 15° grid (γ in
/// 15..=165), each tilted off the line of sight by a known angle, against m I(C, γ) cos θ / d².
fn check_frame(lum: &Luminaire, world: impl Fn(f64, f64) -> [f64; 3], m: f64) {
    let dist = 2.5;
    let mut points = Vec::new();
    let mut want = Vec::new();
    for c in steps(0.0, 345.0, 15.0) {
        for g in steps(15.0, 165.0, 15.0) {
            let w = world(c, g);
            let p = [
                lum.position[0] + dist * w[0],
                lum.position[1] + dist * w[1],
                lum.position[2] + dist * w[2],
            ];
            // Facing the luminaire, tilted by an angle about an axis across the line of sight.
            let back = scale(w, -1.0);
            let across = cross(
                back,
                if w[2].abs() < 0.9 {
                    [0.0, 0.0, 1.0]
                } else {
                    [1.0, 0.0, 0.0]
                },
            );
            let across = scale(across, 1.0 / norm(across));
            let tilt = (c + g).to_radians() * 0.25 % 1.4;
            let normal = [
                back[0] * tilt.cos() + across[0] * tilt.sin(),
                back[1] * tilt.cos() + across[1] * tilt.sin(),
                back[2] * tilt.cos() + across[2] * tilt.sin(),
            ];
            points.push(sensor(p, normal));
            want.push(m * asym(c, g) * tilt.cos() / (dist * dist));
            // The intensity alone, too.
            assert!(
                close(lum.intensity_towards(w), m * asym(c, g), 1e-9),
                "C {c} γ {g}"
            );
        }
    }
    let e = direct(&points, std::slice::from_ref(lum));
    for (k, (got, want)) in e.total.iter().zip(&want).enumerate() {
        assert!(close(*got, *want, 1e-9), "point {k}: {got} vs {want}");
    }
}

/// Frames built without a C0 hint: +x made perpendicular, or +y where the aim is along x.
#[test]
fn default_c0_and_refused_frames() {
    let p = isotropic(1.0);
    let l = Luminaire::new("a", p.clone(), [0.0; 3], [0.0, 0.0, -1.0], None, 1.0, "").unwrap();
    assert_eq!((l.c0, l.c90), ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]));
    let l = Luminaire::new("a", p.clone(), [0.0; 3], [-3.0, 0.0, 0.0], None, 1.0, "").unwrap();
    assert_eq!(l.c0, [0.0, 1.0, 0.0]);
    assert!(close_vec(cross(l.c0, l.c90), l.up()));
    let new = |aim: [f64; 3], c0: Option<[f64; 3]>, m: f64| {
        Luminaire::new("a", p.clone(), [0.0; 3], aim, c0, m, "").map(|_| ())
    };
    assert_eq!(new([0.0; 3], None, 1.0), Err(FrameError::Aim));
    assert_eq!(new([f64::NAN, 0.0, 1.0], None, 1.0), Err(FrameError::Aim));
    assert_eq!(
        new([0.0, 0.0, -1.0], Some([0.0; 3]), 1.0),
        Err(FrameError::C0)
    );
    assert_eq!(
        new([0.0, 0.0, -1.0], Some([0.0, 0.0, 5.0]), 1.0),
        Err(FrameError::C0ParallelToAim)
    );
    assert_eq!(
        new([0.0, 0.0, -1.0], None, -0.1),
        Err(FrameError::Multiplier)
    );
    assert_eq!(
        new([0.0, 0.0, -1.0], None, f64::INFINITY),
        Err(FrameError::Multiplier)
    );
    assert!(direct_illuminance(&[], &[], None, 0.0).is_err());
    assert!(direct_illuminance(&[], &[], None, f64::NAN).is_err());
}

/// An isotropic source at the ceiling (z = 3) of a room with a floor (z = 0) and a 1 × 1
/// quad at z = 1.5 centred under it. A floor point (x, y, 0) is hidden exactly when the line
/// to the source crosses z = 1.5 inside the quad, at (x/2, y/2): |x|, |y| < 1. Hidden points
/// get 0; the others E = I cos θ / d² as without the scene (bit for bit: the shadow ray
/// decides, nothing else changes). Sensors on the floor and a source on the ceiling are not
/// shadowed by those surfaces.
#[test]
fn occluding_quad_blocks_the_points_behind_it() {
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let floor = vec![
        v(-5., -5., 0.),
        v(5., -5., 0.),
        v(5., 5., 0.),
        v(-5., 5., 0.),
    ];
    let ceiling = vec![
        v(-5., -5., 3.),
        v(-5., 5., 3.),
        v(5., 5., 3.),
        v(5., -5., 3.),
    ];
    let blocker = vec![
        v(-0.5, -0.5, 1.5),
        v(0.5, -0.5, 1.5),
        v(0.5, 0.5, 1.5),
        v(-0.5, 0.5, 1.5),
    ];
    let scene = Scene::of_polygons(
        "room",
        Material::diffuse("grey", Rgb::splat(0.5)),
        vec![floor, ceiling, blocker],
    );
    let mesh = Mesh::build(&scene, MeshParams::Faces).unwrap();
    let bvh = Bvh::build(&mesh);
    let lum = down("L", isotropic(100.0), [0.0, 0.0, 3.0]);
    let xy: [(f64, f64, bool); 9] = [
        (0.0, 0.0, true),
        (0.2, 0.1, true),
        (0.9, 0.0, true),
        (-0.8, 0.8, true),
        (1.2, 0.0, false),
        (0.0, -1.3, false),
        (2.0, 0.0, false),
        (-3.0, 1.0, false),
        (4.0, 4.0, false),
    ];
    let points: Vec<SensorPoint> = xy
        .iter()
        .map(|&(x, y, _)| sensor([x, y, 0.0], [0.0, 0.0, 1.0]))
        .collect();
    let open = direct(&points, std::slice::from_ref(&lum));
    let shadowed =
        direct_illuminance(&points, std::slice::from_ref(&lum), Some(&bvh), 1.0).unwrap();
    for (k, &(x, y, hidden)) in xy.iter().enumerate() {
        let d2 = x * x + y * y + 9.0;
        let want = 100.0 * (3.0 / d2.sqrt()) / d2;
        assert!(close(open.total[k], want, 1e-12));
        if hidden {
            assert_eq!(shadowed.total[k], 0.0, "({x}, {y}) should be hidden");
        } else {
            assert_eq!(shadowed.total[k], open.total[k], "({x}, {y}) should be lit");
        }
    }
}

/// Groups in first-appearance order; each point's group values sum to its total (the total
/// is defined as that sum, so exactly); a group's column equals the result of its luminaires
/// alone; the multiplier scales linearly (to rounding: 1e-14); and the result is the same
/// bit for bit run after run.
#[test]
fn groups_and_multipliers() {
    let lam = lambertian(800.0);
    let asy = asymmetric();
    let mk = |name: &str, p: &Arc<Photometry>, at: [f64; 3], m: f64, g: &str| {
        Luminaire::new(
            name,
            p.clone(),
            at,
            [0.1, 0.2, -1.0],
            Some([1.0, 0.3, 0.0]),
            m,
            g,
        )
        .unwrap()
    };
    let lums = vec![
        mk("a1", &lam, [0.0, 0.0, 3.0], 1.0, "work"),
        mk("b1", &asy, [2.0, 1.0, 2.8], 0.7, "accent"),
        mk("a2", &lam, [3.0, -1.0, 3.0], 1.0, "work"),
        mk("c1", &asy, [-2.0, 2.0, 2.5], 1.0, "night"),
    ];
    let points: Vec<SensorPoint> = (0..50)
        .map(|k| {
            let t = k as f64;
            sensor(
                [(t * 0.37) % 5.0 - 2.0, (t * 0.61) % 4.0 - 2.0, 0.8],
                [0.1 * (t * 0.3).sin(), 0.1 * (t * 0.7).cos(), 1.0],
            )
        })
        .collect();
    let e = direct(&points, &lums);
    assert_eq!(e.groups, ["work", "accent", "night"]);
    assert_eq!(e.by_group.len(), points.len() * 3);
    for i in 0..points.len() {
        assert_eq!(e.point(i).iter().sum::<f64>(), e.total[i]);
        assert!(e.total[i] > 0.0);
    }
    for (g, name) in e.groups.iter().enumerate() {
        let own: Vec<Luminaire> = lums.iter().filter(|l| l.group == *name).cloned().collect();
        let alone = direct(&points, &own);
        for i in 0..points.len() {
            assert!(close(e.point(i)[g], alone.total[i], 1e-14));
        }
    }
    let scaled: Vec<Luminaire> = lums
        .iter()
        .map(|l| Luminaire {
            multiplier: l.multiplier * 2.5,
            ..l.clone()
        })
        .collect();
    let e2 = direct(&points, &scaled);
    for (a, b) in e.by_group.iter().zip(&e2.by_group) {
        assert!(close(*b, 2.5 * a, 1e-14));
    }
    let zero: Vec<Luminaire> = lums
        .iter()
        .map(|l| Luminaire {
            multiplier: 0.0,
            ..l.clone()
        })
        .collect();
    assert!(direct(&points, &zero).total.iter().all(|&v| v == 0.0));
    assert_eq!(direct(&points, &lums), e);
    // No luminaires: no groups, zero totals.
    let none = direct(&points, &[]);
    assert!(none.groups.is_empty() && none.by_group.is_empty());
    assert_eq!(none.total, vec![0.0; points.len()]);
}

// ---------------------------------------------------------------------------------------------
// Schedules.

const HEADER: &str = "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group";

/// A folder with `ies/a.ies` (Lambertian) and `b.ies` (asymmetric) and a schedule `s.csv`
/// of `body` under the header.
fn schedule_dir(tag: &str) -> PathBuf {
    let dir = scratch(tag);
    std::fs::create_dir_all(dir.join("ies")).unwrap();
    let lam = ies(&[0.0], &steps(0.0, 90.0, 5.0), |_, g| {
        500.0 * g.to_radians().cos()
    });
    std::fs::write(dir.join("ies/a.ies"), lam).unwrap();
    let asy = ies(&steps(0.0, 360.0, 15.0), &steps(0.0, 180.0, 15.0), asym);
    std::fs::write(dir.join("b.ies"), asy).unwrap();
    dir
}

const VALID: &str = "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group\n\
    L1,ies/a.ies,0,0,3,,,,,,,0.8,work\n\
    \"L2, wall\",b.ies,1.5,2,2.5,1,0,0,0.5,0,1,,\"accent \"\"A\"\"\"\n\
    \n\
    L3 , \"ies/a.ies\" ,4,0,3,,,,,,,,\n";

#[test]
fn schedule_reads_two_files_relative_to_its_folder() {
    let dir = schedule_dir("valid");
    let path = dir.join("s.csv");
    std::fs::write(&path, VALID).unwrap();
    let l = read_schedule(&path, Up::Z).unwrap();
    assert_eq!(l.len(), 3);
    assert_eq!(l[0].name, "L1");
    assert_eq!(l[1].name, "L2, wall");
    assert_eq!(l[2].name, "L3");
    assert_eq!(l[0].position, [0.0, 0.0, 3.0]);
    assert_eq!(l[0].nadir, [0.0, 0.0, -1.0]);
    assert_eq!(l[0].c0, [1.0, 0.0, 0.0]);
    assert_eq!(l[0].multiplier, 0.8);
    assert_eq!(l[0].group, "work");
    assert_eq!(l[1].group, "accent \"A\"");
    assert_eq!(l[1].multiplier, 1.0);
    assert!(close_vec(l[1].nadir, [1.0, 0.0, 0.0]) && close_vec(l[1].c0, [0.0, 0.0, 1.0]));
    assert_eq!(l[2].group, DEFAULT_GROUP);
    // One file read once, shared.
    assert!(Arc::ptr_eq(&l[0].photometry, &l[2].photometry));
    assert!(!Arc::ptr_eq(&l[0].photometry, &l[1].photometry));
    assert_eq!(l[0].photometry.source, "a.ies");
    assert!(close(
        l[0].intensity_towards([0.0, 0.0, -1.0]),
        0.8 * 500.0,
        1e-12
    ));
    // Up = y: the default aim is −y.
    let l = read_schedule(&path, Up::Y).unwrap();
    assert_eq!(l[0].nadir, [0.0, -1.0, 0.0]);
    assert_eq!(l[0].c0, [1.0, 0.0, 0.0]);
    assert!(close_vec(cross(l[0].c0, l[0].c90), [0.0, 1.0, 0.0]));
    // CRLF line ends and a byte-order mark read the same.
    std::fs::write(&path, format!("\u{feff}{}", VALID.replace('\n', "\r\n"))).unwrap();
    assert_eq!(read_schedule(&path, Up::Z).unwrap().len(), 3);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every hostile schedule gives one line naming `s.csv` and the line.
#[test]
fn hostile_schedules_are_located() {
    let dir = schedule_dir("hostile");
    std::fs::write(
        dir.join("bad.ies"),
        "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 x\n",
    )
    .unwrap();
    let row = "L,ies/a.ies,0,0,3,,,,,,,,";
    let cases: Vec<(String, usize, &str)> = vec![
        (String::new(), 1, "empty schedule"),
        ("\n\n".into(), 1, "empty schedule"),
        (
            "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,group,multiplier\n".into(),
            1,
            "expected exactly",
        ),
        (format!("{HEADER},extra\n{row}\n"), 1, "expected exactly"),
        (
            format!("Name{}\n{row}\n", &HEADER[4..]),
            1,
            "expected exactly",
        ),
        (format!("{HEADER}\n"), 1, "no luminaires"),
        (
            format!("{HEADER}\nL,ies/a.ies,0,0,3,,,,,,,\n"),
            2,
            "12 fields",
        ),
        (format!("{HEADER}\n{row},\n"), 2, "14 fields"),
        (
            format!("{HEADER}\nL,ies/a.ies,0,abc,3,,,,,,,,\n"),
            2,
            "'abc' is not a number",
        ),
        (
            format!("{HEADER}\nL,ies/a.ies,0,0,NaN,,,,,,,,\n"),
            2,
            "not a finite number",
        ),
        (
            format!("{HEADER}\nL,ies/a.ies,0,0,,,,,,,,,\n"),
            2,
            "give all three",
        ),
        (format!("{HEADER}\nL,ies/a.ies,,,,,,,,,,,\n"), 2, "position"),
        (
            format!("{HEADER}\nL,ies/a.ies,0,0,3,,,,,,,inf,\n"),
            2,
            "not a finite number",
        ),
        (
            format!("{HEADER}\nL,ies/a.ies,0,0,3,,,,,,,-1,\n"),
            2,
            "negative",
        ),
        (
            format!("{HEADER}\nL,ies/a.ies,0,0,3,0,0,0,,,,,\n"),
            2,
            "aim",
        ),
        (
            format!("{HEADER}\nL,ies/a.ies,0,0,3,0,0,1,,,,,\n\n"),
            2,
            "ok",
        ),
        (
            format!("{HEADER}\nL,ies/a.ies,0,0,3,1,,0,,,,,\n"),
            2,
            "give all three",
        ),
        (
            format!("{HEADER}\nL,ies/a.ies,0,0,3,0,0,-1,0,0,2,,\n"),
            2,
            "parallel",
        ),
        (
            format!("{HEADER}\nL,ies/a.ies,0,0,3,,,,0,0,0,,\n"),
            2,
            "C0 direction is zero",
        ),
        (
            format!("{HEADER}\n{row}\n\n{row}\n"),
            4,
            "already used at line 2",
        ),
        (
            format!("{HEADER}\n,ies/a.ies,0,0,3,,,,,,,,\n"),
            2,
            "name is empty",
        ),
        (format!("{HEADER}\nL,,0,0,3,,,,,,,,\n"), 2, "file is empty"),
        (
            format!("{HEADER}\n{row}\nM,nope.ies,0,0,3,,,,,,,,\n"),
            3,
            "nope.ies: cannot read",
        ),
        (
            format!("{HEADER}\nM,ies/a.txt,0,0,3,,,,,,,,\n"),
            2,
            "a.txt: not a photometric",
        ),
        (
            format!("{HEADER}\nM,bad.ies,0,0,3,,,,,,,,\n"),
            2,
            "bad.ies:",
        ),
        (
            format!("{HEADER}\n\"L,ies/a.ies,0,0,3,,,,,,,,\n"),
            2,
            "no closing quote",
        ),
        (
            format!("{HEADER}\n\"L\"x,ies/a.ies,0,0,3,,,,,,,,\n"),
            2,
            "after its closing quote",
        ),
        (
            format!("{HEADER}\nL\"x,ies/a.ies,0,0,3,,,,,,,,\n"),
            2,
            "quote inside",
        ),
        (
            format!("{HEADER}\r\n\r\n{row}\r\n\r\nL,b.ies,0,0,3,,,,,,,,\r\n"),
            5,
            "already used at line 3",
        ),
        (
            format!("{HEADER}\r{row}\rX,ies/a.ies,0,0,3,1e400,0,0,,,,,\r"),
            3,
            "not a finite number",
        ),
    ];
    let path = dir.join("s.csv");
    for (text, line, needle) in &cases {
        std::fs::write(&path, text).unwrap();
        let result = read_schedule(&path, Up::Z);
        if *needle == "ok" {
            // An aim straight up is allowed (an uplight).
            assert!(result.is_ok(), "{text:?}: {result:?}");
            continue;
        }
        let err = result.expect_err(text).to_string();
        assert!(
            err.starts_with(&format!("s.csv:{line}: ")),
            "{text:?}: {err}"
        );
        assert!(err.contains(needle), "{text:?}: {err}");
        assert!(!err.contains('\n') && !err.contains('\r'), "{err:?}");
    }
    // The photometric file's own place comes after the schedule's.
    std::fs::write(&path, format!("{HEADER}\nM,bad.ies,0,0,3,,,,,,,,\n")).unwrap();
    let err = read_schedule(&path, Up::Z).unwrap_err();
    assert_eq!(err.line(), Some(2));
    assert!(err.to_string().contains("bad.ies:3:"), "{err}");
    // A missing photometric file: the chain goes on to the operating system's reason and
    // repeats nothing.
    std::fs::write(&path, format!("{HEADER}\nM,nope.ies,0,0,3,,,,,,,,\n")).unwrap();
    let err = read_schedule(&path, Up::Z).unwrap_err();
    let mut chain = vec![err.to_string()];
    let mut next = std::error::Error::source(&err);
    while let Some(e) = next {
        chain.push(e.to_string());
        next = e.source();
    }
    assert_eq!(chain.len(), 2, "{chain:?}");
    assert_eq!(chain[0], "s.csv:2: nope.ies: cannot read the file");
    assert!(!chain[0].contains(&chain[1]), "{chain:?}");
    // A schedule that is not there names itself.
    let err = read_schedule(&dir.join("missing.csv"), Up::Z).unwrap_err();
    assert!(err.to_string().starts_with("missing.csv: "), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The valid schedule cut at every byte: an error or a shorter schedule, never a panic, and
/// every error one line at a line that exists.
#[test]
fn truncated_schedules_never_panic() {
    let dir = schedule_dir("truncated");
    let path = dir.join("s.csv");
    let bytes = VALID.as_bytes();
    let lines = VALID.lines().count();
    for cut in 0..=bytes.len() {
        std::fs::write(&path, &bytes[..cut]).unwrap();
        match read_schedule(&path, Up::Z) {
            Ok(l) => assert!(!l.is_empty() && l.len() <= 3),
            Err(e) => {
                let s = e.to_string();
                assert!(s.starts_with("s.csv:") && !s.contains('\n'), "{cut}: {s}");
                assert!(e.line().is_some_and(|l| l >= 1 && l <= lines), "{cut}: {s}");
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------------
// Points.

#[test]
fn points_round_trip() {
    let dir = scratch("points");
    let path = dir.join("grid.pts");
    let points = vec![
        sensor([0.0, 0.0, 0.8], [0.0, 0.0, 1.0]),
        sensor([-123.456, 1e-7, 1e30], [0.3, -0.4, 0.5]),
        sensor([0.1, 0.2, 0.3], [1.0, 1.0, 1.0]),
        sensor([5e-324, -0.0, 7.0], [0.0, -2.0, 0.0]),
    ];
    write_points(&path, &points).unwrap();
    let back = read_points(&path).unwrap();
    assert_eq!(back.len(), points.len());
    for (a, b) in points.iter().zip(&back) {
        assert_eq!(a.position, b.position);
        // Renormalising a unit vector moves it by at most an ulp or two.
        assert!((0..3).all(|k| (a.normal[k] - b.normal[k]).abs() <= 4.0 * f64::EPSILON));
    }
    // Comments, blank lines, CRLF, tabs; directions normalised.
    std::fs::write(
        &path,
        "# a grid\r\n\r\n1 2 3 0 0 2 # up\r\n\t4  5 6\t0 -3 0\r\n   # nothing\n",
    )
    .unwrap();
    let p = read_points(&path).unwrap();
    assert_eq!(p.len(), 2);
    assert_eq!(p[0], sensor([1.0, 2.0, 3.0], [0.0, 0.0, 1.0]));
    assert_eq!(p[1].normal, [0.0, -1.0, 0.0]);
    // An empty file is an empty grid.
    std::fs::write(&path, "").unwrap();
    assert!(read_points(&path).unwrap().is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn hostile_points_are_located() {
    let dir = scratch("points-hostile");
    let path = dir.join("grid.pts");
    let cases: [(&str, usize, &str); 8] = [
        ("0 0 0 0 0\n", 1, "5 numbers"),
        ("0 0 0 0 0 1\n0 0 0 0 0 1 1\n", 2, "7 numbers"),
        ("# c\n\n0 0 x 0 0 1\n", 3, "'x' is not a number"),
        ("0 0 0 0 0 1\n0 NaN 0 0 0 1\n", 2, "not a finite number"),
        ("0 0 0 0 0 0\n", 1, "direction"),
        ("0 0 0 1e-320 0 0\n", 1, "ok"),
        ("0 0 0 1e308 1e308 1e308\n", 1, "ok"),
        ("1,2,3,0,0,1\n", 1, "1 numbers"),
    ];
    for (text, line, needle) in cases {
        std::fs::write(&path, text).unwrap();
        let result = read_points(&path);
        if needle == "ok" {
            // Tiny and huge directions normalise (scaled by their largest component first).
            let p = result.unwrap();
            assert!(p[0].normal.iter().all(|v| v.is_finite()));
            assert!((norm(p[0].normal) - 1.0).abs() < 1e-15);
            continue;
        }
        let err = result.unwrap_err().to_string();
        assert!(
            err.starts_with(&format!("grid.pts:{line}: ")),
            "{text:?}: {err}"
        );
        assert!(err.contains(needle), "{text:?}: {err}");
        assert!(!err.contains('\n'));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------------
// The near field.

/// A Lambertian panel: I₀ cos γ below, a square luminous opening of side `a` metres.
fn panel(i0: f64, a: f64) -> Arc<Photometry> {
    let text = ies(&[0.0], &steps(0.0, 180.0, 1.0), |_, g| {
        if g <= 90.0 {
            (i0 * g.to_radians().cos()).max(0.0)
        } else {
            0.0
        }
    })
    .replace("1 2 0 0 0\n", &format!("1 2 {a} {a} 0\n"));
    parse(&text, "panel.ies")
}

/// Under the centre of a Lambertian square panel of side a at height h, E = 4 × the corner
/// value of an (a/2)² rectangle, E_corner = (L/2)[X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²)
/// atan(X/√(1+Y²))], X = Y = a/(2h), L = I₀/a² (the configuration factor of a differential
/// area to a parallel rectangle, Howell's catalogue, times πL). At h = a the point law is 33 %
/// off; the opening split into cells must match to 1 % (midpoint rule, 10 × 10 cells and
/// the table's 1° steps). Far away (h ≥ 5a) the point law is used as is.
#[test]
fn a_large_opening_is_integrated_in_the_near_field() {
    let (i0, a) = (1000.0, 1.2);
    let l = down("panel", panel(i0, a), [0.0, 0.0, 0.0]);
    let lum = i0 / (a * a);
    let closed = |h: f64| {
        let x: f64 = a / 2.0 / h;
        let q = x / (1.0 + x * x).sqrt() * (x / (1.0 + x * x).sqrt()).atan();
        4.0 * lum / 2.0 * 2.0 * q
    };
    for h in [0.6, 1.2, 2.4] {
        let p = sensor([0.0, 0.0, -h], [0.0, 0.0, 1.0]);
        let e = direct_illuminance(&[p], std::slice::from_ref(&l), None, 1.0)
            .unwrap()
            .total[0];
        let want = closed(h);
        assert!(
            close(e, want, 0.01),
            "h = {h}: {e} lux, closed form {want} lux"
        );
        if h <= 1.2 {
            let point = i0 / (h * h);
            assert!(
                (point - want).abs() > 0.1 * want,
                "h = {h}: the point law is close"
            );
        }
    }
    // Far: exactly the point law.
    let h = 10.0;
    let p = sensor([0.0, 0.0, -h], [0.0, 0.0, 1.0]);
    let e = direct_illuminance(&[p], std::slice::from_ref(&l), None, 1.0)
        .unwrap()
        .total[0];
    assert!(close(e, i0 / (h * h), 1e-12), "{e}");
}

//! Daylight against closed forms: the sky through a roof opening (the configuration factor),
//! the sun's footprint, glazing, and the daylight coefficients' linearity.

use super::*;
use crate::lighting::sky::SkyModel;
use crate::mesh::MeshParams;
use crate::sampling::{stream, uniform};
use crate::scene::Material;
use std::f64::consts::PI;

/// A `w × d × h` room (metres, z up) of reflectance `rho`, its ceiling open over
/// `[x0, x1] × [y0, y1]`; with `pane` the opening is glazed with that normal transmittance.
fn roof_room(
    (w, d, h): (f32, f32, f32),
    [x0, x1, y0, y1]: [f32; 4],
    rho: f64,
    pane: Option<f64>,
) -> Scene {
    let v = Vec3::new;
    let mut faces = vec![
        vec![v(0., 0., 0.), v(w, 0., 0.), v(w, d, 0.), v(0., d, 0.)],
        vec![v(0., 0., 0.), v(0., 0., h), v(w, 0., h), v(w, 0., 0.)],
        vec![v(0., d, 0.), v(w, d, 0.), v(w, d, h), v(0., d, h)],
        vec![v(0., 0., 0.), v(0., d, 0.), v(0., d, h), v(0., 0., h)],
        vec![v(w, 0., 0.), v(w, 0., h), v(w, d, h), v(w, d, 0.)],
    ];
    // The ceiling, facing down, as four rectangles round the opening.
    let rect = |a0: f32, a1: f32, b0: f32, b1: f32| {
        vec![v(a0, b0, h), v(a0, b1, h), v(a1, b1, h), v(a1, b0, h)]
    };
    faces.push(rect(0., w, 0., y0));
    faces.push(rect(0., w, y1, d));
    faces.push(rect(0., x0, y0, y1));
    faces.push(rect(x1, w, y0, y1));
    let mut scene = Scene::of_polygons("roof", Material::diffuse("wall", Rgb::splat(rho)), faces);
    if let Some(t) = pane {
        let mut glass = Material::diffuse("glass", Rgb::BLACK);
        glass.transmittance = t;
        scene.materials.push(glass);
        let mut p = scene.polygons[0].clone();
        p.vertices = rect(x0, x1, y0, y1);
        p.material = 1;
        scene.polygons.push(p);
    }
    scene
}

/// Floor points facing up on a grid of spacing `step` from `start`.
fn floor(w: f64, d: f64, start: f64, step: f64) -> Vec<SensorPoint> {
    let mut out = Vec::new();
    let mut x = start;
    while x < w {
        let mut y = start;
        while y < d {
            out.push(SensorPoint::new([x, y, 0.0], [0.0, 0.0, 1.0]).unwrap());
            y += step;
        }
        x += step;
    }
    out
}

/// The configuration factor from a point facing up to a parallel rectangle `[x0, x1] × [y0,
/// y1]` at height `h` above it (Howell's catalogue, B-3: element to a parallel rectangle with a
/// corner above it, superposed with signs).
fn cf(p: [f64; 2], [x0, x1, y0, y1]: [f64; 4], h: f64) -> f64 {
    let f = |a: f64, b: f64| {
        let (a, b) = (a / h, b / h);
        let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
        (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * PI)
    };
    let (dx0, dx1, dy0, dy1) = (x0 - p[0], x1 - p[0], y0 - p[1], y1 - p[1]);
    f(dx1, dy1) - f(dx0, dy1) - f(dx1, dy0) + f(dx0, dy0)
}

fn settings(patches: usize) -> DaylightSettings {
    DaylightSettings {
        lighting: LightingSettings {
            mesh: MeshParams::Patches(patches),
            ..LightingSettings::default()
        },
        ..DaylightSettings::default()
    }
}

/// A uniform sky of luminance L through a roof opening into a black room: the illuminance
/// at each floor point is πL × its configuration factor to the opening. 65,536 stratified
/// rays a point: only the strata on the opening's outline vary (each by at most ½ a
/// stratum), so the error is about √(strata on the outline)/2 strata, a few parts in 1e4 of
/// the hemisphere, well under 1 % of the smallest factor here (0.027, a corner point).
#[test]
fn a_uniform_sky_through_a_roof_opening_is_pi_l_times_the_configuration_factor() {
    let (w, d, h) = (6.0, 5.0, 3.0);
    let hole = [2.0, 4.0, 1.5, 3.0];
    let scene = roof_room(
        (w as f32, d as f32, h as f32),
        hole.map(|x| x as f32),
        0.0,
        None,
    );
    let points = floor(w, d, 0.5, 1.0);
    let sky = Sky::new(SkyModel::Uniform, None, 10_000.0).unwrap();
    let mut s = settings(400);
    s.point_rays = 65_536;
    let r = daylight(&scene, &points, &sky, None, &s, &crate::observe::Silent).unwrap();
    let l = sky.zenith_luminance;
    assert!((l - 10_000.0 / PI).abs() < 1e-6);
    let mut worst = 0.0f64;
    for (i, p) in points.iter().enumerate() {
        let want = PI * l * cf([p.position[0], p.position[1]], hole, h);
        let got = r.total[i];
        assert_eq!(got, r.direct[i], "a black room reflects nothing");
        worst = worst.max((got - want).abs() / want);
        assert!(
            (got - want).abs() < 0.01 * want,
            "point {:?}: {got} lx, πL·F = {want} lx",
            p.position
        );
        let df = 100.0 * want / 10_000.0;
        assert!((r.daylight_factor[i] - df).abs() < 0.01 * df);
    }
    assert!(worst < 0.01, "{worst}");
    eprintln!("roof opening, uniform sky: worst relative error {worst:.2e}");
}

/// `point_refine` (`--sky-refine`) keeps the sky component: the same roof opening, open and
/// glazed (τ(θ), so that the panes' branches are refined too), at 65,536 strata refined 4
/// (one ray per 16 strata where nothing outside is near, the full density at the opening).
/// Open: within 1 % of πL × the configuration factor at every point, as the unrefined run
/// (the outline's strata vary by up to half a stratum each), and no worse in RMS than it by
/// more than a quarter; glazed: within 1 % of the unrefined run.
#[test]
fn refined_sky_strata_keep_the_sky_component() {
    let (w, d, h) = (6.0, 5.0, 3.0);
    let hole = [2.0, 4.0, 1.5, 3.0];
    let sky = Sky::new(SkyModel::Uniform, None, 10_000.0).unwrap();
    for pane in [None, Some(0.8)] {
        let scene = roof_room(
            (w as f32, d as f32, h as f32),
            hole.map(|x| x as f32),
            0.0,
            pane,
        );
        let points = floor(w, d, 0.5, 1.0);
        let mut s = settings(400);
        s.point_rays = 65_536;
        let plain = daylight(&scene, &points, &sky, None, &s, &crate::observe::Silent).unwrap();
        s.point_refine = 4;
        let refined = daylight(&scene, &points, &sky, None, &s, &crate::observe::Silent).unwrap();
        let (mut rms_plain, mut rms_refined) = (0.0, 0.0);
        for (i, p) in points.iter().enumerate() {
            let (a, b) = (plain.total[i], refined.total[i]);
            if pane.is_some() {
                assert!((a - b).abs() < 0.01 * a, "{:?}: {a} {b}", p.position);
                continue;
            }
            let want = PI * sky.zenith_luminance * cf([p.position[0], p.position[1]], hole, h);
            assert!(
                (b - want).abs() < 0.01 * want,
                "{:?}: {b} {want}",
                p.position
            );
            rms_plain += ((a - want) / want).powi(2);
            rms_refined += ((b - want) / want).powi(2);
        }
        assert!(
            rms_refined <= 1.25f64.powi(2) * rms_plain,
            "{rms_refined} {rms_plain}"
        );
    }
    s_refine_is_validated();
}

/// A refinement outside 1 … 16 is refused, naming the setting.
fn s_refine_is_validated() {
    for bad in [0, 17] {
        let s = DaylightSettings {
            point_refine: bad,
            ..DaylightSettings::default()
        };
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains("sky refinement"), "{e}");
    }
}

/// The sun at 60° above the east (azimuth 90°, +x in a z-up scene) through a 1 m square roof
/// opening 3 m above a black floor, no sky: the points in the opening's shadow-cast footprint
/// (shifted 3/tan 60° = 1.732 m west, towards −x) get E_n sin 60° (to the disc's own
/// averaging of cos θ, 1e-5), every other point exactly 0. With north turned 90°
/// counter-clockwise (north along −x) the same sun at azimuth 0 shifts the footprint east.
#[test]
fn the_sun_lights_exactly_its_footprint() {
    let (w, d, h) = (6.0f64, 6.0f64, 3.0f64);
    let hole = [2.5, 3.5, 2.5, 3.5];
    let scene = roof_room(
        (w as f32, d as f32, h as f32),
        hole.map(|x| x as f32),
        0.0,
        None,
    );
    let points = floor(w, d, 0.05, 0.2);
    let dark = Sky::new(SkyModel::Uniform, None, 0.0).unwrap();
    let en = 80_000.0;
    let shift = h / 60f64.to_radians().tan();
    for (north, azimuth, dx) in [(0.0, 90.0, -shift), (90.0, 0.0, shift)] {
        let mut s = settings(200);
        s.frame = SkyFrame::new(false, north).unwrap();
        let sun = SunPosition::new(60.0, azimuth).unwrap();
        let r = daylight(
            &scene,
            &points,
            &dark,
            Some((sun, en)),
            &s,
            &crate::observe::Silent,
        )
        .unwrap();
        let want = en * 60f64.to_radians().sin();
        let mut lit = 0;
        for (i, p) in points.iter().enumerate() {
            let [x, y, _] = p.position;
            let inside = x > hole[0] + dx && x < hole[1] + dx && y > hole[2] && y < hole[3];
            let e = r.total[i];
            if inside {
                lit += 1;
                assert!((e - want).abs() < 1e-4 * want, "{x},{y}: {e} {want}");
            } else {
                assert_eq!(e, 0.0, "{x},{y} outside the footprint");
            }
        }
        assert_eq!(lit, 25, "the footprint holds 5 × 5 points");
    }
}

/// The same sun through a glazed opening: the footprint gets E_n sin 60° τ(30°), the pane's
/// transmittance at the incidence angle (30° from the pane's normal).
#[test]
fn glazing_passes_the_sun_at_its_angular_transmittance() {
    let (w, d, h) = (6.0f64, 6.0f64, 3.0f64);
    let hole = [2.5, 3.5, 2.5, 3.5];
    let tau_n = 0.8;
    let scene = roof_room(
        (w as f32, d as f32, h as f32),
        hole.map(|x| x as f32),
        0.0,
        Some(tau_n),
    );
    let points =
        vec![SensorPoint::new([3.0 - h / 3f64.sqrt(), 3.0, 0.0], [0.0, 0.0, 1.0]).unwrap()];
    let dark = Sky::new(SkyModel::Uniform, None, 0.0).unwrap();
    let sun = SunPosition::new(60.0, 90.0).unwrap();
    let r = daylight(
        &scene,
        &points,
        &dark,
        Some((sun, 1000.0)),
        &settings(200),
        &crate::observe::Silent,
    )
    .unwrap();
    let g = Glazing::new(tau_n, GLASS_INDEX).unwrap();
    let want = 1000.0 * 60f64.to_radians().sin() * g.transmittance(30f64.to_radians().cos());
    assert!(
        (r.total[0] - want).abs() < 1e-4 * want,
        "{} {want}",
        r.total[0]
    );
    assert!(g.transmittance(30f64.to_radians().cos()) < tau_n);
}

/// A sky split into 6 bands × 8 azimuth sectors of unit luminance: the coefficients times a
/// uniform luminance L reproduce the direct solve under a uniform sky of luminance L (same
/// strata, same rays, the ground's luminance summed over the patches) to 1e-6, the
/// interreflection included (solved to 1e-9 and gathered along the same rays for every
/// column); and a sun's coefficient times E_n is the solve's sun group.
#[test]
fn daylight_coefficients_reproduce_a_direct_solve() {
    let (w, d, h) = (4.0f64, 4.0f64, 3.0f64);
    let scene = roof_room(
        (w as f32, d as f32, h as f32),
        [1.5, 2.5, 1.0, 3.0],
        0.5,
        None,
    );
    let points = floor(w, d, 0.5, 1.0);
    let mut s = settings(150);
    s.lighting.params.tolerance = 1e-10;
    s.lighting.gather.indirect = 32;
    s.point_rays = 1024;
    s.patch_rays = 256;
    let mut sources = Vec::new();
    for band in 0..6 {
        for sector in 0..8 {
            let a = 15.0 * band as f64;
            let z = 45.0 * sector as f64 + 10.0;
            sources.push(DaylightSource::Patch {
                altitude: [a, a + 15.0],
                azimuth: [z, z + 45.0],
            });
        }
    }
    let sun = SunPosition::new(70.0, 200.0).unwrap();
    sources.push(DaylightSource::Sun(sun));
    let dc = daylight_coefficients(&scene, &points, &sources, &s, &crate::observe::Silent).unwrap();
    let sky = Sky::new(SkyModel::Uniform, None, 10_000.0).unwrap();
    let l = sky.zenith_luminance;
    let en = 50_000.0;
    let r = daylight(
        &scene,
        &points,
        &sky,
        Some((sun, en)),
        &s,
        &crate::observe::Silent,
    )
    .unwrap();
    let mut values = vec![l; 48];
    values.push(0.0);
    let from_dc = dc.apply(&values);
    let dc_direct: Vec<f64> = dc
        .direct
        .chunks_exact(dc.sources)
        .map(|row| row.iter().zip(&values).map(|(c, v)| c * v).sum())
        .collect();
    let mut sun_only = vec![0.0; 48];
    sun_only.push(en);
    let sun_dc = dc.apply(&sun_only);
    for i in 0..points.len() {
        assert!(from_dc[i] > dc_direct[i], "the walls reflect");
        let want = r.by_group[2 * i];
        assert!(
            (from_dc[i] - want).abs() < 1e-6 * want,
            "point {i}: {} {want}",
            from_dc[i]
        );
        let want = r.by_group[2 * i + 1];
        assert!(
            (sun_dc[i] - want).abs() < 1e-6 * want.max(1.0),
            "sun at point {i}: {} {want}",
            sun_dc[i]
        );
    }
    // The patches tile the sky: their horizontal illuminances add up to π.
    let sum: f64 = sources[..48].iter().map(|s| s.horizontal()).sum();
    assert!((sum - PI).abs() < 1e-12, "{sum}");
}

/// A uniform sky of luminance L seen through an opening is a Lambertian source of exitance
/// πL filling the opening: the daylight pipeline in a grey room (ρ = 0.5) against the
/// luminaire pipeline with the opening an emitting polygon of πL facing in. Both are Monte
/// Carlo over the same mesh (its rows 256 rays, the gathers a few hundred samples): the
/// room's mean illuminance over the floor points agrees to 2 %.
#[test]
fn a_uniform_sky_is_an_emitting_opening() {
    let (w, d, h) = (4.0f32, 4.0f32, 3.0f32);
    let hole = [1.5f32, 2.5, 1.0, 3.0];
    let rho = 0.5;
    let scene = roof_room((w, d, h), hole, rho, None);
    let points = floor(w as f64, d as f64, 0.25, 0.5);
    let sky = Sky::new(SkyModel::Uniform, None, 10_000.0).unwrap();
    let mut s = settings(600);
    s.point_rays = 4096;
    let r = daylight(&scene, &points, &sky, None, &s, &crate::observe::Silent).unwrap();
    let mut lamp = scene.clone();
    lamp.materials.push(Material::emitter(
        "sky",
        Rgb::BLACK,
        Rgb::splat(PI * sky.zenith_luminance),
    ));
    let mut p = lamp.polygons[0].clone();
    let [x0, x1, y0, y1] = hole;
    // Facing down into the room.
    p.vertices = vec![
        Vec3::new(x0, y0, h),
        Vec3::new(x0, y1, h),
        Vec3::new(x1, y1, h),
        Vec3::new(x1, y0, h),
    ];
    p.material = 1;
    lamp.polygons.push(p);
    let mut ls = s.lighting;
    ls.mesh = MeshParams::Patches(600);
    ls.gather.direct = 64;
    let e = super::super::lighting(&lamp, &[], &points, &ls, &crate::observe::Silent).unwrap();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (a, b) = (mean(&r.total), mean(&e.total));
    assert!(
        (a - b).abs() < 0.02 * b,
        "daylight {a} lx, emitting opening {b} lx"
    );
    // And the interreflection is a sizeable part of it.
    assert!(mean(&r.direct) < 0.85 * a);
}

/// A glTF material with `KHR_materials_transmission` (factor 0.9, white) and
/// `KHR_materials_ior` 1.5 is a pane of 0.9 × (1 − r₀)/(1 + r₀), r₀ = 0.04, of index 1.5.
#[test]
fn a_gltf_transmission_material_is_a_pane() {
    use base64::Engine as _;
    let pos: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&pos)
    );
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"material":0}}]}}],
"materials":[{{"name":"glass","pbrMetallicRoughness":{{"baseColorFactor":[1,1,1,1]}},
"extensions":{{"KHR_materials_transmission":{{"transmissionFactor":0.9}},"KHR_materials_ior":{{"ior":1.5}}}}}}],
"extensionsUsed":["KHR_materials_transmission","KHR_materials_ior"],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],"buffers":[{{"byteLength":36,"uri":"{uri}"}}]}}"#
    );
    let dir = std::env::temp_dir().join(format!("radiosity-pane-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("pane.gltf");
    std::fs::write(&path, json).unwrap();
    let scene = crate::scene::gltf::load_with(&path, false).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let m = scene.materials.iter().find(|m| m.name == "glass").unwrap();
    let want = 0.9 * 0.96 / 1.04;
    assert!((m.transmittance - want).abs() < 1e-6, "{}", m.transmittance);
    assert_eq!(m.ior, Some(1.5));
    let g = Glazing::new(m.transmittance, 1.5).unwrap();
    assert!((g.transmittance(1.0) - m.transmittance).abs() < 1e-12);
}

/// [`DirectSun`] is the sun column's direct light for any position: through the glazed roof
/// opening the footprint point gets E_n sin 60° τ(30°) per unit E_n, a point outside the
/// footprint nothing, and the same position asked twice gives the same values.
#[test]
fn direct_sun_lights_the_footprint_through_the_pane() {
    let (w, d, h) = (6.0f64, 6.0f64, 3.0f64);
    let scene = roof_room(
        (w as f32, d as f32, h as f32),
        [2.5, 3.5, 2.5, 3.5],
        0.5,
        Some(0.8),
    );
    let points = vec![
        SensorPoint::new([3.0 - h / 3f64.sqrt(), 3.0, 0.0], [0.0, 0.0, 1.0]).unwrap(),
        SensorPoint::new([5.0, 5.0, 0.0], [0.0, 0.0, 1.0]).unwrap(),
    ];
    let ds = DirectSun::new(&scene, &points, &settings(200)).unwrap();
    let to_sun = SunPosition::new(60.0, 90.0).unwrap().direction();
    let mut e = vec![0.0; 2];
    ds.illuminance(to_sun, &mut e);
    let g = Glazing::new(0.8, GLASS_INDEX).unwrap();
    let want = 60f64.to_radians().sin() * g.transmittance(30f64.to_radians().cos());
    assert!((e[0] - want).abs() < 1e-4 * want, "{} {want}", e[0]);
    assert_eq!(e[1], 0.0);
    let mut again = vec![0.0; 2];
    ds.illuminance(to_sun, &mut again);
    assert_eq!(e, again);
}

/// The whole-disc decisions (`sun_cone`) change no point's direct sun beyond the pane's
/// transmittance varying over the disc: a glazed roof opening with an opaque mullion across
/// it, 30 sun positions, 3,600 floor points (and a week of suns by groups). Where a pane is crossed, the decided value is
/// cos θ τ(centre) and the sampled one cos θ times the mean of τ over 16 directions within
/// 0.27° of it (|dτ/dθ| < 0.5 a radian at these angles: under 2.5·10⁻³ of 1 lx); elsewhere
/// the two are bit for bit equal. Most points are decided whole.
#[test]
fn whole_disc_decisions_match_the_sampled_disc() {
    let (w, d, h) = (6.0f64, 6.0f64, 3.0f64);
    let mut scene = roof_room(
        (w as f32, d as f32, h as f32),
        [2.0, 4.0, 2.0, 4.0],
        0.5,
        Some(0.8),
    );
    let v = Vec3::new;
    let mut bar = scene.polygons[0].clone();
    bar.material = 0;
    bar.vertices = vec![
        v(2.9, 2.0, 2.9),
        v(2.9, 4.0, 2.9),
        v(3.1, 4.0, 2.9),
        v(3.1, 2.0, 2.9),
    ];
    scene.polygons.push(bar);
    let points = floor(w, d, 0.05, 0.1);
    let ds = DirectSun::new(&scene, &points, &settings(200)).unwrap();
    let sampled = DirectSun::new(&scene, &points, &settings(200))
        .unwrap()
        .sampled_only();
    let mut rng = stream(5, 8, 0, 0);
    let (mut a, mut b) = (vec![0.0; points.len()], vec![0.0; points.len()]);
    let (mut same, mut lit) = (0usize, 0usize);
    for _ in 0..30 {
        let alt = 25.0 + 60.0 * uniform(&mut rng) as f64;
        let az = 360.0 * uniform(&mut rng) as f64;
        let to_sun = SunPosition::new(alt, az).unwrap().direction();
        ds.illuminance(to_sun, &mut a);
        sampled.illuminance(to_sun, &mut b);
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 2.5e-3, "{x} {y} at {alt}°, {az}°");
            same += (x == y) as usize;
            lit += (*y > 0.0) as usize;
        }
    }
    let n = 30 * points.len();
    assert!(lit > n / 20, "{lit} of {n} points lit");
    // Point by point through many suns (each point's cache carried from sun to sun) gives
    // every value of the sun-by-sun calls, bit for bit; a missing sun gives 0.
    let suns: Vec<Option<[f64; 3]>> = (0..12)
        .map(|k| {
            (k % 5 != 4).then(|| {
                SunPosition::new(30.0 + 4.0 * k as f64, 100.0 + 13.0 * k as f64)
                    .unwrap()
                    .direction()
            })
        })
        .collect();
    let mut many = vec![1.0; points.len() * suns.len()];
    ds.illuminance_many(&suns, &mut many);
    for (h, s) in suns.iter().enumerate() {
        match s {
            Some(d) => ds.illuminance(*d, &mut a),
            None => a.fill(0.0),
        }
        for (i, x) in a.iter().enumerate() {
            assert_eq!(many[i * suns.len() + h], *x, "point {i}, sun {h}");
        }
    }
    // A week of suns at five hours of the day, each hour's within about 2° (the groups that
    // are decided whole, `sun_cone::SunGroups`): the same values, bit for bit.
    let week: Vec<Option<[f64; 3]>> = (0..35)
        .map(|k| {
            let (hour, day) = ((k / 7) as f64, (k % 7) as f64);
            Some(
                SunPosition::new(
                    35.0 + 10.0 * hour + 0.3 * day,
                    110.0 + 30.0 * hour + 0.2 * day,
                )
                .unwrap()
                .direction(),
            )
        })
        .collect();
    let mut many = vec![1.0; points.len() * week.len()];
    ds.illuminance_many(&week, &mut many);
    let mut lit_week = 0;
    for (h, s) in week.iter().enumerate() {
        ds.illuminance(s.unwrap(), &mut a);
        for (i, x) in a.iter().enumerate() {
            assert_eq!(many[i * week.len() + h], *x, "point {i}, sun {h}");
            lit_week += (*x > 0.0) as usize;
        }
    }
    assert!(lit_week > week.len() * points.len() / 20, "{lit_week}");
    // Unlit points decided whole are exactly 0; the rest differ by τ's spread only.
    assert!(same > n / 2, "{same} of {n}");
}

/// The block Jacobi solve against Gaussian elimination of (I − ρ F) B = E, channel by channel
/// and column by column, on a random sparse F (rows summing to 0.5…0.95) of 40 patches, 7
/// columns in blocks of 3 (the last block short): tolerance 10⁻¹³ on the unshot flux leaves
/// B within 10⁻¹¹ of the exact solution. A column of zeros stays zero; a tolerance of 0.5
/// stops after the first sweeps with the unshot flux bound met.
#[test]
fn block_jacobi_solves_every_column() {
    let n = 40;
    let mut rng = crate::sampling::stream(3, 5, 0, 0);
    let mut u = || uniform(&mut rng) as f64;
    let rows: Vec<Vec<(u32, f32)>> = (0..n)
        .map(|i| {
            let mut r: Vec<(u32, f32)> = Vec::new();
            for j in (0..n).filter(|&j| j != i) {
                if u() < 0.3 {
                    r.push((j as u32, u() as f32));
                }
            }
            let sum: f32 = r.iter().map(|e| e.1).sum();
            let target = (0.5 + 0.45 * u()) as f32;
            for e in &mut r {
                e.1 *= target / sum.max(1e-6);
            }
            r
        })
        .collect();
    let f = crate::system::SparseMatrix::from_rows(rows.clone());
    let rho: Vec<Rgb> = (0..n)
        .map(|_| Rgb::new(0.9 * u(), 0.9 * u(), 0.9 * u()))
        .collect();
    let area: Vec<f64> = (0..n).map(|_| 0.5 + u()).collect();
    let m = 7;
    let first: Vec<f64> = (0..n * m)
        .map(|k| if k % m == 4 { 0.0 } else { 10.0 * u() })
        .collect();
    // The exact B: (I − ρ_c F) B = ρ_c E by Gaussian elimination with partial pivoting.
    let exact = |c: usize, ch: usize| -> Vec<f64> {
        let rc = |i: usize| rho[i].to_array()[ch];
        let mut a = vec![0.0; n * (n + 1)];
        for i in 0..n {
            a[i * (n + 1) + i] = 1.0;
            for &(j, fij) in &rows[i] {
                a[i * (n + 1) + j as usize] -= rc(i) * fij as f64;
            }
            a[i * (n + 1) + n] = rc(i) * first[i * m + c];
        }
        for k in 0..n {
            let p = (k..n)
                .max_by(|&x, &y| {
                    a[x * (n + 1) + k]
                        .abs()
                        .total_cmp(&a[y * (n + 1) + k].abs())
                })
                .unwrap();
            for col in 0..=n {
                a.swap(k * (n + 1) + col, p * (n + 1) + col);
            }
            for i in 0..n {
                if i != k {
                    let q = a[i * (n + 1) + k] / a[k * (n + 1) + k];
                    for col in k..=n {
                        a[i * (n + 1) + col] -= q * a[k * (n + 1) + col];
                    }
                }
            }
        }
        (0..n)
            .map(|i| a[i * (n + 1) + n] / a[i * (n + 1) + i])
            .collect()
    };
    let block = 3;
    let mut work = BlockJacobi::new(n, block);
    for c0 in (0..m).step_by(block) {
        let w = block.min(m - c0);
        work.load(&rho, |p, c| first[p * m + c0 + c], w);
        assert!(work.solve(&f, &rho, &area, 1e-13, 100_000, &crate::observe::Silent));
        let y = work.luminance();
        for c in 0..w {
            let b: Vec<[f64; 3]> = (0..n)
                .map(|i| {
                    let row = &work.b[i * 3 * w..(i + 1) * 3 * w];
                    [row[c], row[w + c], row[2 * w + c]]
                })
                .collect();
            let want: Vec<Vec<f64>> = (0..3).map(|ch| exact(c0 + c, ch)).collect();
            for i in 0..n {
                for ch in 0..3 {
                    assert!(
                        (b[i][ch] - want[ch][i]).abs() <= 1e-11 * want[ch][i].abs().max(1.0),
                        "column {} patch {i} channel {ch}: {} against {}",
                        c0 + c,
                        b[i][ch],
                        want[ch][i]
                    );
                }
                let lum = luminance(Rgb::new(want[0][i], want[1][i], want[2][i]));
                assert!((y[i * w + c] - lum).abs() <= 1e-11 * lum.max(1.0));
                if c0 + c == 4 {
                    assert_eq!(y[i * w + c], 0.0);
                }
            }
        }
    }
    // A loose tolerance: stops early, and what is left unshot is within it.
    work.load(&rho, |p, c| first[p * m + c], block);
    assert!(work.solve(&f, &rho, &area, 0.5, 100_000, &crate::observe::Silent));
    for c in 0..block {
        assert!(work.unshot[c] <= 0.5 * work.emitted[c]);
    }
}

/// The sky patches' look-up by bisection finds, for every direction, the patch the plain scan
/// over each band's patches finds: 200,000 random directions above the horizon and every
/// patch's corners and edges' midpoints of the Reinhart skies MF:1 and MF:2, in either
/// azimuth convention (a patch starting west of north, or east of it).
#[test]
fn patch_look_up_by_bisection_matches_the_scan() {
    for mf in [1, 2] {
        let sky = crate::daylight::patches::SkyPatches::reinhart(mf).unwrap();
        for shift in [0.0, 0.5] {
            let patches: Vec<PatchBounds> = (0..sky.sky_count())
                .map(|p| {
                    let (alt, [z0, z1]) = sky.bounds(p);
                    let w = z1 - z0;
                    PatchBounds {
                        altitude: [alt[0], alt[1].min(std::f64::consts::FRAC_PI_2)],
                        azimuth: if w < std::f64::consts::TAU {
                            [z0 + shift * w, z1 + shift * w]
                        } else {
                            [z0, z1]
                        },
                        ground: 0.0,
                    }
                })
                .collect();
            let ps = PatchSky::new(patches.clone());
            let scan = |d: [f64; 3]| -> Option<usize> {
                let alt = d[2].clamp(-1.0, 1.0).asin();
                let az = d[0].atan2(d[1]).rem_euclid(std::f64::consts::TAU);
                for (a, members) in &ps.bands {
                    if alt < a[0] || (alt >= a[1] && a[1] < std::f64::consts::FRAC_PI_2) {
                        continue;
                    }
                    for &k in members {
                        if ps.holds(k, az) {
                            return Some(k);
                        }
                    }
                }
                None
            };
            let mut dirs = Vec::new();
            let mut rng = stream(9, mf as u64, 0, 0);
            for _ in 0..200_000 {
                let z = uniform(&mut rng) as f64;
                let phi = std::f64::consts::TAU * uniform(&mut rng) as f64;
                let r = (1.0 - z * z).sqrt();
                dirs.push([r * phi.sin(), r * phi.cos(), z]);
            }
            for p in &patches {
                for &alt in &[p.altitude[0], 0.5 * (p.altitude[0] + p.altitude[1])] {
                    for &az in &[
                        p.azimuth[0],
                        0.5 * (p.azimuth[0] + p.azimuth[1]),
                        p.azimuth[1],
                    ] {
                        dirs.push(direction(alt, az));
                    }
                }
            }
            let mut found = 0;
            for d in dirs {
                let got = ps.bin(d).map(|(k, _)| k);
                assert_eq!(got, scan(d), "MF:{mf} shift {shift} {d:?}");
                found += got.is_some() as usize;
            }
            assert!(found > 200_000, "{found}");
        }
    }
}

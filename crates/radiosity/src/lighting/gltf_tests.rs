//! glTF lights as luminaires, against the inverse-square cosine law.

use super::*;
use crate::lighting::{direct_illuminance, SensorPoint};
use base64::Engine as _;
use std::path::PathBuf;

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "radiosity-gltf-lights-{tag}-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A glTF file of `nodes` (JSON array text) in one scene with the given root extensions,
/// every node a root node; `extra` goes into the root object as is (buffers, bufferViews).
fn gltf(tag: &str, nodes: &str, extensions: &str, extra: &str) -> PathBuf {
    let n = serde_json::from_str::<serde_json::Value>(nodes)
        .unwrap()
        .as_array()
        .unwrap()
        .len();
    let roots: Vec<String> = (0..n).map(|i| i.to_string()).collect();
    let text = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":{nodes},"extensions":{extensions}{extra}}}"#,
        roots.join(",")
    );
    let path = scratch(tag).join("scene.gltf");
    std::fs::write(&path, text).unwrap();
    path
}

/// Floor sensors (y = 0, facing +y) around the origin.
fn floor() -> Vec<SensorPoint> {
    let mut p = Vec::new();
    for i in -4..=4 {
        for k in -4..=4 {
            p.push(SensorPoint {
                position: [0.7 * i as f64, 0.0, 0.55 * k as f64],
                normal: [0.0, 1.0, 0.0],
            });
        }
    }
    p
}

fn lux(lums: &[Luminaire], points: &[SensorPoint]) -> Vec<f64> {
    direct_illuminance(points, lums, None, 1.0).unwrap().total
}

/// E = I(θ) cos θ / d² for a source at (0, h, 0) over the floor, θ from straight down.
fn law(points: &[SensorPoint], h: f64, intensity: impl Fn(f64) -> f64) -> Vec<f64> {
    points
        .iter()
        .map(|p| {
            let d = [p.position[0], p.position[1] - h, p.position[2]];
            let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let cos = h / r;
            intensity(cos.acos()) * cos / (r * r)
        })
        .collect()
}

/// A rotation of −90° about x: the node's −Z points down (−y).
const DOWN: &str = "[-0.7071067811865476,0,0,0.7071067811865476]";

#[test]
fn a_point_light_follows_the_inverse_square_law() {
    let path = gltf(
        "point",
        r#"[{"name":"bulb","translation":[0,2.5,0],"extensions":{"KHR_lights_punctual":{"light":0}}}]"#,
        r#"{"KHR_lights_punctual":{"lights":[{"type":"point","intensity":120}]}}"#,
        r#","extensionsUsed":["KHR_lights_punctual"]"#,
    );
    let (lums, warnings) = gltf_luminaires(&path).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(lums.len(), 1);
    assert_eq!(lums[0].name, "bulb");
    let pts = floor();
    let want = law(&pts, 2.5, |_| 120.0);
    for (g, w) in lux(&lums, &pts).iter().zip(&want) {
        assert!((g - w).abs() <= 1e-9 * w, "{g} vs {w}");
    }
    // Its flux is 4π I.
    let flux = lums[0].photometry.flux();
    assert!((flux - 4.0 * std::f64::consts::PI * 120.0).abs() < 1e-6 * flux);
}

#[test]
fn a_spot_light_has_the_specified_cone_falloff() {
    let (inner, outer) = (0.3, 0.6);
    let path = gltf(
        "spot",
        &format!(
            r#"[{{"translation":[0,3,0],"rotation":{DOWN},"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}]"#
        ),
        &format!(
            r#"{{"KHR_lights_punctual":{{"lights":[{{"name":"spot","type":"spot","intensity":500,"color":[1,0.5,0.25],"spot":{{"innerConeAngle":{inner},"outerConeAngle":{outer}}}}}]}}}}"#
        ),
        "",
    );
    let (lums, _) = gltf_luminaires(&path).unwrap();
    let y = 0.2126 + 0.7152 * 0.5 + 0.0722 * 0.25;
    let pts = floor();
    let want = law(&pts, 3.0, |theta| {
        500.0 * y * spot_falloff(theta, inner, outer)
    });
    let got = lux(&lums, &pts);
    // Tabulation: linear interpolation every (outer − inner)/180 rad errs by at most
    // h²/8 · max|d²(s²)/dγ²| ≈ 2e-5 of I₀ here; at the floor that is ≤ 2e-5 · I₀ / h².
    let bound = 3e-5 * 500.0 * y / 9.0;
    let mut lit = 0;
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w).abs() <= bound, "{g} vs {w}");
        lit += usize::from(*w > 0.0);
    }
    assert!(
        lit > 5 && lit < pts.len(),
        "the cone lights some points, not all"
    );
    // Straight below: the full intensity.
    let below = pts
        .iter()
        .position(|p| p.position == [0.0, 0.0, 0.0])
        .unwrap();
    assert!((got[below] - 500.0 * y / 9.0).abs() < 1e-9);
}

/// A Lambertian downlight, I(γ) = 200 cos γ, as IES text.
const LAMBERT_IES: &str = "IESNA:LM-63-2002\n[TEST] cosine\nTILT=NONE\n\
1 -1 1 7 1 1 2 0 0 0\n1 1 0\n0 15 30 45 60 75 90\n0\n\
200 193.18516525781366 173.20508075688772 141.4213562373095 100 51.76380902050415 0\n";

#[test]
fn an_ies_profile_is_placed_scaled_and_tinted() {
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(LAMBERT_IES)
    );
    let path = gltf(
        "ies",
        &format!(
            r#"[{{"translation":[0,2,0],"rotation":{DOWN},"extensions":{{"EXT_lights_ies":{{"light":0,"multiplier":2,"color":[0.5,1,1]}}}}}},
                {{"translation":[1,2,0],"rotation":{DOWN},"extensions":{{"EXT_lights_ies":{{"light":0}}}}}}]"#
        ),
        &format!(r#"{{"EXT_lights_ies":{{"lights":[{{"uri":"{uri}","name":"down"}}]}}}}"#),
        "",
    );
    let (lums, _) = gltf_luminaires(&path).unwrap();
    assert_eq!(lums.len(), 2);
    assert!(
        Arc::ptr_eq(&lums[0].photometry, &lums[1].photometry),
        "one profile, parsed once"
    );
    let y = 0.2126 * 0.5 + 0.7152 + 0.0722;
    let pts = floor();
    let a = law(&pts, 2.0, |t| 2.0 * y * 200.0 * t.cos());
    let b: Vec<f64> = pts
        .iter()
        .map(|p| {
            let d = [p.position[0] - 1.0, -2.0, p.position[2]];
            let r2 = d[0] * d[0] + 4.0 + d[2] * d[2];
            let cos = 2.0 / r2.sqrt();
            200.0 * cos * cos / r2
        })
        .collect();
    // The table is the cosine at 15° steps: linear interpolation between them errs by at
    // most (15°)²/8 · I₀ ≈ 0.0086 I₀.
    for ((g, wa), wb) in lux(&lums, &pts).iter().zip(&a).zip(&b) {
        let w = wa + wb;
        assert!(
            (g - w).abs() <= 0.0086 * 200.0 * (2.0 * y + 1.0) / 4.0,
            "{g} vs {w}"
        );
    }
}

#[test]
fn a_profile_in_a_buffer_view_reads_like_one_in_a_uri() {
    let bytes = LAMBERT_IES.as_bytes();
    let buffer = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    );
    let nodes = format!(
        r#"[{{"translation":[0,2,0],"rotation":{DOWN},"extensions":{{"EXT_lights_ies":{{"light":0}}}}}}]"#
    );
    let extra = format!(
        r#","buffers":[{{"uri":"{buffer}","byteLength":{n}}}],"bufferViews":[{{"buffer":0,"byteLength":{n}}}]"#,
        n = bytes.len()
    );
    let path = gltf(
        "view",
        &nodes,
        r#"{"EXT_lights_ies":{"lights":[{"bufferView":0,"mimeType":"application/x-ies-lm-63"}]}}"#,
        &extra,
    );
    let (lums, _) = gltf_luminaires(&path).unwrap();
    let pts = floor();
    let want = law(&pts, 2.0, |t| 200.0 * t.cos());
    for (g, w) in lux(&lums, &pts).iter().zip(&want) {
        assert!((g - w).abs() <= 0.0086 * 200.0 / 4.0, "{g} vs {w}");
    }
}

#[test]
fn directional_lights_and_ranges_are_noted_not_used() {
    let path = gltf(
        "sun",
        r#"[{"extensions":{"KHR_lights_punctual":{"light":0}}},{"translation":[0,3,0],"extensions":{"KHR_lights_punctual":{"light":1}}}]"#,
        r#"{"KHR_lights_punctual":{"lights":[{"type":"directional","intensity":3},{"type":"point","intensity":10,"range":5}]}}"#,
        "",
    );
    let (lums, warnings) = gltf_luminaires(&path).unwrap();
    assert_eq!(lums.len(), 1);
    assert_eq!(warnings.len(), 2, "{warnings:?}");
    assert!(warnings[0].contains("directional"), "{warnings:?}");
    assert!(warnings[1].contains("range"), "{warnings:?}");
}

#[test]
fn bad_lights_are_refused_in_one_line_naming_the_place() {
    let cases: &[(&str, &str, &str, &str)] = &[
        (
            r#"[{"extensions":{"KHR_lights_punctual":{"light":0}}}]"#,
            r#"{"KHR_lights_punctual":{"lights":[{"type":"spot","intensity":1,"spot":{"innerConeAngle":0.5,"outerConeAngle":0.4}}]}}"#,
            "",
            "nodes[0]",
        ),
        (
            r#"[{"extensions":{"KHR_lights_punctual":{"light":0}}}]"#,
            r#"{"KHR_lights_punctual":{"lights":[{"type":"point","intensity":-1}]}}"#,
            "",
            "intensity",
        ),
        (
            r#"[{"extensions":{"EXT_lights_ies":{"light":3}}}]"#,
            r#"{"EXT_lights_ies":{"lights":[{"uri":"a.ies"}]}}"#,
            "",
            "light 3",
        ),
        (
            r#"[{"extensions":{"EXT_lights_ies":{"light":0,"multiplier":-2}}}]"#,
            r#"{"EXT_lights_ies":{"lights":[{"uri":"a.ies"}]}}"#,
            "",
            "multiplier",
        ),
        (
            r#"[{"extensions":{"EXT_lights_ies":{"light":0}}}]"#,
            r#"{"EXT_lights_ies":{"lights":[{"uri":"missing.ies"}]}}"#,
            "",
            "cannot read",
        ),
        (
            r#"[{"extensions":{"EXT_lights_ies":{"light":0}}}]"#,
            r#"{"EXT_lights_ies":{"lights":[{"bufferView":0}]}}"#,
            "",
            "mimeType",
        ),
        (
            r#"[{"extensions":{"EXT_lights_ies":{"light":0}}}]"#,
            r#"{"EXT_lights_ies":{"lights":[{"name":"none"}]}}"#,
            "",
            "'uri' or a 'bufferView'",
        ),
        (
            r#"[{"extensions":{"EXT_lights_ies":{"light":0}}}]"#,
            r#"{"EXT_lights_ies":{"lights":[{"uri":"data:text/plain;base64,SUVTTkE6TE0tNjMtMjAwMgpub3QgYSBwcm9maWxl"}]}}"#,
            "",
            "light 1",
        ),
        (
            r#"[{"scale":[0,0,0],"extensions":{"KHR_lights_punctual":{"light":0}}}]"#,
            r#"{"KHR_lights_punctual":{"lights":[{"type":"point","intensity":1}]}}"#,
            "",
            "transform",
        ),
    ];
    for (i, (nodes, ext, extra, needle)) in cases.iter().enumerate() {
        let path = gltf(&format!("bad{i}"), nodes, ext, extra);
        let e = match gltf_luminaires(&path) {
            Ok(l) => panic!("case {i} accepted: {} luminaires", l.0.len()),
            Err(e) => e.to_string(),
        };
        assert!(!e.contains('\n'), "case {i}: {e}");
        assert!(e.contains("scene.gltf"), "case {i} names no file: {e}");
        assert!(e.contains(needle), "case {i}: '{e}' lacks '{needle}'");
    }
}

//! A mutation fuzzer for every input parser, on the stable toolchain: valid seed files of each
//! format (OBJ with MTL, MGF, glTF, GLB, PLY in three encodings, Matrix Market with a patches
//! CSV) are mutated by a seeded random stream (bit flips, byte runs replaced, inserted,
//! deleted, duplicated or truncated, and tokens swapped for hostile ones: huge counts, `nan`,
//! `1e309`, `-1`), written to a scratch folder and parsed, then validated and, when valid,
//! meshed. A case passes when it returns, an error or a scene, without panicking; the caller
//! bounds time and memory ([`Report::slowest`]; the `radiosity fuzz` command also counts the
//! heap). The corpus is built in, so the fuzzer runs anywhere.

use radiosity::io::{matrix_market, patches_csv};
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::sampling::{stream, uniform, Rng64};
use radiosity::scene::{load_with, LoadOptions};
use rand::Rng;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The parsers fuzzed, each with its seed file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// Wavefront OBJ (its MTL beside it, unmutated).
    Obj,
    /// An MTL library, mutated, under a fixed OBJ.
    Mtl,
    /// MGF.
    Mgf,
    /// glTF JSON (its `.bin` and texture beside it).
    Gltf,
    /// Binary glTF.
    Glb,
    /// Binary glTF with a lightmap (`TEXCOORD_1`, `MOZ_lightmap`, an embedded PNG), read as
    /// `view` and a kept UV set read it.
    GlbLightmap,
    /// PLY, ASCII.
    PlyAscii,
    /// PLY, binary big-endian.
    PlyBinary,
    /// Matrix Market (with a valid patches CSV).
    MatrixMarket,
    /// Patches CSV (with a valid matrix).
    PatchesCsv,
    /// NIST View3D input (`.vs3`), vertex-and-surface form (`F 3`).
    Vs3,
    /// NIST View3D input, surfaces with their own geometry (`F 3a`).
    Vs3a,
    /// The thermal boundary-condition table (`bc.csv`).
    BoundaryCsv,
    /// A PFM image (a picture benchmark's reference).
    Pfm,
    /// IES LM-63 photometry (a luminaire's candela table).
    Ies,
    /// IES photometry of type B (a floodlight: laterally symmetric, with a tilt table).
    IesB,
    /// IES photometry of type A (vertical angles 0..90, CRLF, a tilt table).
    IesA,
    /// EULUMDAT photometry.
    Ldt,
    /// A luminaire schedule (with its photometric file beside it, unmutated).
    Schedule,
    /// Calculation points in Radiance's points format.
    Points,
    /// A glTF file's lights (`KHR_lights_punctual` point and spot, `EXT_lights_ies` profiles
    /// in a data URI), read as luminaires.
    GltfLights,
    /// An EnergyPlus weather file (one day of hourly records) for the annual daylight run.
    Epw,
    /// An occupancy schedule (a day of hours, DAYSIM's `month,day,hour,value`).
    Occupancy,
}

impl Target {
    /// Every target.
    pub const ALL: [Target; 23] = [
        Target::Obj,
        Target::Mtl,
        Target::Mgf,
        Target::Gltf,
        Target::Glb,
        Target::GlbLightmap,
        Target::PlyAscii,
        Target::PlyBinary,
        Target::MatrixMarket,
        Target::PatchesCsv,
        Target::Vs3,
        Target::Vs3a,
        Target::BoundaryCsv,
        Target::Pfm,
        Target::Ies,
        Target::IesB,
        Target::IesA,
        Target::Ldt,
        Target::Schedule,
        Target::Points,
        Target::GltfLights,
        Target::Epw,
        Target::Occupancy,
    ];

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Target::Obj => "obj",
            Target::Mtl => "mtl",
            Target::Mgf => "mgf",
            Target::Gltf => "gltf",
            Target::Glb => "glb",
            Target::GlbLightmap => "glb-lightmap",
            Target::PlyAscii => "ply-ascii",
            Target::PlyBinary => "ply-binary",
            Target::MatrixMarket => "matrix-market",
            Target::PatchesCsv => "patches-csv",
            Target::Vs3 => "vs3",
            Target::Vs3a => "vs3a",
            Target::BoundaryCsv => "bc-csv",
            Target::Pfm => "pfm",
            Target::Ies => "ies",
            Target::IesB => "ies-b",
            Target::IesA => "ies-a",
            Target::Ldt => "ldt",
            Target::Schedule => "schedule",
            Target::Points => "points",
            Target::GltfLights => "gltf-lights",
            Target::Epw => "epw",
            Target::Occupancy => "occupancy",
        }
    }
}

const OBJ: &str = "mtllib box.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nusemtl white\nf 1 2 3 4\nf 5 8 7 6\nusemtl light\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n";
const MTL: &str = "newmtl white\nKd 0.7 0.7 0.7\nnewmtl light\nKd 0.5 0.5 0.5\nKe 4 4 4\n";
const MGF: &str = "# a lit room\nm white =\n\tc\n\t\tcxy 0.33 0.33\n\trd 0.6\nm lamp =\n\tc\n\ted 100\nv a =\n\tp 0 0 0\nv b =\n\tp 1 0 0\nv c =\n\tp 1 1 0\nv d =\n\tp 0 1 0\nv e =\n\tp 0 0 1\nm white\nf a b c d\nxf -a 3 -t 0 0 0.3\nm lamp\nf a d c b\nxf\ncyl e 0.2 a\nsph e 0.1\n";
const MTX: &str = "%%MatrixMarket matrix coordinate real general\n% a closed pair\n3 3 5\n1 2 0.5\n1 3 0.5\n2 1 0.5\n2 3 0.5\n3 1 1\n";
const CSV: &str = "area,reflectance,emission\n1,0.5,1\n1,0.5,0\n2,0.25,0\n";
const VS3: &str = "T two forms\nC encl=1 list=2 eps=1.e-4 maxu=8\nF 3\n! a box\nV 1 0. 0. 0.\nV 2 1. 0. 0.\nV 3 1. 1. 0.\nV 4 0. 1. 0.\nV 5 0. 0. 1.\nV 6 1. 0. 1.\nV 7 1. 1. 1.\nV 8 0. 1. 1.\nS 1 1 2 3 4 0 0 0.50 floor\nS 2 1 4 8 5 0 0 0.50 xeq0\nS 3 1 5 6 2 0 0 0.50 yeq0\nS 4 7 6 5 8 0 0 0.90 top\nS 5 7 3 2 0 0 2 0.50 xeq1a ! combined\nS 6 7 2 6 0 0 2 0.50 xeq1b\nS 7 7 8 4 3 0 0 0.50 yeq1\nO 8 1 2 7 8\nEnd of data\n";
const VS3A: &str = "T L room\nC encl=1\nF 3a\nS 1 R 0 0 0.90 s1\n  3. 0. 0. 0 90 3. 3.\nS 2 Q 0 0 0.90 s2\n  3. 0. 3. 0 180\n  2. 0. 3. 0. 3. 1. 2. 1.\nS 3 T 0 1 0.90 s3\n 0. 0. 0. 180 0 0. 0. 1. 0. 1. 1.\nO 4 R 1. 1. 1. 45 30 1. 1.\nE\n";
/// A point, a spot aimed down and an IES profile (a data URI of a cosine downlight), each on
/// its own node.
const GLTF_LIGHTS: &str = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,1,2]}],"extensionsUsed":["KHR_lights_punctual","EXT_lights_ies"],"extensions":{"KHR_lights_punctual":{"lights":[{"type":"point","intensity":120,"color":[1,0.9,0.8]},{"type":"spot","intensity":500,"range":9,"spot":{"innerConeAngle":0.3,"outerConeAngle":0.6}}]},"EXT_lights_ies":{"lights":[{"name":"down","uri":"data:application/octet-stream;base64,SUVTTkE6TE0tNjMtMjAwMgpUSUxUPU5PTkUKMSAtMSAxIDMgMSAxIDIgMCAwIDAKMSAxIDAKMCA0NSA5MAowCjIwMCAxNDEuNCAwCg=="}]}},"nodes":[{"name":"bulb","translation":[0,2.5,0],"extensions":{"KHR_lights_punctual":{"light":0}}},{"translation":[1,3,0],"rotation":[-0.7071067811865476,0,0,0.7071067811865476],"extensions":{"KHR_lights_punctual":{"light":1}}},{"translation":[2,3,1],"rotation":[-0.7071067811865476,0,0,0.7071067811865476],"extensions":{"EXT_lights_ies":{"light":0,"multiplier":2,"color":[0.5,1,1]}}}]}"#;
const IES: &str = "IESNA:LM-63-2002\r\n[TEST] fuzz seed\r\n[MANUFAC] radiosity\r\nTILT=INCLUDE\r\n1\r\n3\r\n0 45 90\r\n1 0.9 0.8\r\n1 1000 1 5 3 1 2 0.6 -0.3 0.1\r\n1 0 0\r\n0 22.5 45 67.5 90\r\n0 90 180\r\n300 280 220 120 10\r\n310 290 230 130 12\r\n320 300 240 140 14\r\n";
const IES_B: &str = "IESNA:LM-63-1995\n[TEST] fuzz seed, type B\n[LUMINAIRE] floodlight\nTILT=INCLUDE\n3\n4\n0 30 60 90\n1 0.97 0.9 0.85\n1 20000 1.0 7 4 2 1 -1.2 -1.2 0.3\n1.0 1.0 400\n-90 -60 -30 0 30 60 90\n0 30 60 90\n0 200 3000 9000 2500 150 0\n0 150 2500 8000 2000 120 0\n0 60 900 2000 700 50 0\n0 0 0 0 0 0 0\n";
const IES_A: &str = "IESNA:LM-63-2002\r\n[TEST] fuzz seed, type A\r\nTILT=INCLUDE\r\n2\r\n2\r\n0 90\r\n1 0.5\r\n1 -1 1 4 5 3 2 0.2 0.1 0\r\n1 0 12\r\n0, 10, 45, 90\r\n-90, -20, 0, 20, 90\r\n0 0 0 0\r\n40 20 5 0\r\n900 300 20 0\r\n50 25 5 0\r\n0 0 0 0\r\n";
const LDT: &str = "radiosity\n1\n2\n4\n90\n5\n22.5\nreport\nfuzz seed\n1\nseed.ldt\n2026-11-28\n600\n300\n80\n580\n280\n0\n0\n0\n0\n95\n80\n1\n0\n1\n2\nLED\n4000\n3000\n80\n40\n0.5\n0.6\n0.7\n0.75\n0.8\n0.85\n0.9\n0.92\n0.95\n0.97\n0\n90\n180\n270\n0\n22.5\n45\n67.5\n90\n300\n280\n220\n120\n10\n310\n290\n230\n130\n12\n320\n300\n240\n140\n14\n";
const SCHEDULE: &str = "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group\nA,lamp.ies,1,2,2.9,,,,,,,0.8,north\n\"B, quoted\",lamp.ies,3,2,2.9,0.1,0,-1,1,0,0,,\n";
const POINTS: &str =
    "# a desk\n0.5 0.5 0.8 0 0 1\n1.5\t0.5 0.8 0 0 2\n\n2.5 0.5 0.8 0.1 0 1 # tilted\n";
const BC: &str = "name,emissivity,temperature,flux\nfloor,0.9,300,\ntop,,,-20.5\n\"xeq0\",1,,\n# comment\nyeq0,0.5,0,\n";

/// The outcome of a run.
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// Cases run.
    pub cases: u64,
    /// Cases that loaded (the rest gave an error).
    pub accepted: u64,
    /// Cases that panicked, with the file kept for each (empty when none did).
    pub panics: Vec<PathBuf>,
    /// The slowest case and its time.
    pub slowest: Duration,
}

/// The seed files of `target`: (file name, bytes), the first one mutated.
fn corpus(target: Target, scratch: &Path) -> Vec<(String, Vec<u8>)> {
    let room = |name: &str| -> Vec<u8> {
        match name {
            "room.gltf" => include_bytes!("../../radiosity/tests/data/room.gltf").to_vec(),
            "room.bin" => include_bytes!("../../radiosity/tests/data/room.bin").to_vec(),
            "checker.png" => include_bytes!("../../radiosity/tests/data/checker.png").to_vec(),
            "room.ply" => include_bytes!("../../radiosity/tests/data/room.ply").to_vec(),
            _ => include_bytes!("../../radiosity/tests/data/room_be.ply").to_vec(),
        }
    };
    let s = |n: &str, t: &str| (n.to_string(), t.as_bytes().to_vec());
    match target {
        Target::Obj => vec![s("box.obj", OBJ), s("box.mtl", MTL)],
        Target::Mtl => vec![s("box.mtl", MTL), s("box.obj", OBJ)],
        Target::Mgf => vec![s("room.mgf", MGF)],
        Target::Gltf => vec![
            ("room.gltf".into(), room("room.gltf")),
            ("room.bin".into(), room("room.bin")),
            ("checker.png".into(), room("checker.png")),
        ],
        Target::Glb => vec![("room.glb".into(), glb(scratch))],
        Target::GlbLightmap => vec![("lit.glb".into(), glb_lightmap(scratch))],
        Target::PlyAscii => vec![("room.ply".into(), room("room.ply"))],
        Target::PlyBinary => vec![("room_be.ply".into(), room("room_be.ply"))],
        Target::MatrixMarket => vec![s("f.mtx", MTX), s("p.csv", CSV)],
        Target::PatchesCsv => vec![s("p.csv", CSV), s("f.mtx", MTX)],
        Target::Vs3 => vec![s("box.vs3", VS3)],
        Target::Vs3a => vec![s("room.vs3", VS3A)],
        Target::BoundaryCsv => vec![s("bc.csv", BC)],
        Target::Ies => vec![s("lamp.ies", IES)],
        Target::IesB => vec![s("lamp.ies", IES_B)],
        Target::IesA => vec![s("lamp.ies", IES_A)],
        Target::Ldt => vec![s("lamp.ldt", LDT)],
        // The schedule first: the mutations fall on the first file.
        Target::Schedule => vec![s("lights.csv", SCHEDULE), s("lamp.ies", IES)],
        Target::Points => vec![s("desk.pts", POINTS)],
        Target::Epw => vec![("golden.epw".into(), epw_day().into_bytes())],
        Target::Occupancy => vec![("occupancy.csv".into(), {
            let mut t = String::from("month,day,hour,occupancy\n# a working day\n");
            for h in 0..24 {
                t.push_str(&format!("6,21,{h}.5,{}\n", (8..18).contains(&h) as u8));
            }
            t.into_bytes()
        })],
        Target::GltfLights => vec![s("lights.gltf", GLTF_LIGHTS)],
        Target::Pfm => vec![("ref.pfm".into(), {
            let mut b = b"PF\n2 2\n-1.0\n".to_vec();
            for k in 0..12u32 {
                b.extend_from_slice(&(k as f32 * 0.25).to_le_bytes());
            }
            b
        })],
    }
}

/// One day (21 June) of hourly weather in EnergyPlus's layout: the site, the data period and
/// 24 records with irradiance and illuminance by day, dark by night.
fn epw_day() -> String {
    let mut s = String::from(
        "LOCATION,Golden,CO,USA,Hand,724666,39.74,-105.18,-7.0,1829.0\nDESIGN CONDITIONS,0\n\
         TYPICAL/EXTREME PERIODS,0\nGROUND TEMPERATURES,0\nHOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\n\
         COMMENTS 1,fuzz seed\nCOMMENTS 2,\nDATA PERIODS,1,1,Data,Sunday, 6/21, 6/21\n",
    );
    for hour in 1..=24 {
        let (ghi, dni, dhi) = if (7..=20).contains(&hour) {
            (300, 400, 100)
        } else {
            (0, 0, 0)
        };
        s.push_str(&format!(
            "1999,6,21,{hour},60,?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9,24.5,6.2,30,82000,\
             1300,1360,400,{ghi},{dni},{dhi},{},{},{},9999,200,3.5,2,1,16.1,77777,9,999999999,10,\
             0.05,0,88,0.2,0,0\n",
            ghi * 110,
            dni * 95,
            dhi * 120
        ));
    }
    s
}

/// A small binary glTF: the built-in furnace baked by our own writer.
fn glb(scratch: &Path) -> Vec<u8> {
    let scene = radiosity::scene::builtin::furnace();
    let mesh = Mesh::build(&scene, MeshParams::Patches(30)).expect("the furnace meshes");
    let values = vec![radiosity::color::Rgb::splat(1.0); mesh.vertices.len()];
    let path = scratch.join("seed.glb");
    radiosity::export::bake::write(
        &path,
        &radiosity::export::bake::Bake {
            scene: &scene,
            mesh: &mesh,
            vertex_radiosity: &values,
            scale: 1.0,
            camera: None,
        },
    )
    .expect("the seed bakes");
    std::fs::read(&path).expect("the seed reads")
}

/// A small lightmapped binary glTF: the furnace's faces charted into a 32 × 32 atlas holding
/// a gradient, written by our own writer.
fn glb_lightmap(scratch: &Path) -> Vec<u8> {
    use radiosity::bake::lightmap::{Lightmap, Texel};
    let scene = radiosity::scene::builtin::furnace();
    let unwrap = radiosity::bake::uv::unwrap(&scene, radiosity::bake::uv::Density::AtlasSize(32))
        .expect("the furnace charts");
    let n = (unwrap.width * unwrap.height * unwrap.atlases) as usize;
    let texels = (0..n)
        .map(|i| [i as f32 / n as f32, 0.5, 1.0 - i as f32 / n as f32])
        .collect();
    let map = Lightmap {
        unwrap,
        texels,
        kind: vec![Texel::Surface; n],
        faces: vec![0; n],
        inside: vec![true; n],
        records: 0,
    };
    let path = scratch.join("seed-lightmap.glb");
    radiosity::export::bake::write_lightmap_gltf(
        &path,
        &radiosity::export::bake::LightmapBake {
            scene: &scene,
            lightmap: &map,
            scale: 1.0,
            camera: None,
        },
        true,
    )
    .expect("the seed bakes");
    std::fs::read(&path).expect("the seed reads")
}

/// Read a lightmapped glTF as `view` does (and render a few pixels, which must be finite) and
/// as a lightmap bake keeps its UV set (charting it into a small atlas).
fn lightmapped(path: &Path) -> bool {
    let mut ok = false;
    if let Ok(Some(view)) = radiosity::render::baked::BakedView::load_lightmap(path) {
        let image = view.render(
            &view.default_camera(),
            &radiosity::render::RenderParams {
                width: 8,
                height: 8,
                samples_per_pixel: 1,
                seed: 1,
            },
            &radiosity::observe::Silent,
        );
        assert!(
            image.pixels.iter().flatten().all(|c| c.is_finite()),
            "a lightmapped view made a non-finite pixel"
        );
        ok = true;
    }
    if let Ok((scene, set)) = radiosity::scene::gltf::load_lightmap(path, false, false) {
        if set.uv.iter().all(|u| u.is_some()) && scene.validate_geometry().is_ok() {
            let uv: Vec<[[f32; 2]; 3]> = set.uv.into_iter().flatten().collect();
            let _ = radiosity::bake::given::unwrap_given(
                &scene,
                radiosity::bake::uv::Density::AtlasSize(32),
                &uv,
            );
        }
        ok = true;
    }
    ok
}

const TOKENS: [&str; 14] = [
    "-1",
    "0",
    "nan",
    "inf",
    "1e309",
    "4294967296",
    "18446744073709551616",
    "99999999999",
    "\n",
    " ",
    "\"",
    "{",
    "]",
    "\u{0}",
];

/// Mutate `bytes` in place by one to four random edits.
fn mutate(bytes: &mut Vec<u8>, rng: &mut Rng64) {
    let edits = 1 + (rng.random::<u32>() % 4);
    for _ in 0..edits {
        let n = bytes.len();
        let at = if n == 0 {
            0
        } else {
            rng.random::<u32>() as usize % n
        };
        match rng.random::<u32>() % 8 {
            0 if n > 0 => bytes[at] ^= 1 << (rng.random::<u32>() % 8),
            1 if n > 0 => bytes[at] = rng.random::<u8>(),
            2 => {
                let t = TOKENS[rng.random::<u32>() as usize % TOKENS.len()];
                // Replace the token under `at` (up to the next space or newline).
                let end = bytes[at..]
                    .iter()
                    .position(|b| b.is_ascii_whitespace() || *b == b',')
                    .map_or(n, |k| at + k);
                bytes.splice(at..end.max(at), t.bytes());
            }
            3 => {
                let len = (rng.random::<u32>() % 64) as usize;
                let junk: Vec<u8> = (0..len).map(|_| rng.random::<u8>()).collect();
                bytes.splice(at..at, junk);
            }
            4 if n > 0 => {
                let len = (rng.random::<u32>() as usize % 64).min(n - at);
                bytes.drain(at..at + len);
            }
            5 if n > 0 => {
                // Duplicate a run, up to a few times.
                let len = (rng.random::<u32>() as usize % 256).min(n - at);
                let run = bytes[at..at + len].to_vec();
                for _ in 0..1 + rng.random::<u32>() % 4 {
                    bytes.splice(at..at, run.iter().copied());
                }
            }
            6 => bytes.truncate(at),
            _ => {
                let b = if uniform(rng) < 0.5 { b'9' } else { b'\n' };
                bytes.splice(at..at, std::iter::repeat_n(b, 1 + at % 32));
            }
        }
    }
}

/// Parse (and, when valid, mesh) the mutated file of `target` in `dir`.
fn parse(target: Target, dir: &Path) -> bool {
    let options = LoadOptions::default();
    let scene = |name: &str| {
        if let Ok(s) = load_with(dir.join(name).to_str().unwrap_or(""), &options) {
            if s.validate_geometry().is_ok() {
                // Bounded work: the mesher's own limits keep a valid scene small here.
                let _ = Mesh::build(&s, MeshParams::Patches(64));
            }
            return true;
        }
        false
    };
    match target {
        Target::Obj | Target::Mtl => scene("box.obj"),
        Target::Mgf => scene("room.mgf"),
        Target::Gltf => scene("room.gltf"),
        Target::Glb => scene("room.glb"),
        Target::GlbLightmap => lightmapped(&dir.join("lit.glb")),
        Target::PlyAscii => scene("room.ply"),
        Target::PlyBinary => scene("room_be.ply"),
        Target::Vs3 => scene("box.vs3"),
        Target::Vs3a => scene("room.vs3"),
        Target::BoundaryCsv => radiosity::thermal::read_boundary_csv(&dir.join("bc.csv")).is_ok(),
        Target::Pfm => radiosity::render::compare::read_pfm(&dir.join("ref.pfm")).is_ok(),
        Target::Ies | Target::IesB | Target::IesA => {
            radiosity::photometry::read(&dir.join("lamp.ies")).is_ok()
        }
        Target::Ldt => radiosity::photometry::read(&dir.join("lamp.ldt")).is_ok(),
        Target::Schedule => {
            radiosity::lighting::read_schedule(&dir.join("lights.csv"), radiosity::lighting::Up::Z)
                .is_ok()
        }
        Target::Points => radiosity::lighting::read_points(&dir.join("desk.pts")).is_ok(),
        Target::Epw => radiosity::daylight::epw::read_epw(&dir.join("golden.epw")).is_ok(),
        Target::Occupancy => std::fs::read_to_string(dir.join("occupancy.csv"))
            .ok()
            .is_some_and(|t| {
                radiosity::daylight::metrics::parse_schedule(&t, "occupancy.csv", 24).is_ok()
            }),
        Target::GltfLights => {
            radiosity::lighting::gltf_luminaires(&dir.join("lights.gltf")).is_ok()
        }
        Target::MatrixMarket | Target::PatchesCsv => {
            let m = matrix_market::read(&dir.join("f.mtx"));
            let p = patches_csv::read(&dir.join("p.csv"));
            m.is_ok() && p.is_ok()
        }
    }
}

/// Run `cases` mutations of `target`'s seed with seed `seed`, in `scratch` (created; a file
/// that made a parser panic is kept there as `panic-K.EXT`). `progress` is called after each
/// case with the case and its time.
pub fn run(
    target: Target,
    cases: u64,
    seed: u64,
    scratch: &Path,
    progress: &mut dyn FnMut(u64, Duration),
) -> std::io::Result<Report> {
    let dir = scratch.join(target.name());
    std::fs::create_dir_all(&dir)?;
    let files = corpus(target, &dir);
    for (name, bytes) in &files {
        std::fs::write(dir.join(name), bytes)?;
    }
    let (name, original) = &files[0];
    let mut report = Report::default();
    let mut bytes = Vec::new();
    for case in 0..cases {
        let mut rng = stream(seed, 0xF022, target as u64, case);
        bytes.clone_from(original);
        mutate(&mut bytes, &mut rng);
        std::fs::write(dir.join(name), &bytes)?;
        let t = Instant::now();
        let outcome = std::panic::catch_unwind(|| parse(target, &dir));
        let took = t.elapsed();
        report.slowest = report.slowest.max(took);
        report.cases += 1;
        match outcome {
            Ok(loaded) => report.accepted += u64::from(loaded),
            Err(_) => {
                let keep = dir.join(format!("panic-{case}-{name}"));
                std::fs::write(&keep, &bytes)?;
                report.panics.push(keep);
            }
        }
        progress(case, took);
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A short fixed-seed run of every parser: no panic, and every case within seconds.
    #[test]
    fn every_parser_survives_a_short_fuzz() {
        let scratch = std::env::temp_dir().join(format!("radiosity-fuzz-{}", std::process::id()));
        for target in Target::ALL {
            let r = run(target, 300, 1, &scratch, &mut |_, _| {}).unwrap();
            assert!(
                r.panics.is_empty(),
                "{}: panics on {:?}",
                target.name(),
                r.panics
            );
            assert!(
                r.slowest < Duration::from_secs(10),
                "{}: a case took {:?}",
                target.name(),
                r.slowest
            );
        }
        let _ = std::fs::remove_dir_all(&scratch);
    }

    /// Every seed file is valid as written, so that the mutations start from a file the
    /// parser accepts (the photometric seeds carry a tilt table, CRLF and a round opening).
    #[test]
    fn every_seed_file_parses_unmutated() {
        let root = std::env::temp_dir().join(format!("radiosity-seeds-{}", std::process::id()));
        for target in Target::ALL {
            let dir = root.join(target.name());
            std::fs::create_dir_all(&dir).unwrap();
            for (name, bytes) in corpus(target, &dir) {
                std::fs::write(dir.join(name), bytes).unwrap();
            }
            assert!(
                parse(target, &dir),
                "{}: the seed file is refused",
                target.name()
            );
        }
        let _ = std::fs::remove_dir_all(&root);
    }

    /// The photometric seeds cover every photometric type and every lamp-to-luminaire
    /// geometry of a tilt table, read as such.
    #[test]
    fn the_photometric_seeds_cover_types_b_and_a_and_tilt() {
        use radiosity::photometry::{parse_bytes, LampGeometry, PhotometricType};
        for (text, kind, geometry) in [
            (IES, PhotometricType::C, LampGeometry::Vertical),
            (IES_B, PhotometricType::B, LampGeometry::AcrossC0),
            (IES_A, PhotometricType::A, LampGeometry::AlongC0),
        ] {
            let p = parse_bytes(text.as_bytes(), "seed.ies").unwrap();
            assert_eq!(p.kind, kind);
            assert_eq!(p.tilt.as_ref().map(|t| t.geometry), Some(geometry));
            assert!(p.flux() > 0.0);
        }
    }

    /// Mutations are reproducible from the seed.
    #[test]
    fn mutations_follow_the_seed() {
        let m = |seed| {
            let mut b = OBJ.as_bytes().to_vec();
            mutate(&mut b, &mut stream(seed, 1, 2, 3));
            b
        };
        assert_eq!(m(4), m(4));
        assert_ne!(m(4), m(5));
    }
}

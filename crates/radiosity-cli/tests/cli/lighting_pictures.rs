//! `radiosity lighting --pictures`: the false-colour maps and isolux plots of each grid,
//! decoded and checked against the grid's CSV, and the bad input refused before any work.

use crate::common::*;
use radiosity::lighting::{SensorPoint, Up};
use radiosity_cli::false_colour::grid::GridPictures;
use radiosity_cli::false_colour::{Bands, Scale};
use std::path::{Path, PathBuf};

/// A closed box 6 × 4 × 3 m, black (nothing interreflects), its floor a material of its own.
const ROOM: &str = "mtllib room.mtl\nv 0 0 0\nv 6 0 0\nv 6 4 0\nv 0 4 0\nv 0 0 3\nv 6 0 3\nv 6 4 3\nv 0 4 3\nusemtl floor\nf 1 2 3 4\nusemtl black\nf 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n";

/// The room, one isotropic 1,000 cd luminaire off-centre at (2, 1.5, 2.5) (so the work plane
/// runs from about 20 lx in the far corner to 346 lx under it), and 60 scattered desk points
/// at 0.8 m.
fn room(dir: &Path) {
    write(dir, "room.obj", ROOM);
    write(
        dir,
        "room.mtl",
        "newmtl black\nKd 0 0 0\nnewmtl floor\nKd 0 0 0\n",
    );
    let gammas: Vec<String> = (0..=36).map(|k| (5 * k).to_string()).collect();
    write(
        dir,
        "iso.ies",
        &format!(
            "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 37 1 1 2 0 0 0\n1 1 0\n{}\n0\n{}\n",
            gammas.join(" "),
            vec!["1000"; 37].join(" ")
        ),
    );
    write(
        dir,
        "schedule.csv",
        "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group\n\
         A,iso.ies,2,1.5,2.5,,,,,,,1,\n",
    );
    let mut s = 99u64;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut pts = String::new();
    for _ in 0..60 {
        pts += &format!("{} {} 0.8 0 0 1\n", 1.0 + 4.0 * next(), 0.8 + 2.4 * next());
    }
    write(dir, "desk.pts", &pts);
}

/// The grid CSV's points and illuminances.
fn grid(dir: &Path) -> (Vec<SensorPoint>, Vec<f64>) {
    let (header, rows) = read_csv(&dir.join("grid.csv"));
    let e = column(&header, "illuminance");
    rows.iter()
        .map(|r| {
            let v: Vec<f64> = r.iter().map(|t| t.parse().unwrap()).collect();
            (
                SensorPoint::new([v[0], v[1], v[2]], [v[3], v[4], v[5]]).unwrap(),
                v[e],
            )
        })
        .unzip()
}

/// The texts of an SVG's `<text>` elements, trimmed.
fn texts(svg: &str) -> Vec<&str> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = &t[t.find('>')? + 1..];
            Some(body[..body.find("</text>")?].trim())
        })
        .collect()
}

/// The band whose legend colour is nearest `c` (and how far, in RGB units): the colour map
/// read backwards.
fn band_of(bands: &Bands, c: [u8; 3]) -> (usize, f64) {
    (0..bands.count())
        .map(|k| {
            let b = bands.colour(k);
            let d2: f64 = (0..3).map(|i| (c[i] as f64 - b[i] as f64).powi(2)).sum();
            (k, d2.sqrt())
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap()
}

/// A work-plane grid and a scattered one, drawn: eight files; in each map, the pixel at every
/// point shows the legend colour of its illuminance's band (read back through the colour
/// map, within one legend step of the CSV's value: exactly its band on the lattice, where the
/// cell is the point's, the brightest point's cell in the top band and the dimmest's in the
/// bottom one; the scattered map is interpolated between points); the isolux SVGs
/// label every level the grid crosses and are whole SVG documents.
#[test]
fn lighting_draws_false_colour_and_isolux_pictures() {
    let dir = scratch("lighting-pictures");
    room(&dir);
    let text = run_ok(
        &[
            "lighting",
            "room.obj",
            "--luminaires",
            "schedule.csv",
            "--grid",
            "desk.pts",
            "--workplane",
            "floor",
            "--out",
            "grid.csv",
            "--pictures",
            "pics/new",
            "--patches",
            "300",
        ],
        &dir,
    );
    let pics = dir.join("pics/new");
    let names = [
        "desk-illuminance",
        "desk-isolux",
        "workplane-floor-illuminance",
        "workplane-floor-isolux",
    ];
    for n in names {
        for ext in ["png", "svg"] {
            let p = pics.join(format!("{n}.{ext}"));
            assert!(p.is_file(), "{} missing", p.display());
            assert!(
                text.contains(&p.strip_prefix(&dir).unwrap().display().to_string()),
                "{text}"
            );
        }
    }
    let (points, e) = grid(&dir);
    assert_eq!(points.len(), 60 + 40);
    let ranges = [
        ("desk.pts".to_string(), 0..60),
        ("workplane floor".to_string(), 60..100),
    ];
    let layout = GridPictures::prepare(
        &pics,
        &ranges,
        &[PathBuf::from("desk.pts")],
        &points,
        Up::Z,
        "m",
    )
    .unwrap();
    for ((stem, plane, frame), (_, range)) in layout.frames().into_iter().zip(&ranges) {
        let values = &e[range.clone()];
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        assert!(
            hi > 5.0 * lo,
            "{stem}: {lo}–{hi} lx is not a test of colours"
        );
        let bands = Bands::new(lo, hi, Scale::Linear);
        let step = bands.levels[1] - bands.levels[0];
        let img = image::open(pics.join(format!("{stem}-illuminance.png")))
            .unwrap()
            .to_rgb8();
        assert_eq!(img.dimensions(), frame.size);
        let lattice = stem.starts_with("workplane");
        let mut seen = 0;
        for (p, &v) in points[range.clone()].iter().zip(values) {
            let (x, y) = frame.pixel(plane.project(p.position));
            let c = img.get_pixel(x as u32, y as u32).0;
            if c == [255, 255, 255] && !lattice {
                continue; // on the hull's edge: the cell's centre is outside
            }
            seen += 1;
            let (k, off) = band_of(&bands, c);
            assert!(off < 1.0, "{stem}: ({x}, {y}) is {c:?}, no legend colour");
            let (l0, l1) = (bands.levels[k], bands.levels[k + 1]);
            assert!(
                v >= l0 - step && v <= l1 + step,
                "{stem}: {v} lx shown in the band {l0}–{l1}"
            );
            if lattice {
                assert_eq!(k, bands.band(v), "{stem}: {v} lx");
            }
            if lattice && v == hi {
                assert_eq!(k, bands.count() - 1, "{stem}: the brightest point");
            }
            if lattice && v == lo {
                assert_eq!(k, 0, "{stem}: the dimmest point");
            }
        }
        assert!(seen >= range.len() * 3 / 4, "{stem}: {seen} points inside");
        for kind in ["illuminance", "isolux"] {
            let svg = read(&pics, &format!("{stem}-{kind}.svg"));
            assert!(svg.trim_start().starts_with("<svg"), "{stem}-{kind}");
            assert!(svg.trim_end().ends_with("</svg>"), "{stem}-{kind}");
            assert_eq!(svg.matches("<text").count(), svg.matches("</text>").count());
            assert!(!svg.contains("NaN"), "{stem}-{kind}");
            assert!(texts(&svg).contains(&"lx"), "{stem}-{kind}: the unit");
        }
        let iso = read(&pics, &format!("{stem}-isolux.svg"));
        let iso_texts = texts(&iso);
        let crossed = bands.crossed(lo, hi);
        assert!(crossed.len() >= 4, "{stem}: {crossed:?}");
        assert!(iso.matches("<polyline").count() >= crossed.len(), "{stem}");
        for k in crossed {
            let label = bands.label(k);
            assert!(
                iso_texts.contains(&label.as_str()),
                "{stem}: no line labelled {label}"
            );
            let row = format!("{label} lx");
            assert!(
                iso_texts.contains(&row.as_str()),
                "{stem}: no legend row {row}"
            );
        }
    }
}

/// `--pictures` at a file, a grid on two planes and one on a line: one line each, naming the
/// problem, before any work (no grid.csv written).
#[test]
fn lighting_pictures_refuse_bad_input() {
    let dir = scratch("lighting-pictures-bad");
    room(&dir);
    write(&dir, "taken", "a file\n");
    write(
        &dir,
        "two-planes.pts",
        "1 1 0.8 0 0 1\n2 1 0.8 0 0 1\n1 2 0.8 0 0 1\n2 2 0.8 0 0 1\n0 1 1 1 0 0\n0 2 1 1 0 0\n0 1 2 1 0 0\n",
    );
    write(
        &dir,
        "line.pts",
        "1 1 0.8 0 0 1\n2 1 0.8 0 0 1\n3 1 0.8 0 0 1\n",
    );
    let keep = [
        "room.obj",
        "room.mtl",
        "iso.ies",
        "schedule.csv",
        "desk.pts",
        "taken",
        "two-planes.pts",
        "line.pts",
    ];
    let args = |grid: &str, pictures: &str| {
        [
            "lighting",
            "room.obj",
            "--luminaires",
            "schedule.csv",
            "--grid",
            grid,
            "--out",
            "grid.csv",
            "--pictures",
            pictures,
        ]
        .map(String::from)
    };
    for (grid, pictures, needles) in [
        (
            "desk.pts",
            "taken",
            vec!["--pictures taken", "not a folder"],
        ),
        (
            "desk.pts",
            "taken/pics",
            vec!["--pictures taken/pics", "not a folder"],
        ),
        (
            "two-planes.pts",
            "pics",
            vec!["two-planes.pts", "not on one plane"],
        ),
        ("line.pts", "pics", vec!["line.pts", "line"]),
    ] {
        let a = args(grid, pictures);
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        fails(&a, &dir, &needles, &keep);
    }
}

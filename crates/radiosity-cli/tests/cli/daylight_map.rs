//! `radiosity lighting --sky … --pictures DIR`: each grid's daylight-factor map, decoded and
//! read back through its colour map against the CSV's `daylight_factor`, and the bad folder
//! refused before any work.

use crate::common::*;
use radiosity::lighting::{SensorPoint, Up};
use radiosity_cli::false_colour::grid::{map_scale, GridPictures};
use radiosity_cli::false_colour::{Bands, Scale};
use std::path::{Path, PathBuf};

/// The points of a 12 × 8 lattice of cell centres over the 6 × 4 m floor, at 0.8 m facing up.
fn lattice(dir: &Path) {
    let mut pts = String::new();
    for j in 0..8 {
        for i in 0..12 {
            pts += &format!(
                "{} {} 0.8 0 0 1\n",
                0.25 + 0.5 * i as f64,
                0.25 + 0.5 * j as f64
            );
        }
    }
    write(dir, "desk.pts", &pts);
}

/// A black 6 × 4 × 3 m box facing in, its ceiling open over x 2…4, y 1.5…2.5.
fn skylit_room(dir: &Path) {
    let mut obj = String::from("mtllib room.mtl\nusemtl black\n");
    let mut k = 0;
    let mut rect = |o: [f64; 3], u: [f64; 3], v: [f64; 3]| {
        for c in [
            o,
            [o[0] + u[0], o[1] + u[1], o[2] + u[2]],
            [o[0] + u[0] + v[0], o[1] + u[1] + v[1], o[2] + u[2] + v[2]],
            [o[0] + v[0], o[1] + v[1], o[2] + v[2]],
        ] {
            obj += &format!("v {} {} {}\n", c[0], c[1], c[2]);
        }
        obj += &format!("f {} {} {} {}\n", k + 1, k + 2, k + 3, k + 4);
        k += 4;
    };
    rect([0.0; 3], [6.0, 0.0, 0.0], [0.0, 4.0, 0.0]); // floor, up
    rect([0.0; 3], [0.0, 0.0, 3.0], [6.0, 0.0, 0.0]); // y = 0, facing +y
    rect([0.0, 4.0, 0.0], [6.0, 0.0, 0.0], [0.0, 0.0, 3.0]); // y = 4, facing −y
    rect([0.0; 3], [0.0, 4.0, 0.0], [0.0, 0.0, 3.0]); // x = 0, facing +x
    rect([6.0, 0.0, 0.0], [0.0, 0.0, 3.0], [0.0, 4.0, 0.0]); // x = 6, facing −x
                                                             // The ceiling, facing down, around its opening.
    for (x0, x1, y0, y1) in [
        (0.0, 2.0, 0.0, 4.0),
        (4.0, 6.0, 0.0, 4.0),
        (2.0, 4.0, 0.0, 1.5),
        (2.0, 4.0, 2.5, 4.0),
    ] {
        rect([x0, y0, 3.0], [0.0, y1 - y0, 0.0], [x1 - x0, 0.0, 0.0]);
    }
    write(dir, "room.obj", &obj);
    write(dir, "room.mtl", "newmtl black\nKd 0 0 0\n");
}

/// The CSV's points and daylight factors.
fn daylight_factors(dir: &Path) -> (Vec<SensorPoint>, Vec<f64>) {
    let (header, rows) = read_csv(&dir.join("grid.csv"));
    let df = column(&header, "daylight_factor");
    rows.iter()
        .map(|r| {
            let v: Vec<f64> = r.iter().map(|t| t.parse().unwrap()).collect();
            (
                SensorPoint::new([v[0], v[1], v[2]], [v[3], v[4], v[5]]).unwrap(),
                v[df],
            )
        })
        .unzip()
}

/// The decoded map and, per point, the colour of its pixel and the grid's bands.
fn map_colours(dir: &Path, points: &[SensorPoint], df: &[f64]) -> (Vec<[u8; 3]>, Bands) {
    let pics = dir.join("pics");
    let ranges = [("desk.pts".to_string(), 0..points.len())];
    let layout = GridPictures::prepare(
        &pics,
        &ranges,
        &[PathBuf::from("desk.pts")],
        points,
        Up::Z,
        "m",
    )
    .unwrap();
    let (stem, plane, frame) = layout.frames().remove(0);
    assert_eq!(stem, "desk");
    let (lo, hi) = df
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let img = image::open(pics.join("desk-daylight-factor.png"))
        .unwrap()
        .to_rgb8();
    assert_eq!(img.dimensions(), frame.size);
    let colours = points
        .iter()
        .map(|p| {
            let (x, y) = frame.pixel(plane.project(p.position));
            img.get_pixel(x as u32, y as u32).0
        })
        .collect();
    let svg = read(&pics, "desk-daylight-factor.svg");
    assert!(svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains("daylight factor"), "the title");
    assert!(svg.contains(">%<") || svg.contains(">\n%") || svg.contains("%</text>"));
    (colours, Bands::new(lo, hi, map_scale(lo, hi, true)))
}

/// Under a uniform sky an open floor's points see the whole sky: DF = 100 % at every point
/// (every ray escapes; π/N Σ L over N rays is πL exactly), and the map is one colour, the
/// legend's colour of 100 %.
#[test]
fn an_unobstructed_grid_is_one_colour() {
    let dir = scratch("daylight-map-open");
    write(
        &dir,
        "floor.obj",
        "mtllib floor.mtl\nusemtl grey\nv 0 0 0\nv 6 0 0\nv 6 4 0\nv 0 4 0\nf 1 2 3 4\n",
    );
    write(&dir, "floor.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
    lattice(&dir);
    let text = run_ok(
        &[
            "lighting",
            "floor.obj",
            "--sky",
            "uniform",
            "--grid",
            "desk.pts",
            "--out",
            "grid.csv",
            "--pictures",
            "pics",
            "--sky-rays",
            "256",
            "--patches",
            "4",
        ],
        &dir,
    );
    assert!(text.contains("desk-daylight-factor.png"), "{text}");
    let (points, df) = daylight_factors(&dir);
    assert_eq!(points.len(), 96);
    for v in &df {
        assert!((v - 100.0).abs() < 1e-9, "{v}");
    }
    let (colours, bands) = map_colours(&dir, &points, &df);
    assert_eq!(bands.scale, Scale::Linear);
    let want = bands.colour(bands.band(100.0));
    for c in colours {
        assert_eq!(c, want);
    }
}

/// A black room lit through a roof opening: the daylight factor is the sky component alone,
/// highest under the opening; every point's pixel shows the legend colour of its own band
/// (a lattice: the cell is the point's), the brightest in the top band, the dimmest in the
/// bottom one.
#[test]
fn the_map_shows_each_points_daylight_factor() {
    let dir = scratch("daylight-map-roof");
    skylit_room(&dir);
    lattice(&dir);
    run_ok(
        &[
            "lighting",
            "room.obj",
            "--sky",
            "cie-overcast",
            "--grid",
            "desk.pts",
            "--out",
            "grid.csv",
            "--pictures",
            "pics",
            "--sky-rays",
            "1024",
            "--patches",
            "50",
        ],
        &dir,
    );
    let (points, df) = daylight_factors(&dir);
    let (lo, hi) = df
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    assert!(
        hi > 5.0 * lo && lo > 0.0,
        "{lo}–{hi} % is not a test of colours"
    );
    let (colours, bands) = map_colours(&dir, &points, &df);
    assert!(bands.count() >= 4, "{:?}", bands.levels);
    for (c, &v) in colours.iter().zip(&df) {
        let k = (0..bands.count())
            .find(|&k| bands.colour(k) == *c)
            .unwrap_or_else(|| panic!("{c:?} is no legend colour"));
        assert_eq!(k, bands.band(v), "{v} %");
        if v == hi {
            assert_eq!(k, bands.count() - 1);
        }
        if v == lo {
            assert_eq!(k, 0);
        }
    }
}

/// `--pictures` at a file with `--sky`: one line naming it, before any work (no grid.csv).
#[test]
fn a_daylight_map_into_a_file_is_refused() {
    let dir = scratch("daylight-map-bad");
    skylit_room(&dir);
    lattice(&dir);
    write(&dir, "taken", "a file\n");
    fails(
        &[
            "lighting",
            "room.obj",
            "--sky",
            "uniform",
            "--grid",
            "desk.pts",
            "--out",
            "grid.csv",
            "--pictures",
            "taken/pics",
        ],
        &dir,
        &["--pictures taken/pics", "not a folder"],
        &["room.obj", "room.mtl", "desk.pts", "taken"],
    );
}

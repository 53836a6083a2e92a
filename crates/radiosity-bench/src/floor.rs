//! `radiosity-bench daylight-floor`: issue 58's annual benchmark, an office floor of side-lit
//! rooms, its work-plane grid and a synthetic year, written as files, and the time of
//! `radiosity lighting FLOOR.obj --weather year.epw --grid floor.pts --annual annual.csv` on
//! them (a child process: CPU and wall seconds, peak memory).
//!
//! **The floor.** Two rows of rooms along a corridor, z up, north +y. Each room is 4.5 m wide
//! (x), 6 m deep (y), 3 m high, walls 0.1 m thick (rooms 4.6 m apart); the south row spans
//! y = 0…6 and looks south through its façade at y = 0, the north row y = 8.2…14.2 looks north
//! through y = 14.2, the corridor (2 m wide, y = 6.1…8.1) has a window at each end. A room's
//! window is 3.5 × 1.5 m (sill 0.9 m, head 2.4 m) centred in its façade, glazed with a clear
//! pane of normal transmittance 0.7 (MTL `d 0.3`). Every space is a box of one-sided polygons
//! facing in: floor ρ = 0.2, walls 0.5, ceiling 0.8 (grey). No doors: each room is lit by its
//! own window only.
//!
//! **The grid.** `per_room` points at 0.8 m in each room on a regular lattice of cell
//! centres, facing up (500 a room: 20 across the width × 25 into the depth, 0.225 × 0.24 m).
//!
//! **The year** ([`synthetic_year`]): a deterministic EPW year at 52° N, 0° E (GMT) built from
//! the sun's position (`daylight::solar`) and the Meinel & Meinel (1976) clear-sky beam
//! irradiance I = 1353 × 0.7^(AM^0.678) W/m² (AM = 1/sin α, the plane-parallel air mass), a
//! day clear with probability 0.4 from a fixed-seed generator: a clear hour has direct normal
//! I and diffuse horizontal 0.1 I (the clear-sky diffuse share); an overcast hour no direct
//! and diffuse horizontal 0.3 I sin α (a quarter to a third of the clear global). Night hours
//! (sun below the horizon at mid-hour) are 0.

use crate::args::FloorArgs;
use anyhow::{bail, Context, Result};
use radiosity::daylight::solar::{solar_position, Site};
use std::fmt::Write as _;

/// Inner width (x), depth (y), height of a room, and the walls' thickness, metres.
const ROOM: (f64, f64, f64) = (4.5, 6.0, 3.0);
const WALL: f64 = 0.1;
/// The corridor's width.
const CORRIDOR: f64 = 2.0;
/// A window's width, sill and head heights.
const WINDOW: (f64, f64, f64) = (3.5, 0.9, 2.4);
/// The work plane's height.
const WORK_PLANE: f64 = 0.8;

/// An OBJ being written: vertices and faces, a material at a time.
struct Obj {
    text: String,
    vertices: usize,
}

impl Obj {
    /// The rectangle o, o + u, o + u + v, o + v (front side u × v).
    fn rect(&mut self, o: [f64; 3], u: [f64; 3], v: [f64; 3]) {
        for c in [
            o,
            [o[0] + u[0], o[1] + u[1], o[2] + u[2]],
            [o[0] + u[0] + v[0], o[1] + u[1] + v[1], o[2] + u[2] + v[2]],
            [o[0] + v[0], o[1] + v[1], o[2] + v[2]],
        ] {
            let _ = writeln!(self.text, "v {} {} {}", c[0], c[1], c[2]);
        }
        let k = self.vertices;
        let _ = writeln!(self.text, "f {} {} {} {}", k + 1, k + 2, k + 3, k + 4);
        self.vertices += 4;
    }

    fn material(&mut self, name: &str) {
        let _ = writeln!(self.text, "usemtl {name}");
    }

    /// A wall in the plane y = `y` over x0…x1, z 0…h, facing +y (`north` false) or −y, with
    /// an opening x wx0…wx1, z z0…z1 (when given) left out: four rectangles around it.
    fn wall_y(&mut self, y: f64, x: [f64; 2], h: f64, faces_north: bool, hole: Option<[f64; 4]>) {
        let mut piece = |x0: f64, x1: f64, z0: f64, z1: f64| {
            if x1 <= x0 || z1 <= z0 {
                return;
            }
            let (u, v) = ([x1 - x0, 0.0, 0.0], [0.0, 0.0, z1 - z0]);
            // x × z = −y.
            if faces_north {
                self.rect([x0, y, z0], v, u);
            } else {
                self.rect([x0, y, z0], u, v);
            }
        };
        match hole {
            None => piece(x[0], x[1], 0.0, h),
            Some([wx0, wx1, z0, z1]) => {
                piece(x[0], x[1], 0.0, z0);
                piece(x[0], x[1], z1, h);
                piece(x[0], wx0, z0, z1);
                piece(wx1, x[1], z0, z1);
            }
        }
    }

    /// A wall in the plane x = `x` over y0…y1, z 0…h, facing +x or −x, with an optional
    /// opening y wy0…wy1, z z0…z1.
    fn wall_x(&mut self, x: f64, y: [f64; 2], h: f64, faces_east: bool, hole: Option<[f64; 4]>) {
        let mut piece = |y0: f64, y1: f64, z0: f64, z1: f64| {
            if y1 <= y0 || z1 <= z0 {
                return;
            }
            let (u, v) = ([0.0, y1 - y0, 0.0], [0.0, 0.0, z1 - z0]);
            // y × z = +x.
            if faces_east {
                self.rect([x, y0, z0], u, v);
            } else {
                self.rect([x, y0, z0], v, u);
            }
        };
        match hole {
            None => piece(y[0], y[1], 0.0, h),
            Some([wy0, wy1, z0, z1]) => {
                piece(y[0], y[1], 0.0, z0);
                piece(y[0], y[1], z1, h);
                piece(y[0], wy0, z0, z1);
                piece(wy1, y[1], z0, z1);
            }
        }
    }

    /// A box x0…x1 × y0…y1 × 0…h facing in, its walls' openings by side (south, north, west,
    /// east: the opening's two horizontal bounds), the panes in them.
    fn room(&mut self, x: [f64; 2], y: [f64; 2], h: f64, holes: [Option<[f64; 2]>; 4]) {
        let (sill, head) = (WINDOW.1, WINDOW.2);
        let hole = |s: usize| holes[s].map(|[a, b]| [a, b, sill, head]);
        self.material("floor");
        self.rect(
            [x[0], y[0], 0.0],
            [x[1] - x[0], 0.0, 0.0],
            [0.0, y[1] - y[0], 0.0],
        );
        self.material("ceiling");
        self.rect(
            [x[0], y[0], h],
            [0.0, y[1] - y[0], 0.0],
            [x[1] - x[0], 0.0, 0.0],
        );
        self.material("wall");
        self.wall_y(y[0], x, h, true, hole(0));
        self.wall_y(y[1], x, h, false, hole(1));
        self.wall_x(x[0], y, h, true, hole(2));
        self.wall_x(x[1], y, h, false, hole(3));
        self.material("glass");
        for (s, o) in holes.iter().enumerate() {
            let Some([a, b]) = *o else { continue };
            let (dz, da) = (head - sill, b - a);
            match s {
                0 => self.rect([a, y[0], sill], [0.0, 0.0, dz], [da, 0.0, 0.0]),
                1 => self.rect([a, y[1], sill], [da, 0.0, 0.0], [0.0, 0.0, dz]),
                2 => self.rect([x[0], a, sill], [0.0, da, 0.0], [0.0, 0.0, dz]),
                _ => self.rect([x[1], a, sill], [0.0, 0.0, dz], [0.0, da, 0.0]),
            }
        }
    }
}

/// The rooms' interiors, x0…x1 × y0…y1, and whether each looks south.
fn rooms(count: usize) -> Vec<([f64; 2], [f64; 2], bool)> {
    let per_row = count.div_ceil(2);
    let north_y0 = ROOM.1 + WALL + CORRIDOR + WALL;
    (0..count)
        .map(|r| {
            let (row, i) = (r / per_row, r % per_row);
            let x0 = WALL + i as f64 * (ROOM.0 + WALL);
            let y0 = if row == 0 { 0.0 } else { north_y0 };
            ([x0, x0 + ROOM.0], [y0, y0 + ROOM.1], row == 0)
        })
        .collect()
}

/// The floor of `count` rooms as OBJ text (with `mtllib floor.mtl`) and its MTL.
pub fn floor_obj(count: usize) -> (String, String) {
    let mut obj = Obj {
        text: format!(
            "# radiosity-bench daylight-floor: {count} side-lit rooms along a corridor, z up, north +y\nmtllib floor.mtl\n"
        ),
        vertices: 0,
    };
    for (x, y, south) in rooms(count) {
        let mid = 0.5 * (x[0] + x[1]);
        let w = [mid - 0.5 * WINDOW.0, mid + 0.5 * WINDOW.0];
        let holes = if south {
            [Some(w), None, None, None]
        } else {
            [None, Some(w), None, None]
        };
        obj.room(x, y, ROOM.2, holes);
    }
    let per_row = count.div_ceil(2);
    let length = per_row as f64 * (ROOM.0 + WALL) - WALL;
    let cy = [ROOM.1 + WALL, ROOM.1 + WALL + CORRIDOR];
    let end = [cy[0] + 0.25, cy[1] - 0.25];
    obj.room(
        [WALL, WALL + length],
        cy,
        ROOM.2,
        [None, None, Some(end), Some(end)],
    );
    let mtl = "newmtl floor\nKd 0.2 0.2 0.2\nnewmtl wall\nKd 0.5 0.5 0.5\n\
               newmtl ceiling\nKd 0.8 0.8 0.8\nnewmtl glass\nKd 0 0 0\nd 0.3\n"
        .to_string();
    (obj.text, mtl)
}

/// `per_room` work-plane points a room (a lattice of cell centres, as square as the room
/// allows: columns across the width, rows into the depth), one `x y z 0 0 1` line each.
pub fn floor_points(count: usize, per_room: usize) -> String {
    let (nx, ny) = lattice(per_room);
    let mut s = String::new();
    for (x, y, _) in rooms(count) {
        for j in 0..ny {
            for i in 0..nx {
                let px = x[0] + (i as f64 + 0.5) * (x[1] - x[0]) / nx as f64;
                let py = y[0] + (j as f64 + 0.5) * (y[1] - y[0]) / ny as f64;
                let _ = writeln!(s, "{px:.4} {py:.4} {WORK_PLANE} 0 0 1");
            }
        }
    }
    s
}

/// Columns and rows of a lattice of exactly `n` points over a room, the cells nearest square:
/// the divisor pair of n whose cell aspect is closest to 1.
fn lattice(n: usize) -> (usize, usize) {
    (1..=n)
        .filter(|a| n % a == 0)
        .map(|a| (a, n / a))
        .min_by(|p, q| {
            let aspect =
                |(a, b): (usize, usize)| ((ROOM.0 / a as f64) / (ROOM.1 / b as f64)).ln().abs();
            aspect(*p).total_cmp(&aspect(*q))
        })
        .unwrap_or((1, 1))
}

/// The synthetic year described in the module's documentation, as EPW text: 8,760 hours of
/// 2005 at 52° N, 0° E, time zone 0, dew point 8 °C; `seed` drives the clear/overcast days.
pub fn synthetic_year(seed: u64) -> String {
    let site = Site {
        latitude: 52.0,
        longitude: 0.0,
        time_zone: 0.0,
    };
    let mut s = String::from(
        "LOCATION,Synthetic 52N,,,radiosity-bench,0,52.0,0.0,0.0,10\nDESIGN CONDITIONS,0\n\
         TYPICAL/EXTREME PERIODS,0\nGROUND TEMPERATURES,0\nHOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\n\
         COMMENTS 1,synthetic: Meinel clear-sky beam; clear days 40 %, overcast otherwise\n\
         COMMENTS 2,\nDATA PERIODS,1,1,Data,Saturday, 1/ 1,12/31\n",
    );
    // SplitMix64: the day's weather.
    let mut state = seed;
    let mut next = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let days = [31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31];
    for month in 1..=12u32 {
        for day in 1..=days[month as usize - 1] {
            let clear = next() < 0.4;
            for hour in 1..=24u32 {
                let pos = solar_position(&site, 2005, month, day, hour as f64 - 0.5);
                let sin_a = pos.altitude.sin();
                let (dni, dhi) = if sin_a <= 0.0 {
                    (0.0, 0.0)
                } else {
                    let beam = 1353.0 * 0.7f64.powf((1.0 / sin_a).powf(0.678));
                    if clear {
                        (beam, 0.1 * beam)
                    } else {
                        (0.0, 0.3 * beam * sin_a)
                    }
                };
                let ghi = dni * sin_a.max(0.0) + dhi;
                let _ = writeln!(
                    s,
                    "2005,{month},{day},{hour},60,x,15,8,60,101325,0,0,300,{ghi:.1},{dni:.1},{dhi:.1}"
                );
            }
        }
    }
    s
}

/// Run the mode: write the files, then (with `--run`) time the annual command on them.
pub fn run(a: &FloorArgs) -> Result<()> {
    crate::positive(&[
        ("--rooms", a.rooms),
        ("--points-per-room", a.points_per_room),
    ])?;
    if a.rooms < 2 || a.rooms % 2 != 0 {
        bail!(
            "--rooms {}: must be even and at least 2 (two rows)",
            a.rooms
        );
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}", a.out.display()))?;
    let write = |name: &str, text: &str| -> Result<()> {
        let p = a.out.join(name);
        radiosity::io::write_atomic::<radiosity::io::OutputError>(&p, |w| {
            std::io::Write::write_all(w, text.as_bytes())
        })
        .with_context(|| format!("{}", p.display()))
    };
    let (obj, mtl) = floor_obj(a.rooms);
    write("floor.obj", &obj)?;
    write("floor.mtl", &mtl)?;
    write("floor.pts", &floor_points(a.rooms, a.points_per_room))?;
    write("year.epw", &synthetic_year(a.seed))?;
    let n = a.rooms * a.points_per_room;
    println!(
        "wrote       {}/floor.obj, floor.mtl, floor.pts ({n} points), year.epw",
        a.out.display()
    );
    if !a.run {
        return Ok(());
    }
    let exe = crate::radiosity_exe()?;
    let mut cmd = std::process::Command::new(&exe);
    let path = |f: &str| a.out.join(f);
    cmd.arg("lighting")
        .arg(path("floor.obj"))
        .arg("--weather")
        .arg(path("year.epw"))
        .arg("--grid")
        .arg(path("floor.pts"))
        .arg("--annual")
        .arg(path("annual.csv"))
        .arg("--summary")
        .arg(path("summary.json"))
        .args(&a.extra);
    let u = crate::view3d::run_measured(cmd, &path("lighting.log"))?;
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(path("summary.json")).context("summary.json")?,
    )?;
    let secs = &summary["seconds"];
    let g = &summary["annual"]["grids"][0];
    println!(
        "annual      {n} points, {} patches: cpu {:.1} s, wall {:.1} s (coefficients {:.1} s, year {:.1} s), peak {:.0} MiB",
        summary["patches"], u.cpu, u.wall, secs["coefficients"].as_f64().unwrap_or(f64::NAN),
        secs["year"].as_f64().unwrap_or(f64::NAN), u.peak_mib
    );
    println!(
        "metrics     sDA {:.1} %, ASE {:.1} %, UDI useful {:.1} %",
        100.0 * g["sda"].as_f64().unwrap_or(f64::NAN),
        100.0 * g["ase"].as_f64().unwrap_or(f64::NAN),
        100.0 * g["udi"]["useful"].as_f64().unwrap_or(f64::NAN)
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use radiosity::daylight::epw::parse_epw;
    use radiosity::geom::Vec3;
    use radiosity::scene::Polygon;

    /// A planar polygon's area vector (Newell): its normal times its area.
    fn area_vector(p: &Polygon) -> Vec3 {
        let v = &p.vertices;
        (1..v.len() - 1).fold(Vec3::ZERO, |a, i| {
            a + 0.5 * (v[i] - v[0]).cross(v[i + 1] - v[0])
        })
    }

    #[test]
    fn the_floor_has_its_rooms_windows_and_points() {
        let (obj, mtl) = floor_obj(20);
        let dir = std::env::temp_dir().join(format!("floor-bench-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("floor.obj"), &obj).unwrap();
        std::fs::write(dir.join("floor.mtl"), &mtl).unwrap();
        let scene = radiosity::scene::obj::load(&dir.join("floor.obj")).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        let glass = scene
            .materials
            .iter()
            .position(|m| m.name == "glass")
            .unwrap();
        assert!((scene.materials[glass].transmittance - 0.7).abs() < 1e-12);
        // 20 rooms and the corridor: a floor, a ceiling, a plain wall's 1 + 3 × 1 and the
        // façade's 4 pieces, and a pane; the corridor has two ends of 4 pieces, two panes.
        let panes = scene
            .polygons
            .iter()
            .filter(|p| p.material == glass)
            .count();
        assert_eq!(panes, 22);
        assert_eq!(scene.polygons.len(), 20 * (2 + 3 + 4 + 1) + (2 + 2 + 8 + 2));
        // Every room's interior: floor area 4.5 × 6; the glazed area 22 panes (20 of 3.5 ×
        // 1.5 and the corridor's 1.5 × 1.5).
        let area = |m: usize| -> f64 {
            scene
                .polygons
                .iter()
                .filter(|p| p.material == m)
                .map(|p| area_vector(p).length() as f64)
                .sum()
        };
        let floor = scene
            .materials
            .iter()
            .position(|m| m.name == "floor")
            .unwrap();
        let length = 10.0 * 4.6 - 0.1;
        assert!((area(floor) - (20.0 * 27.0 + length * 2.0)).abs() < 1e-3);
        assert!((area(glass) - (20.0 * 5.25 + 2.0 * 1.5 * 1.5)).abs() < 1e-3);
        // Faces point into their rooms: every floor polygon up, ceiling down.
        for p in scene.polygons.iter().filter(|p| p.material == floor) {
            assert!(area_vector(p).normalize().z > 0.99);
        }
        let pts = floor_points(20, 500);
        let lines: Vec<&str> = pts.lines().collect();
        assert_eq!(lines.len(), 10_000);
        assert_eq!(lattice(500), (20, 25));
        // Inside the rooms, at 0.8 m.
        for l in &lines {
            let v: Vec<f64> = l.split(' ').map(|t| t.parse().unwrap()).collect();
            assert_eq!(v[2], 0.8);
            assert!(rooms(20)
                .iter()
                .any(|(x, y, _)| x[0] < v[0] && v[0] < x[1] && y[0] < v[1] && v[1] < y[1]));
        }
    }

    #[test]
    fn the_synthetic_year_reads_and_is_deterministic() {
        let text = synthetic_year(58);
        assert_eq!(text, synthetic_year(58));
        let epw = parse_epw(&text, "year.epw").unwrap();
        assert_eq!(epw.records.len(), 8760);
        let site = Site {
            latitude: 52.0,
            longitude: 0.0,
            time_zone: 0.0,
        };
        let (mut clear_days, mut lit) = (0, 0);
        for (h, r) in epw.records.iter().enumerate() {
            let pos = solar_position(&site, 2005, r.month, r.day, r.mid_hour());
            let (dni, dhi) = (r.direct_normal.unwrap(), r.diffuse_horizontal.unwrap());
            if pos.altitude <= 0.0 {
                assert_eq!((dni, dhi), (0.0, 0.0), "hour {h}");
                continue;
            }
            lit += 1;
            let beam = 1353.0 * 0.7f64.powf((1.0 / pos.altitude.sin()).powf(0.678));
            if dni > 0.0 {
                assert!((dni - beam).abs() < 0.051 && (dhi - 0.1 * beam).abs() < 0.051);
                if h % 24 == 12 {
                    clear_days += 1;
                }
            } else {
                assert!((dhi - 0.3 * beam * pos.altitude.sin()).abs() < 0.051);
            }
        }
        // Daylight hours at 52° N average 12 h a day; clear days 40 % ± 3σ (σ = √(365·0.24)).
        assert!((4300..4500).contains(&lit), "{lit}");
        assert!(
            (clear_days as f64 - 146.0).abs() < 3.0 * 9.4,
            "{clear_days}"
        );
    }
}

//! The pictures of `radiosity lighting --pictures DIR`: for each calculation grid, a
//! false-colour illuminance map (`<stem>-illuminance.png`, `.svg`) and an isolux plot
//! (`<stem>-isolux.png`, `.svg`), each with its legend in lux, the grid's name and its
//! summary (Ē, E_min, E_max, U₀ = E_min/Ē) on top, axes in scene units.
//!
//! A grid is drawn in its plane ([`GridPlane`]). Points on a regular lattice along the
//! drawing axes (the work-plane grid) are drawn as their cells, one flat band colour a cell,
//! and the isolines are those of the bilinear interpolant between the nodes: marching
//! squares on the lattice subdivided to about 100 nodes a side ([`Field::refined`]). Other
//! points are triangulated (Delaunay) and interpolated linearly within each triangle, exact
//! for a linear field and never beyond the neighbours' values, onto a raster of 200 cells
//! along the grid's longer side; only cells whose centre lies in the points' convex hull are
//! drawn, and the isolines are marching squares on that raster. The isolux plot shows the
//! grid's area in light grey, its points as dots (up to 20,000 of them), and each isoline in
//! its level's colour, labelled with its level.

use super::contour::{isolines, Polyline};
use super::delaunay::triangulate;
use super::lattice::{detect, Field};
use super::plane::GridPlane;
use super::{
    draw_band_legend, draw_header, register_font, rgb, write_png, Bands, DrawResult, Scale, HEADER,
    LEGEND_WIDTH,
};
use anyhow::{bail, Context, Result};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor;
use radiosity::io::{write_atomic, OutputError};
use radiosity::lighting::{SensorPoint, Up};
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// The chart's margin, pixels.
const MARGIN: u32 = 14;
/// Height of the x axis's labels, pixels.
const X_LABELS: u32 = 48;
/// Width of the y axis's labels, pixels.
const Y_LABELS: u32 = 70;
/// Raster cells along the longer side of a scattered grid.
const RASTER: f64 = 200.0;

/// Where a grid picture puts its plot: the picture's size, the plotted ranges along the
/// drawing axes (one scale both ways) and the plotting area's pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct MapFrame {
    /// The picture's width and height, pixels.
    pub size: (u32, u32),
    /// The plotted range along u (to the right).
    pub u: Range<f64>,
    /// The plotted range along v (up the page).
    pub v: Range<f64>,
    /// The plotting area's first and last pixel columns.
    pub columns: (i32, i32),
    /// The plotting area's first and last pixel rows.
    pub rows: (i32, i32),
}

impl MapFrame {
    /// The frame for content spanning `lo..hi` along (u, v): one scale both ways, the
    /// plotting area at most 752 × 760 pixels and at least 452 × 260 (the content centred
    /// where its aspect leaves room), the picture as wide as the plot, its axes and legend.
    pub fn of(lo: [f64; 2], hi: [f64; 2]) -> MapFrame {
        let (most, least) = ((752.0, 760.0), (452.0, 260.0));
        let du = (hi[0] - lo[0]).max(1e-12);
        let dv = (hi[1] - lo[1]).max(1e-12);
        let s = (most.0 / du).min(most.1 / dv);
        let pw = (s * du).round().clamp(least.0, most.0) as u32;
        let ph = (s * dv).round().clamp(least.1, most.1) as u32;
        let size = (
            pw + 2 * MARGIN + Y_LABELS + LEGEND_WIDTH,
            HEADER + 2 * MARGIN + X_LABELS + ph,
        );
        let (cu, cv) = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]));
        let (hu, hv) = (0.5 * pw as f64 / s, 0.5 * ph as f64 / s);
        let x0 = (MARGIN + Y_LABELS) as i32;
        let y0 = (HEADER + MARGIN) as i32;
        MapFrame {
            size,
            u: cu - hu..cu + hu,
            v: cv - hv..cv + hv,
            columns: (x0, x0 + pw as i32 - 1),
            rows: (y0, y0 + ph as i32 - 1),
        }
    }

    /// The pixel showing the point (u, v) (plotters' mapping).
    pub fn pixel(&self, p: [f64; 2]) -> (i32, i32) {
        let tu = (p[0] - self.u.start) / (self.u.end - self.u.start);
        let tv = (p[1] - self.v.start) / (self.v.end - self.v.start);
        let x =
            self.columns.0 + ((self.columns.1 - self.columns.0) as f64 * tu + 1e-3).floor() as i32;
        let y = self.rows.1 + ((self.rows.0 - self.rows.1) as f64 * tv - 1e-3).ceil() as i32;
        (x, y)
    }
}

/// How a grid's values become a field.
enum Layout {
    /// The points are the nodes: point `k` at node `node[k]`.
    Lattice { node: Vec<usize> },
    /// A raster interpolated within the Delaunay triangles: point `k` is vertex
    /// `vertex[k]` (coincident points share one, their values averaged); each covered
    /// raster cell (index) takes weights on three vertices.
    Scattered {
        vertex: Vec<usize>,
        vertices: usize,
        cells: Vec<(usize, [usize; 3], [f64; 3])>,
    },
}

/// One grid, ready to draw once its values are known.
struct Prepared {
    name: String,
    stem: String,
    range: Range<usize>,
    plane: GridPlane,
    uv: Vec<[f64; 2]>,
    /// The field with no values: its lattice.
    field: Field,
    layout: Layout,
}

/// The pictures of every grid of a run: checked and laid out before the computation, drawn
/// after it ([`GridPictures::write`]).
pub struct GridPictures {
    dir: PathBuf,
    unit: String,
    grids: Vec<Prepared>,
}

/// Refuse a `--pictures` path that is not a folder (or the nearest existing folder above a
/// new one): before any work.
pub fn check_dir(dir: &Path) -> Result<()> {
    let mut at = dir.to_path_buf();
    loop {
        match std::fs::metadata(&at) {
            Ok(m) if m.is_dir() => return Ok(()),
            Ok(_) if at == dir => bail!("--pictures {}: is a file, not a folder", dir.display()),
            Ok(_) => bail!(
                "--pictures {}: {} is a file, not a folder",
                dir.display(),
                at.display()
            ),
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
                ) =>
            {
                match at.parent() {
                    Some(p) if !p.as_os_str().is_empty() => at = p.to_path_buf(),
                    _ => return Ok(()),
                }
            }
            Err(e) => bail!("--pictures {}: {e}", dir.display()),
        }
    }
}

/// The bands' scale of a map whose values run from `lo` to `hi`: with `log_if_wide`,
/// logarithmic (1–2–5 a decade) when they are positive and span a decade or more (a
/// daylight factor from 0.5 % at the back of a side-lit room to 20 % at its window), else
/// linear.
pub fn map_scale(lo: f64, hi: f64, log_if_wide: bool) -> Scale {
    if log_if_wide && lo > 0.0 && hi >= 10.0 * lo {
        Scale::Log
    } else {
        Scale::Linear
    }
}

/// A file-name stem from a grid's name: letters, digits, `.`, `_`, `-` kept, the rest `-`.
fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                c
            } else {
                '-'
            }
        })
        .collect()
}

/// A value in lux for the caption: three significant figures down to hundredths.
fn lux(x: f64) -> String {
    if x.abs() >= 100.0 {
        format!("{x:.0}")
    } else if x.abs() >= 10.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.2}")
    }
}

impl GridPictures {
    /// Lay out the pictures of `grids` (a name and its points' range in `points`; the first
    /// `files.len()` are the `--grid` files, named after their stems, the others after their
    /// names) in `dir`, for a scene whose vertical is `up` and whose length unit is `unit`.
    /// Refused, naming the grid: points not on one plane, on a line or at one spot, points that
    /// cannot be triangulated, and two grids whose pictures would share a name.
    pub fn prepare(
        dir: &Path,
        grids: &[(String, Range<usize>)],
        files: &[PathBuf],
        points: &[SensorPoint],
        up: Up,
        unit: &str,
    ) -> Result<GridPictures> {
        let mut prepared: Vec<Prepared> = Vec::new();
        for (k, (name, range)) in grids.iter().enumerate() {
            let stem = match files.get(k) {
                Some(f) => file_stem(&f.file_stem().unwrap_or_default().to_string_lossy()),
                None => file_stem(name),
            };
            if let Some(other) = prepared.iter().find(|p| p.stem == stem) {
                bail!(
                    "--pictures: grids {} and {name} would both be drawn as {}",
                    other.name,
                    dir.join(format!("{stem}-*.png")).display()
                );
            }
            let pts = &points[range.clone()];
            let positions: Vec<[f64; 3]> = pts.iter().map(|p| p.position).collect();
            let normals: Vec<[f64; 3]> = pts.iter().map(|p| p.normal).collect();
            let plane = GridPlane::fit(&positions, &normals, up)
                .map_err(|e| anyhow::anyhow!("--pictures: grid {name}: {e}"))?;
            let uv: Vec<[f64; 2]> = positions.iter().map(|&p| plane.project(p)).collect();
            let (field, layout) = match detect(&uv) {
                Some((field, node)) => (field, Layout::Lattice { node }),
                None => {
                    scattered(&uv).map_err(|e| anyhow::anyhow!("--pictures: grid {name}: {e}"))?
                }
            };
            prepared.push(Prepared {
                name: name.clone(),
                stem,
                range: range.clone(),
                plane,
                uv,
                field,
                layout,
            });
        }
        Ok(GridPictures {
            dir: dir.to_path_buf(),
            unit: unit.to_string(),
            grids: prepared,
        })
    }

    /// Each grid's picture stem, plane and frame, in order: where a point lands in its
    /// pictures (`frame.pixel(plane.project(position))`).
    pub fn frames(&self) -> Vec<(String, GridPlane, MapFrame)> {
        self.grids
            .iter()
            .map(|g| {
                let (lo, hi) = g.extent(&g.field);
                (g.stem.clone(), g.plane.clone(), MapFrame::of(lo, hi))
            })
            .collect()
    }

    /// Draw every grid's two pictures from the illuminance `e` at every point (lux), creating
    /// the folder; each file written atomically. Returns the files written.
    pub fn write(&self, e: &[f64]) -> Result<Vec<PathBuf>> {
        std::fs::create_dir_all(&self.dir)
            .with_context(|| format!("--pictures {}: creating the folder", self.dir.display()))?;
        register_font();
        let mut written = Vec::new();
        for g in &self.grids {
            let values = &e[g.range.clone()];
            let field = g.field_of(values);
            let n = values.len() as f64;
            let mean = values.iter().sum::<f64>() / n;
            let min = values.iter().copied().fold(f64::INFINITY, f64::min);
            let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let u0 = if mean > 0.0 { min / mean } else { 0.0 };
            let how = match &g.layout {
                Layout::Lattice { .. } => format!("{} × {} lattice", field.nu, field.nv),
                Layout::Scattered { .. } => "linear between neighbours".to_string(),
            };
            let caption = format!(
                "Ē = {} lx    E_min = {} lx    E_max = {} lx    U₀ = {u0:.2}    {} points, {how}",
                lux(mean),
                lux(min),
                lux(max),
                values.len()
            );
            let bands = Bands::new(min, max, Scale::Linear);
            // A lattice's isolines are its bilinear interpolant's, traced on the lattice
            // subdivided to about 100 nodes along its longer side.
            let fine = match g.layout {
                Layout::Lattice { .. } => {
                    field.refined((100 / field.nu.max(field.nv)).clamp(1, 16))
                }
                Layout::Scattered { .. } => field.clone(),
            };
            let isolines: Vec<(usize, Vec<Polyline>)> = bands
                .crossed(min, max)
                .into_iter()
                .map(|k| (k, isolines(&fine, bands.levels[k])))
                .collect();
            let (lo, hi) = g.extent(&field);
            let pic = Picture {
                title: String::new(),
                caption,
                axes: g
                    .plane
                    .names
                    .clone()
                    .map(|a| format!("{a} ({})", self.unit)),
                field: &field,
                bands: &bands,
                points: &g.uv,
                isolines,
                frame: MapFrame::of(lo, hi),
                bitmap: false,
                unit: "lx",
            };
            let map = Picture {
                title: format!("{}: illuminance", g.name),
                ..pic.clone()
            };
            written.extend(write_both(
                &self.dir.join(format!("{}-illuminance", g.stem)),
                &map,
                Kind::Map,
            )?);
            let iso = Picture {
                title: format!("{}: isolux lines", g.name),
                ..pic
            };
            written.extend(write_both(
                &self.dir.join(format!("{}-isolux", g.stem)),
                &iso,
                Kind::Isolux,
            )?);
        }
        Ok(written)
    }

    /// Draw every grid's false-colour map of `values` (one a point, in `unit`) as
    /// `<stem>-<suffix>.png` and `.svg`, titled `<grid>: <what>`, in the cells of the
    /// illuminance map, in bands on the scale [`map_scale`] picks for the grid's range
    /// (`log_if_wide`: 1–2–5 a decade when it spans one or more), `caption(grid's values)`
    /// under the title; each file written atomically. Returns the files written.
    pub fn write_maps(
        &self,
        values: &[f64],
        what: &str,
        suffix: &str,
        unit: &'static str,
        log_if_wide: bool,
        caption: impl Fn(&[f64]) -> String,
    ) -> Result<Vec<PathBuf>> {
        std::fs::create_dir_all(&self.dir)
            .with_context(|| format!("--pictures {}: creating the folder", self.dir.display()))?;
        register_font();
        let mut written = Vec::new();
        for g in &self.grids {
            let v = &values[g.range.clone()];
            let field = g.field_of(v);
            let min = v.iter().copied().fold(f64::INFINITY, f64::min);
            let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let bands = Bands::new(min, max, map_scale(min, max, log_if_wide));
            let (lo, hi) = g.extent(&field);
            let pic = Picture {
                title: format!("{}: {what}", g.name),
                caption: caption(v),
                axes: g
                    .plane
                    .names
                    .clone()
                    .map(|a| format!("{a} ({})", self.unit)),
                field: &field,
                bands: &bands,
                points: &g.uv,
                isolines: Vec::new(),
                frame: MapFrame::of(lo, hi),
                bitmap: false,
                unit,
            };
            written.extend(write_both(
                &self.dir.join(format!("{}-{suffix}", g.stem)),
                &pic,
                Kind::Map,
            )?);
        }
        Ok(written)
    }
}

impl Prepared {
    /// The field holding this grid's `values` (its points' in order).
    fn field_of(&self, values: &[f64]) -> Field {
        let mut field = self.field.clone();
        match &self.layout {
            Layout::Lattice { node } => {
                for (&k, &v) in node.iter().zip(values) {
                    field.values[k] = v;
                }
            }
            Layout::Scattered {
                vertex,
                vertices,
                cells,
            } => {
                let mut sum = vec![0.0; *vertices];
                let mut count = vec![0usize; *vertices];
                for (&k, &v) in vertex.iter().zip(values) {
                    sum[k] += v;
                    count[k] += 1;
                }
                let at: Vec<f64> = sum.iter().zip(&count).map(|(s, &c)| s / c as f64).collect();
                for &(cell, v, w) in cells {
                    field.values[cell] = w[0] * at[v[0]] + w[1] * at[v[1]] + w[2] * at[v[2]];
                }
            }
        }
        field
    }

    /// What the pictures span: the cells and the points, with 3 % to spare.
    fn extent(&self, field: &Field) -> ([f64; 2], [f64; 2]) {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let half = [0.5 * field.step[0], 0.5 * field.step[1]];
        for p in &self.uv {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k] - half[k]);
                hi[k] = hi[k].max(p[k] + half[k]);
            }
        }
        let pad = 0.03 * (hi[0] - lo[0]).max(hi[1] - lo[1]);
        ([lo[0] - pad, lo[1] - pad], [hi[0] + pad, hi[1] + pad])
    }
}

/// The raster layout of scattered points: coincident points merged, the rest triangulated,
/// each raster cell whose centre lies in a triangle given its barycentric weights.
fn scattered(uv: &[[f64; 2]]) -> std::result::Result<(Field, Layout), String> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in uv {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    // Points closer than 1e-7 of the grid's size are one vertex.
    let q = 1e-7 * size;
    let mut index: HashMap<(i64, i64), usize> = HashMap::new();
    let mut unique: Vec<[f64; 2]> = Vec::new();
    let vertex: Vec<usize> = uv
        .iter()
        .map(|p| {
            let key = ((p[0] / q).round() as i64, (p[1] / q).round() as i64);
            *index.entry(key).or_insert_with(|| {
                unique.push(*p);
                unique.len() - 1
            })
        })
        .collect();
    let tri = triangulate(&unique).map_err(|e| format!("cannot triangulate its points: {e}"))?;
    let h = size / RASTER;
    let nu = (((hi[0] - lo[0]) / h).ceil() as usize).max(1) + 1;
    let nv = (((hi[1] - lo[1]) / h).ceil() as usize).max(1) + 1;
    let origin = [
        0.5 * (lo[0] + hi[0]) - 0.5 * (nu - 1) as f64 * h,
        0.5 * (lo[1] + hi[1]) - 0.5 * (nv - 1) as f64 * h,
    ];
    let field = Field::empty(origin, [h, h], nu, nv);
    let mut taken = vec![false; nu * nv];
    let mut cells = Vec::new();
    for t in &tri.triangles {
        let [a, b, c] = t.map(|k| unique[k]);
        let area2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if area2 <= 0.0 {
            continue;
        }
        let index_range = |k: usize, n: usize| {
            let lo = a[k].min(b[k]).min(c[k]);
            let hi = a[k].max(b[k]).max(c[k]);
            let i0 = ((lo - origin[k]) / h).ceil().max(0.0) as usize;
            let i1 = (((hi - origin[k]) / h).floor().max(-1.0) + 1.0) as usize;
            i0..i1.min(n)
        };
        for j in index_range(1, nv) {
            for i in index_range(0, nu) {
                let p = field.node(i, j);
                let w = [
                    ((b[0] - p[0]) * (c[1] - p[1]) - (b[1] - p[1]) * (c[0] - p[0])) / area2,
                    ((c[0] - p[0]) * (a[1] - p[1]) - (c[1] - p[1]) * (a[0] - p[0])) / area2,
                    ((a[0] - p[0]) * (b[1] - p[1]) - (a[1] - p[1]) * (b[0] - p[0])) / area2,
                ];
                let cell = j * nu + i;
                if w.iter().all(|&x| x >= -1e-12) && !std::mem::replace(&mut taken[cell], true) {
                    cells.push((cell, *t, w));
                }
            }
        }
    }
    let vertices = unique.len();
    Ok((
        field,
        Layout::Scattered {
            vertex,
            vertices,
            cells,
        },
    ))
}

/// What a grid picture shows.
#[derive(Clone)]
struct Picture<'a> {
    title: String,
    caption: String,
    axes: [String; 2],
    field: &'a Field,
    bands: &'a Bands,
    points: &'a [[f64; 2]],
    /// Per crossed level (an index into the bands' levels), its isolines.
    isolines: Vec<(usize, Vec<Polyline>)>,
    frame: MapFrame,
    /// Drawn into a bitmap (else SVG).
    bitmap: bool,
    /// The values' unit, on top of the legend.
    unit: &'static str,
}

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;
type ChartAndLegend<'a, DB> = (Chart<'a, DB>, DrawingArea<DB, Shift>);

/// The header, and the chart over the frame's ranges with its axes (no grid lines); returns
/// the chart and the legend's column.
fn frame_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    pic: &Picture<'_>,
) -> std::result::Result<ChartAndLegend<'a, DB>, Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (header, body) = root.split_vertically(HEADER);
    draw_header(&header, &pic.title, &pic.caption)?;
    let (left, legend) = body.split_horizontally(pic.frame.size.0 - LEGEND_WIDTH);
    let mut chart = ChartBuilder::on(&left)
        .margin(MARGIN)
        .x_label_area_size(X_LABELS)
        .y_label_area_size(Y_LABELS)
        .build_cartesian_2d(pic.frame.u.clone(), pic.frame.v.clone())?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(pic.axes[0].as_str())
        .y_desc(pic.axes[1].as_str())
        .label_style(("sans-serif", 14))
        .draw()?;
    Ok((chart, legend))
}

/// The field's cells as rectangles, runs of one colour along a row merged; `colour` gives a
/// value's colour, `None` to leave it out.
fn draw_cells<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    field: &Field,
    colour: impl Fn(f64) -> Option<[u8; 3]>,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let [hu, hv] = [0.5 * field.step[0], 0.5 * field.step[1]];
    let mut rects = Vec::new();
    for j in 0..field.nv {
        let mut i = 0;
        while i < field.nu {
            let Some(c) = Some(field.value(i, j))
                .filter(|v| v.is_finite())
                .and_then(&colour)
            else {
                i += 1;
                continue;
            };
            let start = i;
            while i + 1 < field.nu
                && Some(field.value(i + 1, j))
                    .filter(|v| v.is_finite())
                    .and_then(&colour)
                    == Some(c)
            {
                i += 1;
            }
            let (a, b) = (field.node(start, j), field.node(i, j));
            rects.push(Rectangle::new(
                [(a[0] - hu, a[1] - hv), (b[0] + hu, b[1] + hv)],
                rgb(c).filled(),
            ));
            i += 1;
        }
    }
    chart.draw_series(rects)?;
    Ok(())
}

/// The false-colour map: each cell its band's colour, the band legend.
fn draw_map<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, pic: &Picture<'_>) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (mut chart, legend) = frame_chart(root, pic)?;
    draw_cells(&mut chart, pic.field, |v| {
        Some(pic.bands.colour(pic.bands.band(v)))
    })?;
    draw_band_legend(&legend, pic.bands, pic.unit)?;
    root.present()?;
    Ok(())
}

/// The point at fraction `f` of a pixel polyline's length.
fn along(px: &[(f64, f64)], f: f64) -> (f64, f64) {
    let total: f64 = px
        .windows(2)
        .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
        .sum();
    let mut left = f * total;
    for w in px.windows(2) {
        let d = (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1);
        if d >= left && d > 0.0 {
            let t = left / d;
            return (
                w[0].0 + t * (w[1].0 - w[0].0),
                w[0].1 + t * (w[1].1 - w[0].1),
            );
        }
        left -= d;
    }
    px[px.len() - 1]
}

/// The isolux plot: the grid's area in light grey, the isolines in their levels' colours,
/// labelled, the points as dots, the levels' legend.
fn draw_isolux<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, pic: &Picture<'_>) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (mut chart, legend) = frame_chart(root, pic)?;
    draw_cells(&mut chart, pic.field, |_| Some([238, 238, 238]))?;
    for (k, lines) in &pic.isolines {
        let colour = rgb(pic.bands.line_colour(*k));
        if pic.bitmap {
            // Plotters' bitmap backend polygonises wide lines with truncated corners, thinning
            // steep stretches: four one-pixel lines a pixel apart make an even 2-pixel line.
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                for l in lines {
                    let px: Vec<(i32, i32)> = l
                        .points
                        .iter()
                        .map(|&p| {
                            let (x, y) = pic.frame.pixel(p);
                            (x + dx, y + dy)
                        })
                        .collect();
                    root.draw(&PathElement::new(px, colour.stroke_width(1)))?;
                }
            }
        } else {
            chart.draw_series(lines.iter().map(|l| {
                PathElement::new(
                    l.points.iter().map(|p| (p[0], p[1])).collect::<Vec<_>>(),
                    colour.stroke_width(2),
                )
            }))?;
        }
    }
    // The points: smaller dots where there are many, none past 20,000 (a blur, and a large
    // SVG).
    let dot = if pic.points.len() > 400 { 1 } else { 2 };
    let shown = if pic.points.len() <= 20_000 {
        pic.points
    } else {
        &[]
    };
    chart.draw_series(
        shown
            .iter()
            .map(|p| Circle::new((p[0], p[1]), dot, RGBColor(60, 60, 60).filled())),
    )?;
    // Labels: one a line long enough to carry it (the longest of each level always), at
    // the first of a few places along it where it overlaps no other label.
    let font: TextStyle = ("sans-serif", 13).into();
    let f = &pic.frame;
    let mut placed: Vec<(f64, f64, f64, f64)> = Vec::new();
    for (k, lines) in &pic.isolines {
        let text = pic.bands.label(*k);
        let (tw, th) = root.estimate_text_size(&text, &font)?;
        let (bw, bh) = (tw as f64 / 2.0 + 3.0, th as f64 / 2.0 + 2.0);
        let mut order: Vec<&Polyline> = lines.iter().collect();
        order.sort_by(|a, b| b.length().total_cmp(&a.length()));
        for (n, line) in order.iter().enumerate() {
            let px: Vec<(f64, f64)> = line
                .points
                .iter()
                .map(|&p| {
                    let (x, y) = f.pixel(p);
                    (x as f64, y as f64)
                })
                .collect();
            let length: f64 = px
                .windows(2)
                .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
                .sum();
            if n > 0 && length < 6.0 * bw {
                continue;
            }
            let fits = |(x, y): (f64, f64)| {
                x - bw >= f.columns.0 as f64
                    && x + bw <= f.columns.1 as f64
                    && y - bh >= f.rows.0 as f64
                    && y + bh <= f.rows.1 as f64
                    && placed.iter().all(|&(x0, y0, x1, y1)| {
                        x + bw < x0 || x - bw > x1 || y + bh < y0 || y - bh > y1
                    })
            };
            let spot = [0.5, 0.3, 0.7, 0.15, 0.85]
                .into_iter()
                .map(|t| along(&px, t))
                .find(|&p| fits(p))
                .or_else(|| (n == 0).then(|| along(&px, 0.5)));
            let Some((x, y)) = spot else {
                continue;
            };
            placed.push((x - bw, y - bh, x + bw, y + bh));
            let (xi, yi) = (x.round() as i32, y.round() as i32);
            let (bwi, bhi) = (bw.round() as i32, bh.round() as i32);
            root.draw(&Rectangle::new(
                [(xi - bwi, yi - bhi), (xi + bwi, yi + bhi)],
                WHITE.filled(),
            ))?;
            root.draw(&Text::new(
                text.clone(),
                (xi, yi),
                font.color(&rgb(pic.bands.line_colour(*k)))
                    .pos(text_anchor::Pos::new(
                        text_anchor::HPos::Center,
                        text_anchor::VPos::Center,
                    )),
            ))?;
        }
    }
    // The legend: the unit, then each level's line and value, highest on top.
    legend.draw(&Text::new(
        pic.unit.to_string(),
        (12, 16),
        ("sans-serif", 16).into_font().color(&BLACK),
    ))?;
    for (row, (k, _)) in pic.isolines.iter().rev().enumerate() {
        let y = 56 + 24 * row as i32;
        legend.draw(&PathElement::new(
            vec![(12, y), (44, y)],
            rgb(pic.bands.line_colour(*k)).stroke_width(3),
        ))?;
        legend.draw(&Text::new(
            format!("{} lx", pic.bands.label(*k)),
            (53, y),
            ("sans-serif", 14)
                .into_font()
                .color(&BLACK)
                .pos(text_anchor::Pos::new(
                    text_anchor::HPos::Left,
                    text_anchor::VPos::Center,
                )),
        ))?;
    }
    if pic.isolines.is_empty() {
        legend.draw(&Text::new(
            "uniform: no".to_string(),
            (12, 56),
            ("sans-serif", 14).into_font().color(&BLACK),
        ))?;
        legend.draw(&Text::new(
            "level crossed".to_string(),
            (12, 74),
            ("sans-serif", 14).into_font().color(&BLACK),
        ))?;
    }
    root.present()?;
    Ok(())
}

/// Which picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// The false-colour illuminance map.
    Map,
    /// The isolux plot.
    Isolux,
}

fn draw<DB: DrawingBackend>(
    kind: Kind,
    root: &DrawingArea<DB, Shift>,
    pic: &Picture<'_>,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    match kind {
        Kind::Map => draw_map(root, pic),
        Kind::Isolux => draw_isolux(root, pic),
    }
}

/// Draw `pic` as `<stem>.png` and `<stem>.svg`, each written atomically.
fn write_both(stem: &Path, pic: &Picture<'_>, kind: Kind) -> Result<[PathBuf; 2]> {
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    let size = pic.frame.size;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        draw(kind, &root, pic).map_err(|e| anyhow::anyhow!("{}: drawing: {e}", svg.display()))?;
    }
    write_atomic::<OutputError>(&svg, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    let mut buf = vec![255u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        let pic = Picture {
            bitmap: true,
            ..pic.clone()
        };
        draw(kind, &root, &pic).map_err(|e| anyhow::anyhow!("{}: drawing: {e}", png.display()))?;
    }
    write_png(&png, size, buf)?;
    Ok([png, svg])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `MapFrame::pixel` is plotters' own mapping of the chart it builds, and keeps one
    /// scale both ways.
    #[test]
    fn the_frame_is_the_charts() {
        register_font();
        for (lo, hi) in [
            ([0.5, 0.5], [5.5, 3.5]),
            ([-3.0, 10.0], [-1.0, 40.0]),
            ([0.0, 0.0], [30.0, 15.0]),
            ([0.0, 0.0], [7.0, 11.0]),
        ] {
            let frame = MapFrame::of(lo, hi);
            let mut buf = vec![0u8; frame.size.0 as usize * frame.size.1 as usize * 3];
            let root = BitMapBackend::with_buffer(&mut buf, frame.size).into_drawing_area();
            let bands = Bands::new(0.0, 1.0, Scale::Linear);
            let field = Field::empty(lo, [1.0, 1.0], 1, 1);
            let pic = Picture {
                title: String::new(),
                caption: String::new(),
                axes: ["x".into(), "y".into()],
                field: &field,
                bands: &bands,
                points: &[],
                isolines: Vec::new(),
                frame: frame.clone(),
                bitmap: true,
                unit: "lx",
            };
            let (chart, _) = frame_chart(&root, &pic).unwrap();
            for t in [0.0, 0.13, 0.5, 0.77, 1.0] {
                let p = [lo[0] + t * (hi[0] - lo[0]), hi[1] - t * (hi[1] - lo[1])];
                assert_eq!(chart.backend_coord(&(p[0], p[1])), frame.pixel(p), "{p:?}");
            }
            let su = (frame.columns.1 - frame.columns.0) as f64 / (frame.u.end - frame.u.start);
            let sv = (frame.rows.1 - frame.rows.0) as f64 / (frame.v.end - frame.v.start);
            assert!((su - sv).abs() < 0.005 * su, "{su} {sv}");
        }
    }

    /// Scattered points of a linear field E = 3 + 2u − v: the raster's values are the field
    /// at its cells (linear interpolation is exact), and every drawn cell lies in the hull.
    #[test]
    fn scattered_points_are_interpolated_in_their_hull() {
        let mut s = 12345u64;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        // A disc of radius 2 about (1, 1): its hull is inside the disc.
        let mut uv: Vec<[f64; 2]> = (0..300)
            .map(|_| {
                let (r, a) = (2.0 * next().sqrt(), std::f64::consts::TAU * next());
                [1.0 + r * a.cos(), 1.0 + r * a.sin()]
            })
            .collect();
        uv.push(uv[5]); // a coincident pair: one vertex, values averaged
        let e = |p: [f64; 2]| 3.0 + 2.0 * p[0] - p[1];
        let (field, layout) = scattered(&uv).unwrap();
        let g = Prepared {
            name: "disc".into(),
            stem: "disc".into(),
            range: 0..uv.len(),
            plane: GridPlane::fit(
                &uv.iter().map(|p| [p[0], p[1], 0.0]).collect::<Vec<_>>(),
                &vec![[0.0, 0.0, 1.0]; uv.len()],
                Up::Z,
            )
            .unwrap(),
            uv: uv.clone(),
            field,
            layout,
        };
        let values: Vec<f64> = uv.iter().map(|&p| e(p)).collect();
        let f = g.field_of(&values);
        let mut drawn = 0;
        for j in 0..f.nv {
            for i in 0..f.nu {
                let v = f.value(i, j);
                if v.is_nan() {
                    continue;
                }
                drawn += 1;
                let p = f.node(i, j);
                assert!((v - e(p)).abs() < 1e-9, "{p:?}: {v} vs {}", e(p));
                assert!((p[0] - 1.0).hypot(p[1] - 1.0) <= 2.0, "{p:?} outside");
            }
        }
        // The hull of 300 points fills most of the disc: most of its area is drawn.
        let cell = f.step[0] * f.step[1];
        assert!(
            drawn as f64 * cell > 0.85 * std::f64::consts::PI * 4.0,
            "{drawn} cells"
        );
    }
}

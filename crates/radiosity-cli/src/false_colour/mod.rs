//! False-colour pictures: a value per cell drawn in banded colours with a legend in its unit,
//! and the lighting grids' illuminance maps and isolux plots (`radiosity lighting --pictures`).
//!
//! The colour map is viridis (van der Walt & Smith, matplotlib 2015): perceptually uniform,
//! ordered dark blue → green → yellow, legible to colour-blind readers and in grey. It is
//! sampled here at its ten published anchors (matplotlib's `viridis(linspace(0, 1, 10))`) and
//! interpolated linearly in sRGB. Values are drawn in **bands** between nice round levels
//! ([`Bands`]: 1, 2, 2.5 or 5 × 10ᵏ apart, or 1–2–5 per decade on a logarithmic scale), each
//! band one flat colour (its middle's), as lighting false-colour maps are: a reader matches a
//! cell to a legend row, and the band edges are the isolux levels.
//!
//! [`write_raster_png`] draws any raster (width × height values, a unit) with its legend; the
//! lighting grids' pictures are [`grid`]'s. Pictures are drawn with plotters, text in DejaVu
//! Sans embedded in the binary (as `radiosity_experiments::plot` does), and written atomically.

pub mod contour;
pub mod delaunay;
pub mod grid;
pub mod lattice;
pub mod plane;

use anyhow::{bail, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor;
use radiosity::io::{write_atomic, OutputError};
use std::path::Path;
use std::sync::Once;

/// viridis at t = 0, 1/9, …, 1 (matplotlib; sRGB).
const VIRIDIS: [[u8; 3]; 10] = [
    [68, 1, 84],
    [72, 40, 120],
    [62, 73, 137],
    [49, 104, 142],
    [38, 130, 142],
    [31, 158, 137],
    [53, 183, 121],
    [110, 206, 88],
    [181, 222, 43],
    [253, 231, 37],
];

/// The viridis colour of `t` ∈ [0, 1] (clamped; NaN reads as 0), linear between the anchors.
pub fn viridis(t: f64) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let k = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - k as f64;
    let (a, b) = (VIRIDIS[k], VIRIDIS[k + 1]);
    std::array::from_fn(|i| (a[i] as f64 + f * (b[i] as f64 - a[i] as f64)).round() as u8)
}

/// How values are spaced between the legend's levels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// Levels equally spaced by a nice step (illuminance on a work plane).
    Linear,
    /// Levels 1, 2, 5 × 10ᵏ (or one a decade over a wide range), bands equally wide in log
    /// (luminance over a view, which spans decades). Values ≤ 0 fall in the lowest band.
    Log,
}

/// The legend: levels `levels[0] < levels[1] < …`, band `k` covering `[levels[k],
/// levels[k + 1])`, each band one colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Bands {
    /// The band edges, ascending; at least two.
    pub levels: Vec<f64>,
    /// How they are spaced.
    pub scale: Scale,
}

/// The nice step for a span cut into about `parts`: 1, 2, 2.5 or 5 × 10ᵏ.
fn nice_step(span: f64, parts: f64) -> f64 {
    let raw = span / parts;
    let mag = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .into_iter()
        .map(|m| m * mag)
        .find(|&s| s >= raw * (1.0 - 1e-12))
        .unwrap_or(10.0 * mag)
}

impl Bands {
    /// Bands covering `[lo, hi]`: 5 to 11 linear bands (a tenth of the span rounded up to a
    /// nice step), or 1–2–5 levels per decade on a log scale (one a decade past six decades);
    /// a single value gets bands around it. Non-finite bounds, or both zero, read as `[0, 1]`.
    pub fn new(lo: f64, hi: f64, scale: Scale) -> Bands {
        // Nothing to show (no range, or all zero: a dark grid): the unit range.
        let (mut lo, mut hi) =
            if lo.is_finite() && hi.is_finite() && lo <= hi && (lo != 0.0 || hi != 0.0) {
                (lo, hi)
            } else {
                (0.0, 1.0)
            };
        match scale {
            Scale::Linear => {
                if hi - lo <= 1e-9 * hi.abs().max(lo.abs()) {
                    let pad = (0.05 * hi.abs().max(lo.abs())).max(1e-9);
                    lo -= pad;
                    hi += pad;
                }
                let step = nice_step(hi - lo, 10.0);
                let first = (lo / step + 1e-9).floor() as i64;
                let last = ((hi / step - 1e-9).ceil() as i64).max(first + 1);
                Bands {
                    levels: (first..=last).map(|k| k as f64 * step).collect(),
                    scale,
                }
            }
            Scale::Log => {
                let tiny = 1e-9 * hi.abs().max(1e-300);
                lo = lo.max(tiny);
                hi = hi.max(lo * 10.0);
                let (d0, d1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
                let mantissas: &[f64] = if d1 - d0 > 6 {
                    &[1.0]
                } else {
                    &[1.0, 2.0, 5.0]
                };
                let mut levels = Vec::new();
                for d in d0..=d1 {
                    for &m in mantissas {
                        let l = m * 10f64.powi(d);
                        // Keep the last level ≤ lo and the first ≥ hi, nothing beyond.
                        levels.push(l);
                    }
                }
                let start = levels
                    .iter()
                    .rposition(|&l| l <= lo * (1.0 + 1e-9))
                    .unwrap_or(0);
                let end = levels
                    .iter()
                    .position(|&l| l >= hi * (1.0 - 1e-9))
                    .unwrap_or(levels.len() - 1)
                    .max(start + 1);
                Bands {
                    levels: levels[start..=end].to_vec(),
                    scale,
                }
            }
        }
    }

    /// Bands covering the finite values of `values` (the positive ones on a log scale).
    pub fn of_values(values: &[f64], scale: Scale) -> Bands {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &v in values {
            if v.is_finite() && (scale == Scale::Linear || v > 0.0) {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        if lo > hi {
            return Bands::new(0.0, 1.0, scale);
        }
        Bands::new(lo, hi, scale)
    }

    /// How many bands.
    pub fn count(&self) -> usize {
        self.levels.len() - 1
    }

    /// The band holding `v` (values below the first level in the first band, above the last
    /// in the last).
    pub fn band(&self, v: f64) -> usize {
        let above = self.levels.partition_point(|&l| l <= v);
        above.saturating_sub(1).min(self.count() - 1)
    }

    /// The colour of band `k`: viridis at the band's middle.
    pub fn colour(&self, k: usize) -> [u8; 3] {
        viridis((k as f64 + 0.5) / self.count() as f64)
    }

    /// The colour of the level `levels[k]` (an isolux line's): viridis at the band edge,
    /// darkened a fifth so that the light end stays legible on white.
    pub fn line_colour(&self, k: usize) -> [u8; 3] {
        viridis(k as f64 / self.count() as f64).map(|c| (c as f64 * 0.8).round() as u8)
    }

    /// The text of level `k`: as many decimals as the step needs, none for whole numbers.
    pub fn label(&self, k: usize) -> String {
        let l = self.levels[k];
        let step = match self.scale {
            Scale::Linear => self.levels[1] - self.levels[0],
            Scale::Log => l,
        };
        let mut decimals = 0;
        while decimals < 9 {
            let scaled = step * 10f64.powi(decimals);
            if (scaled - scaled.round()).abs() < 1e-6 * scaled.max(1.0) {
                break;
            }
            decimals += 1;
        }
        let text = format!("{l:.*}", decimals as usize);
        if text.starts_with('-') && text.trim_start_matches(['-', '0', '.']).is_empty() {
            text[1..].to_string()
        } else {
            text
        }
    }

    /// The band edges strictly between `lo` and `hi`, as indices into `levels`: the isolux
    /// levels a field spanning `[lo, hi]` crosses.
    pub fn crossed(&self, lo: f64, hi: f64) -> Vec<usize> {
        (0..self.levels.len())
            .filter(|&k| self.levels[k] > lo && self.levels[k] < hi)
            .collect()
    }
}

/// Register DejaVu Sans (embedded) as the `sans-serif` family for the bitmap backend.
pub(crate) fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are a well-formed TrueType font shipped by the crate; a failure would
        // only leave text out of the PNGs, which the tests would catch.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

/// An `[r, g, b]` as a plotters colour.
pub(crate) fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

pub(crate) type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

/// Width of the legend column, pixels.
pub const LEGEND_WIDTH: u32 = 150;
/// Height of the title and caption band at the top, pixels.
pub const HEADER: u32 = 64;

/// The title (22 px) and the caption line (16 px) in the header band.
pub(crate) fn draw_header<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    caption: &str,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.draw(&Text::new(
        title.to_string(),
        (16, 10),
        ("sans-serif", 22).into_font().color(&BLACK),
    ))?;
    root.draw(&Text::new(
        caption.to_string(),
        (16, 40),
        ("sans-serif", 16).into_font().color(&RGBColor(40, 40, 40)),
    ))?;
    Ok(())
}

/// The colour legend in `area` (the right-hand column): the unit on top, the bands stacked
/// upwards from the lowest, each level written at its edge.
pub(crate) fn draw_band_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    bands: &Bands,
    unit: &str,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (_, h) = area.dim_in_pixel();
    let n = bands.count() as i32;
    let top = 44;
    let swatch = ((h as i32 - top - 30) / n.max(1)).clamp(6, 36);
    let font = ("sans-serif", 14).into_font().color(&BLACK);
    area.draw(&Text::new(
        unit.to_string(),
        (12, 16),
        ("sans-serif", 16).into_font().color(&BLACK),
    ))?;
    for k in 0..n {
        let y1 = top + (n - k) * swatch;
        area.draw(&Rectangle::new(
            [(12, y1 - swatch), (44, y1)],
            rgb(bands.colour(k as usize)).filled(),
        ))?;
    }
    area.draw(&Rectangle::new(
        [(12, top), (44, top + n * swatch)],
        RGBColor(90, 90, 90).stroke_width(1),
    ))?;
    for k in 0..=n {
        let y = top + (n - k) * swatch;
        area.draw(&PathElement::new(
            vec![(44, y), (49, y)],
            BLACK.stroke_width(1),
        ))?;
        area.draw(&Text::new(
            bands.label(k as usize),
            (53, y),
            font.pos(text_anchor::Pos::new(
                text_anchor::HPos::Left,
                text_anchor::VPos::Center,
            )),
        ))?;
    }
    Ok(())
}

/// A raster to draw in false colour: `width × height` values row by row from the top row
/// (an image's order), NaN where there is nothing (drawn white).
#[derive(Clone, Copy, Debug)]
pub struct Raster<'a> {
    /// Values a row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// `width × height` values, row-major from the top.
    pub values: &'a [f64],
    /// The values' unit, written over the legend (e.g. "cd/m²").
    pub unit: &'a str,
    /// The title line.
    pub title: &'a str,
    /// The caption line under the title (may be empty).
    pub caption: &'a str,
    /// Linear or logarithmic bands.
    pub scale: Scale,
}

/// Where [`write_raster_png`] puts a raster: its top-left pixel, the pixels a value is wide
/// and tall, and the picture's size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterFrame {
    /// The picture's width and height, pixels.
    pub size: (u32, u32),
    /// The raster's top-left corner in the picture, pixels.
    pub origin: (u32, u32),
    /// Pixels per raster value (the same both ways; may be below or above 1).
    pub scale: f64,
    /// The drawn raster's width and height, pixels.
    pub drawn: (u32, u32),
}

/// Largest drawn raster, pixels.
const RASTER_MAX: (f64, f64) = (860.0, 700.0);

impl RasterFrame {
    /// The frame of a `width × height` raster: scaled (by nearest value) to fit 860 × 700
    /// pixels, below the header, left of the legend (the picture at least 700 pixels wide).
    pub fn of(width: usize, height: usize) -> RasterFrame {
        let scale = (RASTER_MAX.0 / width.max(1) as f64).min(RASTER_MAX.1 / height.max(1) as f64);
        let drawn = (
            ((width as f64 * scale).round() as u32).max(1),
            ((height as f64 * scale).round() as u32).max(1),
        );
        // At least 700 pixels wide: room for the caption.
        let size = (
            (16 + drawn.0 + 16 + LEGEND_WIDTH).max(700),
            HEADER + drawn.1 + 16,
        );
        RasterFrame {
            size,
            origin: (16, HEADER),
            scale,
            drawn,
        }
    }

    /// The raster value (column, row) shown at picture pixel `(x, y)`, if any.
    pub fn value_at(&self, x: u32, y: u32, width: usize, height: usize) -> Option<(usize, usize)> {
        if x < self.origin.0 || y < self.origin.1 {
            return None;
        }
        let (dx, dy) = (x - self.origin.0, y - self.origin.1);
        if dx >= self.drawn.0 || dy >= self.drawn.1 {
            return None;
        }
        let c = (((dx as f64 + 0.5) / self.scale) as usize).min(width - 1);
        let r = (((dy as f64 + 0.5) / self.scale) as usize).min(height - 1);
        Some((c, r))
    }
}

/// Draw `raster` in false colour with its legend into the PNG `path` (written atomically):
/// the title and caption on top, the raster scaled to fit 860 × 700 pixels (each picture pixel
/// the nearest value's band colour; NaN white), the legend of the returned [`Bands`] in
/// `raster.unit` on the right ([`RasterFrame::of`] says where each value lands).
pub fn write_raster_png(path: &Path, raster: &Raster<'_>) -> Result<Bands> {
    let (w, h) = (raster.width, raster.height);
    if w == 0 || h == 0 || w.checked_mul(h) != Some(raster.values.len()) {
        bail!(
            "{}: a raster of {w} × {h} values needs {} values, got {}",
            path.display(),
            w.saturating_mul(h),
            raster.values.len()
        );
    }
    register_font();
    let bands = Bands::of_values(raster.values, raster.scale);
    let frame = RasterFrame::of(w, h);
    let (pw, ph) = frame.size;
    let mut rgb_buf = vec![255u8; pw as usize * ph as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb_buf, frame.size).into_drawing_area();
        let draw = || -> DrawResult {
            root.fill(&WHITE)?;
            let (header, body) = root.split_vertically(HEADER);
            draw_header(&header, raster.title, raster.caption)?;
            let (_, legend) = body.split_horizontally(pw - LEGEND_WIDTH);
            draw_band_legend(&legend, &bands, raster.unit)?;
            root.present()?;
            Ok(())
        };
        draw().map_err(|e| anyhow::anyhow!("{}: drawing the picture: {e}", path.display()))?;
    }
    // The raster itself, pixel by pixel: each picture pixel shows the nearest value.
    let colours: Vec<[u8; 3]> = (0..bands.count()).map(|k| bands.colour(k)).collect();
    for y in frame.origin.1..frame.origin.1 + frame.drawn.1 {
        for x in frame.origin.0..frame.origin.0 + frame.drawn.0 {
            let Some((c, r)) = frame.value_at(x, y, w, h) else {
                continue;
            };
            let v = raster.values[r * w + c];
            let colour = if v.is_nan() {
                [255; 3]
            } else {
                colours[bands.band(v)]
            };
            let at = (y as usize * pw as usize + x as usize) * 3;
            rgb_buf[at..at + 3].copy_from_slice(&colour);
        }
    }
    write_png(path, frame.size, rgb_buf)?;
    Ok(bands)
}

/// Write an RGB buffer as a PNG, atomically.
pub(crate) fn write_png(path: &Path, size: (u32, u32), rgb_buf: Vec<u8>) -> Result<()> {
    let img = image::RgbImage::from_raw(size.0, size.1, rgb_buf)
        .ok_or_else(|| anyhow::anyhow!("{}: picture buffer of the wrong size", path.display()))?;
    write_atomic::<OutputError>(path, |out| {
        img.write_to(out, image::ImageFormat::Png)
            .map_err(std::io::Error::other)
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The anchors are matplotlib's; lightness rises monotonically along the map (the
    /// perceptual order a reader relies on), measured as BT.709 luma.
    #[test]
    fn viridis_is_ordered_dark_to_light() {
        assert_eq!(viridis(0.0), [68, 1, 84]);
        assert_eq!(viridis(1.0), [253, 231, 37]);
        assert_eq!(viridis(f64::NAN), viridis(0.0));
        let luma = |c: [u8; 3]| 0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64;
        let mut last = -1.0;
        for k in 0..=100 {
            let l = luma(viridis(k as f64 / 100.0));
            assert!(l > last, "luma falls at t = {}", k as f64 / 100.0);
            last = l;
        }
    }

    /// Nice levels: 0–410 lx in 50 lx steps, 87–410 lx from 50 to 450, a constant field gets
    /// a band around it, and labels have the decimals their step needs.
    #[test]
    fn levels_are_round() {
        let b = Bands::new(0.0, 410.0, Scale::Linear);
        assert_eq!(
            b.levels,
            (0..=9).map(|k| 50.0 * k as f64).collect::<Vec<_>>()
        );
        let b = Bands::new(87.0, 410.0, Scale::Linear);
        assert_eq!(b.levels.first(), Some(&50.0));
        assert_eq!(b.levels.last(), Some(&450.0));
        assert_eq!(b.band(87.0), 0);
        assert_eq!(b.band(100.0), 1);
        assert_eq!(b.band(410.0), b.count() - 1);
        assert_eq!(b.band(1e9), b.count() - 1);
        assert_eq!(b.band(-1.0), 0);
        assert_eq!(b.crossed(87.0, 410.0).len(), 7);
        let b = Bands::new(300.0, 300.0, Scale::Linear);
        assert!(b.levels[0] <= 300.0 && *b.levels.last().unwrap() >= 300.0);
        assert_eq!(
            Bands::new(0.0, 0.0, Scale::Linear),
            Bands::new(0.0, 1.0, Scale::Linear)
        );
        let b = Bands::new(0.0, 1.1, Scale::Linear);
        assert_eq!(b.label(1), "0.2");
        let b = Bands::new(0.0, 2.1, Scale::Linear);
        assert_eq!(b.label(1), "0.25");
        let b = Bands::new(0.5, 3.0e4, Scale::Log);
        assert_eq!(b.levels.first(), Some(&0.5));
        assert_eq!(b.levels.last(), Some(&5.0e4));
        assert_eq!(b.label(0), "0.5");
        assert_eq!(b.band(0.0), 0);
    }

    /// A raster ramp drawn by `write_raster_png`: decoded, every pixel of the raster has the
    /// legend colour of the value shown there (one band exactly: the colour is the band's),
    /// the NaN column is white, and a size mismatch is refused.
    #[test]
    fn a_raster_is_drawn_in_its_bands() {
        let dir = std::env::temp_dir().join(format!("radiosity-fc-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (w, h) = (40, 30);
        let values: Vec<f64> = (0..w * h)
            .map(|i| {
                if i % w == 0 {
                    f64::NAN
                } else {
                    10.0 * (i % w) as f64 + 0.1 * (i / w) as f64
                }
            })
            .collect();
        let raster = Raster {
            width: w,
            height: h,
            values: &values,
            unit: "cd/m²",
            title: "ramp",
            caption: "luminance",
            scale: Scale::Linear,
        };
        let path = dir.join("ramp.png");
        let bands = write_raster_png(&path, &raster).unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        let frame = RasterFrame::of(w, h);
        assert_eq!(img.dimensions(), frame.size);
        for y in (frame.origin.1..frame.origin.1 + frame.drawn.1).step_by(7) {
            for x in (frame.origin.0..frame.origin.0 + frame.drawn.0).step_by(5) {
                let (c, r) = frame.value_at(x, y, w, h).unwrap();
                let v = values[r * w + c];
                let want = if v.is_nan() {
                    [255; 3]
                } else {
                    bands.colour(bands.band(v))
                };
                assert_eq!(img.get_pixel(x, y).0, want, "({x}, {y}) shows {v}");
            }
        }
        assert!(write_raster_png(
            &path,
            &Raster {
                width: 41,
                ..raster
            }
        )
        .is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

//! Line plots of experiment results, written as SVG and PNG.
//!
//! One code path for linear and logarithmic axes: a logarithmic axis plots log10 of the data and
//! labels its ticks as powers of ten. Text in the PNG is drawn with DejaVu Sans, embedded in the
//! binary (crate `dejavu`), so no system font or fontconfig is needed; the SVG names the
//! `sans-serif` family and leaves the font to the viewer.

use plotters::coord::Shift;
use plotters::prelude::*;
use radiosity::export::{write_atomic, ExportError, OutputError};
use std::path::{Path, PathBuf};
use std::sync::Once;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// A polyline through the points.
    Line,
    /// Markers at the points, joined by a line.
    LinePoints,
    /// A dashed reference line (e.g. a fitted or claimed slope).
    Dashed,
}

/// One named series of (x, y) points.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// The points; those that cannot be shown on a logarithmic axis (≤ 0, not finite) are
    /// skipped.
    pub points: Vec<(f64, f64)>,
    /// How to draw it.
    pub mark: Mark,
}

/// A 2-D line plot.
#[derive(Clone, Debug)]
pub struct Plot {
    /// Title above the plot.
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// The series, drawn in order, each in its own colour.
    pub series: Vec<Series>,
}

/// Width and height of the pictures, pixels.
pub const SIZE: (u32, u32) = (1150, 600);
/// Width of the legend column on the right, pixels.
const LEGEND_WIDTH: u32 = 300;

const COLOURS: [RGBColor; 12] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(0, 0, 0),
    RGBColor(120, 120, 255),
];

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are a well-formed TrueType font shipped by the crate; a failure here would
        // only mean text is missing from PNGs, which the tests would catch.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

fn to_axis(v: f64, log: bool) -> Option<f64> {
    if !v.is_finite() {
        return None;
    }
    if log {
        (v > 0.0).then(|| v.log10())
    } else {
        Some(v)
    }
}

fn tick_label(v: f64, log: bool) -> String {
    if log {
        let r = v.round();
        if (v - r).abs() < 1e-9 {
            format!("1e{}", r as i64)
        } else {
            format!("{:.3}", 10f64.powf(v))
        }
    } else if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        format!("{v:.1e}")
    } else {
        format!("{}", (v * 1e6).round() / 1e6)
    }
}

/// The plotted range of one axis, padded a little; log axes are widened to whole decades.
fn range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if log {
        lo = lo.floor();
        hi = hi.ceil();
        if hi <= lo {
            hi = lo + 1.0;
        }
        (lo, hi)
    } else {
        if hi <= lo {
            hi = lo + 1.0;
        }
        let pad = 0.03 * (hi - lo);
        (if lo >= 0.0 { lo.max(0.0) } else { lo - pad }, hi + pad)
    }
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

fn draw<DB: DrawingBackend>(plot: &Plot, root: &DrawingArea<DB, Shift>) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (root, legend) = root.split_horizontally(SIZE.0 - LEGEND_WIDTH);
    let series: Vec<(&Series, Vec<(f64, f64)>)> = plot
        .series
        .iter()
        .map(|s| {
            let pts = s
                .points
                .iter()
                .filter_map(|&(x, y)| Some((to_axis(x, plot.log_x)?, to_axis(y, plot.log_y)?)))
                .collect();
            (s, pts)
        })
        .collect();
    let all = || series.iter().flat_map(|s| s.1.iter().copied());
    let (x0, x1) = range(all().map(|p| p.0), plot.log_x);
    let (y0, y1) = range(all().map(|p| p.1), plot.log_y);
    let mut chart = ChartBuilder::on(&root)
        .caption(&plot.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    let (lx, ly) = (plot.log_x, plot.log_y);
    let x_fmt = move |v: &f64| tick_label(*v, lx);
    let y_fmt = move |v: &f64| tick_label(*v, ly);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(plot.x_label.as_str())
        .y_desc(plot.y_label.as_str())
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style(("sans-serif", 14))
        .light_line_style(RGBColor(235, 235, 235));
    if plot.log_x {
        mesh.x_labels(((x1 - x0) as usize + 1).max(2));
    }
    if plot.log_y {
        mesh.y_labels(((y1 - y0) as usize + 1).max(2));
    }
    mesh.draw()?;
    for (k, (s, pts)) in series.into_iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let style = ShapeStyle::from(&colour).stroke_width(1);
        match s.mark {
            Mark::Dashed => chart.draw_series(DashedLineSeries::new(pts.clone(), 6, 4, style))?,
            _ => chart.draw_series(LineSeries::new(pts.clone(), style))?,
        };
        if s.mark == Mark::LinePoints {
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, colour.filled())))?;
        }
        // The legend, beside the plot so it hides no curve.
        let y = 50 + 22 * k as i32;
        // Thin lines on the plot: plotters' bitmap backend mis-draws steep lines wider than one
        // pixel. The legend's are horizontal and can be bold.
        legend.draw(&PathElement::new(
            vec![(8, y), (30, y)],
            style.stroke_width(3),
        ))?;
        if s.mark == Mark::LinePoints {
            legend.draw(&Circle::new((19, y), 4, colour.filled()))?;
        }
        legend.draw(&Text::new(
            s.name.clone(),
            (36, y - 8),
            ("sans-serif", 14).into_font().color(&BLACK),
        ))?;
    }
    root.present()?;
    legend.present()?;
    Ok(())
}

fn plot_error(path: &Path, e: impl std::fmt::Display) -> ExportError {
    ExportError::Output(OutputError {
        path: path.to_path_buf(),
        source: std::io::Error::other(format!("drawing the plot: {e}")),
    })
}

/// Write `plot` as `<stem>.svg` and `<stem>.png`; returns the two paths.
pub fn write_plot(stem: &Path, plot: &Plot) -> Result<[PathBuf; 2], ExportError> {
    register_font();
    let svg_path = stem.with_extension("svg");
    let png_path = stem.with_extension("png");
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        draw(plot, &root).map_err(|e| plot_error(&svg_path, e))?;
    }
    write_atomic::<ExportError>(&svg_path, |w| std::io::Write::write_all(w, svg.as_bytes()))?;
    let (w, h) = SIZE;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(plot, &root).map_err(|e| plot_error(&png_path, e))?;
    }
    let img = image::RgbImage::from_raw(w, h, rgb).expect("buffer of the right size");
    write_atomic::<ExportError>(&png_path, |out| {
        img.write_to(out, image::ImageFormat::Png)
            .map_err(std::io::Error::other)
    })?;
    Ok([svg_path, png_path])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plot with log axes is written as an SVG naming its series and ticks, and as a PNG
    /// with non-white pixels in the plot area (lines and text drawn with the embedded font).
    #[test]
    fn writes_svg_and_png() {
        let dir = std::env::temp_dir().join(format!("radiosity-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let plot = Plot {
            title: "error per iteration".into(),
            x_label: "iteration".into(),
            y_label: "error".into(),
            log_x: false,
            log_y: true,
            series: vec![
                Series {
                    name: "halving".into(),
                    points: (0..20).map(|k| (k as f64, 0.5f64.powi(k))).collect(),
                    mark: Mark::Line,
                },
                Series {
                    name: "zero is skipped".into(),
                    points: vec![(0.0, 0.0), (5.0, 0.1), (10.0, 0.01)],
                    mark: Mark::LinePoints,
                },
            ],
        };
        let [svg, png] = write_plot(&dir.join("p"), &plot).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.contains("halving") && text.contains("1e-5"), "{text}");
        let img = image::open(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), SIZE);
        // The title band holds text: dark pixels in the top 30 rows.
        let dark = (0..SIZE.0)
            .flat_map(|x| (0..30).map(move |y| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x, y).0.iter().all(|&c| c < 100))
            .count();
        assert!(dark > 50, "{dark} dark pixels in the title band");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

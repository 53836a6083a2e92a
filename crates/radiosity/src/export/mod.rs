//! Files out: images (PNG, OpenEXR, PFM), the per-patch CSV and baked meshes (glTF, PLY;
//! [`bake`]). Every file is written to a
//! temporary file next to its destination and renamed into place when complete, so a failure
//! never leaves a half-written output.

pub mod bake;
pub mod plot;

use crate::color::Rgb;
use crate::mesh::Mesh;
use crate::render::{to_srgb8, Image};
use crate::scene::Scene;
use crate::solve::{relative_error, SolverState, Status};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Why a file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The operating system refused.
    #[error("{}: {source}", path.display())]
    Io {
        /// The destination.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file name's extension names no supported format.
    #[error("{}: unsupported {what} format (use {supported})", path.display())]
    Format {
        /// The destination.
        path: PathBuf,
        /// What kind of file was asked for.
        what: &'static str,
        /// The extensions that work.
        supported: &'static str,
    },
}

/// Image formats, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit sRGB PNG (exposed and tone-mapped).
    Png,
    /// OpenEXR, linear 32-bit float RGB radiance.
    Exr,
    /// Portable float map, linear 32-bit float RGB radiance.
    Pfm,
}

impl ImageFormat {
    /// The format named by `path`'s extension (`.png`, `.exr`, `.pfm`).
    pub fn from_path(path: &Path) -> Result<Self, ExportError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(Self::Png),
            Some("exr") => Ok(Self::Exr),
            Some("pfm") => Ok(Self::Pfm),
            _ => Err(ExportError::Format {
                path: path.to_path_buf(),
                what: "image",
                supported: ".png, .exr or .pfm",
            }),
        }
    }
}

/// Write through `body` into a temporary file beside `path`, then rename it to `path`.
pub fn write_atomic(
    path: &Path,
    body: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<(), ExportError> {
    let io = |source| ExportError::Io {
        path: path.to_path_buf(),
        source,
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let tmp = path.with_file_name(format!(".{name}.tmp{}", std::process::id()));
    let result = (|| {
        let mut w = BufWriter::new(File::create(&tmp)?);
        body(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

/// Write `image` to `path` in the format its extension names. PNG applies `scale` (the
/// exposure) and the sRGB curve; EXR and PFM keep linear radiance.
pub fn write_image(path: &Path, image: &Image, scale: f32) -> Result<(), ExportError> {
    let format = ImageFormat::from_path(path)?;
    let (w, h) = (image.width, image.height);
    write_atomic(path, |out| match format {
        ImageFormat::Png => {
            let bytes = to_srgb8(image, scale);
            let enc = image::codecs::png::PngEncoder::new(out);
            image::ImageEncoder::write_image(enc, &bytes, w, h, image::ExtendedColorType::Rgb8)
                .map_err(std::io::Error::other)
        }
        ImageFormat::Pfm => {
            write!(out, "PF\n{w} {h}\n-1.0\n")?;
            for y in (0..h).rev() {
                for x in 0..w {
                    for c in image.at(x, y) {
                        out.write_all(&c.to_le_bytes())?;
                    }
                }
            }
            Ok(())
        }
        ImageFormat::Exr => {
            use exr::prelude::*;
            let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
                let p = image.at(pos.x() as u32, pos.y() as u32);
                (p[0], p[1], p[2])
            });
            let layer = Layer::new(
                (w as usize, h as usize),
                LayerAttributes::named("radiance"),
                Encoding::FAST_LOSSLESS,
                channels,
            );
            exr::image::Image::from_layer(layer)
                .write()
                .to_buffered(out)
                .map_err(std::io::Error::other)
        }
    })
}

/// The header of [`write_patches_csv`].
pub const PATCHES_CSV_HEADER: &str = "patch,surface,area,cx,cy,cz,nx,ny,nz,reflectance_r,reflectance_g,reflectance_b,emission_r,emission_g,emission_b,radiosity_r,radiosity_g,radiosity_b";

/// One row per patch: index (0-based), surface (input polygon, 0-based), area, centre, normal,
/// reflectance, emission and radiosity, with [`PATCHES_CSV_HEADER`].
pub fn write_patches_csv(
    path: &Path,
    scene: &Scene,
    mesh: &Mesh,
    radiosity: &[Rgb],
) -> Result<(), ExportError> {
    write_atomic(path, |out| {
        writeln!(out, "{PATCHES_CSV_HEADER}")?;
        for (k, (p, b)) in mesh.patches.iter().zip(radiosity).enumerate() {
            let m = &scene.materials[p.material as usize];
            let (c, n, r, e) = (p.centre, p.normal, m.reflectance, m.emission);
            writeln!(
                out,
                "{k},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                p.surface,
                p.area,
                c.x,
                c.y,
                c.z,
                n.x,
                n.y,
                n.z,
                r.r,
                r.g,
                r.b,
                e.r,
                e.g,
                e.b,
                b.r,
                b.g,
                b.b
            )?;
        }
        Ok(())
    })
}

/// The header of [`write_patch_table`]: [`PATCHES_CSV_HEADER`] without the radiosity columns.
pub const PATCH_TABLE_HEADER: &str = "patch,surface,area,cx,cy,cz,nx,ny,nz,reflectance_r,reflectance_g,reflectance_b,emission_r,emission_g,emission_b";

/// One row of a patch table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchRow {
    /// Surface (input polygon) index.
    pub surface: u32,
    /// Area.
    pub area: f64,
    /// Centroid.
    pub centre: crate::geom::Vec3,
    /// Unit normal.
    pub normal: crate::geom::Vec3,
    /// Reflectance.
    pub reflectance: Rgb,
    /// Emission.
    pub emission: Rgb,
}

/// The rows of a form-factor matrix's patches (or faces), with [`PATCH_TABLE_HEADER`]; the
/// `patch` column is the 0-based row (row k of a Matrix Market file is patch k − 1).
pub fn write_patch_table(path: &Path, rows: &[PatchRow]) -> Result<(), ExportError> {
    write_atomic(path, |out| {
        writeln!(out, "{PATCH_TABLE_HEADER}")?;
        for (k, r) in rows.iter().enumerate() {
            let (c, n, rho, e) = (r.centre, r.normal, r.reflectance, r.emission);
            writeln!(
                out,
                "{k},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                r.surface, r.area, c.x, c.y, c.z, n.x, n.y, n.z, rho.r, rho.g, rho.b, e.r, e.g, e.b
            )?;
        }
        Ok(())
    })
}

/// The header of convergence traces.
pub const TRACE_HEADER: &str = "iteration,seconds,error,unshot";

/// A convergence trace, one row per iteration: iteration, seconds in the solver, the error of
/// eq. 22 of Gortler, Cohen & Slusallek (1993) against an exact solution (empty without one), and the
/// unshot energy as a fraction of the emitted energy.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    text: String,
    exact: Option<Vec<Rgb>>,
    emission: Vec<Rgb>,
    buf: Vec<Rgb>,
}

impl Trace {
    /// A trace measuring the error against `exact` (if given) of a system with `emission`.
    pub fn new(exact: Option<Vec<Rgb>>, emission: &[Rgb]) -> Self {
        Self {
            text: format!("{TRACE_HEADER}\n"),
            exact,
            emission: emission.to_vec(),
            buf: Vec::new(),
        }
    }

    /// Record the solver's state.
    pub fn record(&mut self, status: &Status, solver: &dyn SolverState) {
        use std::fmt::Write as _;
        let error = match &self.exact {
            Some(exact) => {
                solver.radiosity(&mut self.buf);
                relative_error(exact, &self.emission, &self.buf).to_string()
            }
            None => String::new(),
        };
        let _ = writeln!(
            self.text,
            "{},{},{},{}",
            status.iterations, status.seconds, error, status.unshot_fraction
        );
    }

    /// Rows recorded.
    pub fn len(&self) -> usize {
        self.text.lines().count() - 1
    }

    /// True when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Write the trace.
    pub fn write(&self, path: &Path) -> Result<(), ExportError> {
        write_atomic(path, |out| out.write_all(self.text.as_bytes()))
    }
}

/// One radiosity row per patch: header `radiosity` (one channel, the red one) or
/// `radiosity_r,radiosity_g,radiosity_b`.
pub fn write_radiosity_csv(
    path: &Path,
    b: &[Rgb],
    single_channel: bool,
) -> Result<(), ExportError> {
    write_atomic(path, |out| {
        if single_channel {
            writeln!(out, "radiosity")?;
            for v in b {
                writeln!(out, "{}", v.r)?;
            }
        } else {
            writeln!(out, "radiosity_r,radiosity_g,radiosity_b")?;
            for v in b {
                writeln!(out, "{},{},{}", v.r, v.g, v.b)?;
            }
        }
        Ok(())
    })
}

//! Files out: images (PNG, OpenEXR, PFM), the per-patch CSV and baked meshes (glTF, PLY;
//! [`bake`]). Every file is written to a
//! temporary file next to its destination and renamed into place when complete, so a failure
//! never leaves a half-written output.

pub mod bake;

use crate::color::Rgb;
use crate::io::FileFormat;
pub use crate::io::{write_atomic, OutputError};
use crate::mesh::Mesh;
use crate::render::{to_srgb8, Image};
use crate::scene::Scene;
use rayon::prelude::*;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Why a file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The file could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
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
        match FileFormat::from_path(path) {
            Some(FileFormat::Png) => Ok(Self::Png),
            Some(FileFormat::Exr) => Ok(Self::Exr),
            Some(FileFormat::Pfm) => Ok(Self::Pfm),
            _ => Err(ExportError::Format {
                path: path.to_path_buf(),
                what: "image",
                supported: ".png, .exr or .pfm",
            }),
        }
    }
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
    // Rows are formatted in parallel, a block of them into one string each, then written in
    // order: at a million patches the shortest round-trip formatting of 18 numbers a row,
    // done serially, would be a part of a solve that does not scale with threads
    // (docs/notes/library.md). A group of blocks at a time, so that the text held is bounded
    // (two groups, some 20 MB), not the whole file; a group is written while the next is
    // formatted, so that the copy into the file does not wait for the formatting nor the
    // formatting for the copy.
    const BLOCK: usize = 4096;
    const GROUP: usize = 16 * BLOCK;
    let format = |first: usize, patches: &[crate::mesh::Patch], radiosity: &[Rgb]| {
        use std::fmt::Write as _;
        let mut s = String::with_capacity(patches.len() * 160);
        for (j, (p, b)) in patches.iter().zip(radiosity).enumerate() {
            let m = &scene.materials[p.material as usize];
            let (c, n, r, e) = (p.centre, p.normal, m.reflectance, m.emission);
            // Writing into a String cannot fail.
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                first + j,
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
            );
        }
        s
    };
    let rows = mesh.patches.len().min(radiosity.len());
    let group = |start: usize| -> Vec<String> {
        let end = (start + GROUP).min(rows);
        mesh.patches[start..end]
            .par_chunks(BLOCK)
            .zip(radiosity[start..end].par_chunks(BLOCK))
            .enumerate()
            .map(|(i, (patches, radiosity))| format(start + i * BLOCK, patches, radiosity))
            .collect()
    };
    let put = |out: &mut std::io::BufWriter<std::fs::File>, blocks: &[String]| {
        blocks.iter().try_for_each(|b| out.write_all(b.as_bytes()))
    };
    write_atomic(path, |out| {
        writeln!(out, "{PATCHES_CSV_HEADER}")?;
        let mut ready: Option<Vec<String>> = None;
        for start in (0..rows).step_by(GROUP) {
            let next = match ready.take() {
                Some(blocks) => {
                    let (written, next) = rayon::join(|| put(out, &blocks), || group(start));
                    written?;
                    next
                }
                None => group(start),
            };
            ready = Some(next);
        }
        if let Some(blocks) = ready {
            put(out, &blocks)?;
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
    write_atomic(path, |out| patch_table_to(out, rows))
}

/// [`write_patch_table`] into a stream (an [`crate::io::Staged`] output, with others).
pub fn patch_table_to(out: &mut dyn Write, rows: &[PatchRow]) -> std::io::Result<()> {
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
}

/// Write `text` to `path` as it is (a trace's CSV, a Markdown summary).
pub fn write_text(path: &Path, text: &str) -> Result<(), ExportError> {
    write_atomic(path, |out| out.write_all(text.as_bytes()))
}

/// A hierarchical solution's links as CSV, one row each:
/// `receiver,source,source_kind,form_factor,uncertainty,power_r,power_g,power_b` (source kind
/// `element` or `cluster`; power: what the link carries, A_r · k · B_s).
pub fn write_links_csv(path: &Path, h: &crate::hierarchical::Hierarchy) -> Result<(), ExportError> {
    use crate::hierarchical::cluster::CLUSTER;
    write_atomic(path, |out| {
        writeln!(
            out,
            "receiver,source,source_kind,form_factor,uncertainty,power_r,power_g,power_b"
        )?;
        for l in &h.links {
            let (id, kind) = if l.source & CLUSTER != 0 {
                (l.source & !CLUSTER, "cluster")
            } else {
                (l.source, "element")
            };
            let a = h.elements.items[l.receiver as usize].area as f64;
            let p = h.link_radiosity(l) * (a * l.k as f64);
            writeln!(
                out,
                "{},{id},{kind},{},{},{},{},{}",
                l.receiver, l.k, l.uncertainty, p.r, p.g, p.b
            )?;
        }
        Ok(())
    })
}

/// A hierarchical solution's elements as CSV, one row each (roots first):
/// `element,parent,level,surface,leaf,area,cx,cy,cz,radiosity_r,radiosity_g,radiosity_b,exposed`
/// (parent empty for a root; surface: the input polygon; leaf 1 or 0; exposed: the fraction
/// of the element not inside a closed solid, [`crate::hierarchical::kernel::Cover`]).
pub fn write_elements_csv(
    path: &Path,
    h: &crate::hierarchical::Hierarchy,
    roots: &[u32],
) -> Result<(), ExportError> {
    write_atomic(path, |out| {
        writeln!(
            out,
            "element,parent,level,surface,leaf,area,cx,cy,cz,radiosity_r,radiosity_g,radiosity_b,exposed"
        )?;
        for (i, e) in h.elements.items.iter().enumerate() {
            let parent = if e.parent == crate::hierarchical::element::NONE {
                String::new()
            } else {
                e.parent.to_string()
            };
            let b = h.radiosity[i];
            writeln!(
                out,
                "{i},{parent},{},{},{},{},{},{},{},{},{},{},{}",
                e.level,
                roots[e.root as usize],
                e.is_leaf() as u8,
                e.area,
                e.centre.x,
                e.centre.y,
                e.centre.z,
                b.r,
                b.g,
                b.b,
                h.exposure[i]
            )?;
        }
        Ok(())
    })
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::MeshParams;
    use crate::scene::builtin;

    /// A patch table of more than two groups of rows (each written while the next is
    /// formatted) holds every patch once, in order, with its own radiosity; the same on one
    /// thread and on two.
    #[test]
    fn patches_csv_keeps_its_rows_in_order_across_groups() {
        let scene = builtin::cornell();
        let mesh = Mesh::build(&scene, MeshParams::Patches(140_000)).unwrap();
        let n = mesh.patches.len();
        assert!(n > 2 * 16 * 4096, "{n} patches");
        let radiosity: Vec<Rgb> = (0..n)
            .map(|i| Rgb::new(i as f64, 0.5 * i as f64, 1.0 / (1 + i) as f64))
            .collect();
        let dir = std::env::temp_dir().join(format!("radiosity-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut texts = Vec::new();
        for threads in [1, 2] {
            let path = dir.join(format!("p{threads}.csv"));
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| write_patches_csv(&path, &scene, &mesh, &radiosity))
                .unwrap();
            texts.push(std::fs::read_to_string(&path).unwrap());
        }
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(texts[0], texts[1]);
        let mut lines = texts[0].lines();
        assert_eq!(lines.next(), Some(PATCHES_CSV_HEADER));
        let mut count = 0;
        for (k, line) in lines.enumerate() {
            let v: Vec<&str> = line.split(',').collect();
            assert_eq!(v[0].parse::<usize>().unwrap(), k, "{line}");
            let b: Vec<f64> = v[15..18].iter().map(|x| x.parse().unwrap()).collect();
            let want = radiosity[k];
            assert_eq!((b[0], b[1], b[2]), (want.r, want.g, want.b), "{line}");
            count += 1;
        }
        assert_eq!(count, n);
    }
}

//! How far a picture is from a reference: relative RMSE over the pixels that are not the light,
//! the measure of the picture benchmarks and tests.
//!
//! Pixels where the reference is brighter than 5 × its median luminance (the emitters seen
//! directly), and those within two pixels of them (partly covered by an emitter, where a few
//! samples more or less of the light swamp every other error), are left out. Over the rest,
//! `RMSE = sqrt(mean over pixels and channels of (a − r)²) / mean(r)` and the bias
//! `mean(a − r) / mean(r)`.

use super::Image;
use crate::io::{at, InputError};
use std::path::Path;

/// Relative error of `image` against `reference`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Difference {
    /// Relative root-mean-square error.
    pub rmse: f64,
    /// Relative mean error (positive: brighter than the reference).
    pub bias: f64,
    /// Pixels compared.
    pub pixels: usize,
}

/// The pixels that are compared: not an emitter, not within two pixels of one.
pub fn mask(reference: &Image) -> Vec<bool> {
    let (w, h) = (reference.width as usize, reference.height as usize);
    let lum: Vec<f32> = reference
        .pixels
        .iter()
        .map(|p| p[0] + p[1] + p[2])
        .collect();
    let mut sorted = lum.clone();
    sorted.sort_by(f32::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
    let mut keep = vec![true; w * h];
    for y in 0..h {
        for x in 0..w {
            if lum[y * w + x] >= 5.0 * median {
                for yy in y.saturating_sub(2)..(y + 3).min(h) {
                    for xx in x.saturating_sub(2)..(x + 3).min(w) {
                        keep[yy * w + xx] = false;
                    }
                }
            }
        }
    }
    for (k, l) in keep.iter_mut().zip(&lum) {
        if l.is_nan() || *l <= 0.0 {
            *k = false;
        }
    }
    keep
}

/// [`Difference`] of `image` against `reference` (the same size).
pub fn difference(reference: &Image, image: &Image) -> Difference {
    assert_eq!(
        (reference.width, reference.height),
        (image.width, image.height),
        "images of different sizes"
    );
    let keep = mask(reference);
    let (mut se, mut e, mut sum, mut n) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    for ((r, a), k) in reference.pixels.iter().zip(&image.pixels).zip(&keep) {
        if !k {
            continue;
        }
        n += 1;
        for c in 0..3 {
            let d = a[c] as f64 - r[c] as f64;
            se += d * d;
            e += d;
            sum += r[c] as f64;
        }
    }
    let mean = sum / (3 * n.max(1)) as f64;
    Difference {
        rmse: (se / (3 * n.max(1)) as f64).sqrt() / mean,
        bias: e / (3 * n.max(1)) as f64 / mean,
        pixels: n,
    }
}

/// Read a PFM image (colour, `PF`), as `render` writes it: header `PF`, `width height`, a
/// scale whose sign gives the byte order, then rows bottom to top.
pub fn read_pfm(path: &Path) -> Result<Image, InputError> {
    let bytes = crate::io::read_input(path).map_err(|source| InputError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut fields = Vec::new();
    let mut pos = 0;
    // Three whitespace-separated header tokens after "PF", then one whitespace byte.
    while fields.len() < 4 {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() && pos - start < 32 {
            pos += 1;
        }
        if start == pos {
            return Err(at(path, 1, "not a PFM file: the header ends early"));
        }
        fields.push(String::from_utf8_lossy(&bytes[start..pos]).into_owned());
    }
    pos += 1;
    if fields[0] != "PF" {
        return Err(at(
            path,
            1,
            format!(
                "not a colour PFM file (starts with '{}', not 'PF')",
                fields[0]
            ),
        ));
    }
    let dim = |s: &str| -> Result<u32, InputError> {
        match s.parse::<u32>() {
            Ok(v) if (1..=32768).contains(&v) => Ok(v),
            _ => Err(at(path, 2, format!("image size '{s}' is not in 1…32768"))),
        }
    };
    let (w, h) = (dim(&fields[1])?, dim(&fields[2])?);
    let scale: f32 = fields[3]
        .parse()
        .ok()
        .filter(|v: &f32| v.is_finite() && *v != 0.0)
        .ok_or_else(|| {
            at(
                path,
                3,
                format!("scale '{}' is not a non-zero number", fields[3]),
            )
        })?;
    let need = w as usize * h as usize * 12;
    let data = bytes.get(pos..).unwrap_or(&[]);
    if data.len() != need {
        return Err(at(
            path,
            3,
            format!(
                "{} bytes of pixels where a {w}×{h} image has {need}",
                data.len()
            ),
        ));
    }
    let mut pixels = vec![[0.0f32; 3]; (w * h) as usize];
    for (k, chunk) in data.chunks_exact(12).enumerate() {
        let (x, row) = (k % w as usize, k / w as usize);
        let y = h as usize - 1 - row;
        let mut p = [0.0f32; 3];
        for c in 0..3 {
            let b: [u8; 4] = chunk[4 * c..4 * c + 4].try_into().unwrap_or([0; 4]);
            p[c] = if scale < 0.0 {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            };
        }
        pixels[y * w as usize + x] = p;
    }
    Ok(Image {
        width: w,
        height: h,
        pixels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pfm_round_trip_and_difference() {
        let dir = std::env::temp_dir().join(format!("radiosity-pfm-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.pfm");
        let image = Image {
            width: 3,
            height: 2,
            pixels: vec![
                [1.0, 2.0, 3.0],
                [0.5, 0.5, 0.5],
                [1.0, 1.0, 1.0],
                [2.0, 2.0, 2.0],
                [0.25, 0.5, 1.0],
                [1.0, 1.0, 1.0],
            ],
        };
        crate::export::write_image(&p, &image, 1.0).unwrap();
        let back = read_pfm(&p).unwrap();
        assert_eq!(back, image);
        let d = difference(&image, &back);
        assert_eq!((d.rmse, d.bias), (0.0, 0.0));
        std::fs::write(&p, b"PF\n3 2\n-1.0\n\0\0").unwrap();
        assert!(read_pfm(&p)
            .unwrap_err()
            .to_string()
            .contains("bytes of pixels"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

//! NIST View3D's view-factor output file (text form, `out=0`; View3D manual, "View Factor
//! Output File"), and Hottel's total exchange factors that View3D reports with `emit=1`.
//!
//! ```text
//! View3D 3.2 0 encl emit N        header: program, format version, out, encl, emit, N
//! A_1 A_2 … A_N                   areas
//! F_11 F_12 … F_1N                N rows of F_mn (row m, column n), %.6f
//! …
//! ε_1 ε_2 … ε_N                   emissivities, %.3f
//! ```
//!
//! The header is padded to 30 characters as View3D's `SaveVF` writes it, so its own readers
//! (ViewHT's `ReadVF`, which reads the first 35 characters) take the file.

use super::output::{write_atomic, OutputError};
use std::io::Write;
use std::path::Path;

/// A dense square table of factors with the surfaces' areas and emissivities.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewFactorTable {
    /// Areas, in the scene's units squared.
    pub area: Vec<f64>,
    /// Row-major N × N factors: `f[m * n + k]` from surface m to surface k.
    pub f: Vec<f64>,
    /// Emissivities.
    pub emissivity: Vec<f64>,
    /// The enclosure flag written in the header.
    pub enclosure: bool,
    /// True when `f` holds total exchange factors ([`script_f`]).
    pub emit: bool,
}

impl ViewFactorTable {
    /// Number of surfaces.
    pub fn n(&self) -> usize {
        self.area.len()
    }
}

/// Write `t` in View3D's text format (a dense table; [`write_rows`] writes without one).
pub fn write(path: &Path, t: &ViewFactorTable) -> Result<(), OutputError> {
    let n = t.n();
    write_rows(
        path,
        &t.area,
        &t.emissivity,
        t.enclosure,
        t.emit,
        |m: usize, row: &mut [f64]| row.copy_from_slice(&t.f[m * n..(m + 1) * n]),
    )
}

/// Write View3D's text format row by row: `row(m, out)` fills `out` (length N) with the
/// factors from surface m, so no N × N copy is ever held (one row of N values is). `area` and
/// `emissivity` give N. Rows are asked for in order, 0 to N − 1, once each. The file is
/// written whole or not at all ([`write_atomic`]); [`write_rows_to`] writes into a stream
/// (an [`super::Staged`] output, with others).
pub fn write_rows(
    path: &Path,
    area: &[f64],
    emissivity: &[f64],
    enclosure: bool,
    emit: bool,
    row: impl FnMut(usize, &mut [f64]),
) -> Result<(), OutputError> {
    write_atomic(path, |w| {
        write_rows_to(w, area, emissivity, enclosure, emit, row)
    })
}

/// [`write_rows`] into `w`: the header, the areas, the N rows as `row` fills them, the
/// emissivities. Holds one row of N values, never N × N.
pub fn write_rows_to(
    w: &mut dyn Write,
    area: &[f64],
    emissivity: &[f64],
    enclosure: bool,
    emit: bool,
    mut row: impl FnMut(usize, &mut [f64]),
) -> std::io::Result<()> {
    let n = area.len();
    if emissivity.len() != n {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{} areas but {} emissivities", n, emissivity.len()),
        ));
    }
    let header = format!("View3D 3.2 0 {} {} {}", enclosure as u8, emit as u8, n);
    writeln!(w, "{header:<30}")?;
    let line = |w: &mut dyn Write, v: &mut dyn Iterator<Item = String>| -> std::io::Result<()> {
        let mut first = true;
        for s in v {
            if !first {
                w.write_all(b" ")?;
            }
            first = false;
            w.write_all(s.as_bytes())?;
        }
        w.write_all(b"\n")
    };
    line(w, &mut area.iter().map(|a| format_g(*a)))?;
    let mut buf = vec![0.0; n];
    let mut text = String::new();
    for m in 0..n {
        row(m, &mut buf);
        // One row's text at a time, reused: no allocation per value.
        text.clear();
        for (k, v) in buf.iter().enumerate() {
            if k > 0 {
                text.push(' ');
            }
            push_fixed6(&mut text, *v);
        }
        text.push('\n');
        w.write_all(text.as_bytes())?;
    }
    line(w, &mut emissivity.iter().map(|e| format!("{e:.3}")))
}

/// Append `v` as `format!("{v:.6}")` writes it (the digits of `v` rounded to six decimals),
/// without the general formatter for the common case: a value in [0, 1000) whose scaled value
/// `v · 10⁶` (within 1.2 · 10⁻⁷ of the exact product) lies farther than 10⁻⁶ from a tie rounds
/// to the same integer as the exact decimal does. Anything else goes to the formatter.
fn push_fixed6(out: &mut String, v: f64) {
    if v.to_bits() == 0 {
        out.push_str("0.000000");
        return;
    }
    if v > 0.0 && v < 1000.0 {
        let scaled = v * 1e6;
        let r = scaled.round();
        if (scaled - r).abs() < 0.5 - 1e-6 {
            let r = r as u64;
            let (int, frac) = (r / 1_000_000, r % 1_000_000);
            let mut digits = [0u8; 4];
            let mut k = 0;
            let mut i = int;
            loop {
                digits[k] = b'0' + (i % 10) as u8;
                k += 1;
                i /= 10;
                if i == 0 {
                    break;
                }
            }
            for d in digits[..k].iter().rev() {
                out.push(*d as char);
            }
            out.push('.');
            let mut f = [b'0'; 6];
            let mut x = frac;
            for d in f.iter_mut().rev() {
                *d = b'0' + (x % 10) as u8;
                x /= 10;
            }
            out.push_str(std::str::from_utf8(&f).expect("ASCII digits"));
            return;
        }
    }
    use std::fmt::Write as _;
    let _ = write!(out, "{v:.6}");
}

/// Bytes [`script_f`] holds at once for N surfaces: the dense view factors it is given, the
/// system matrix, its right-hand side, the solution and the result, N² f64 each (the LU
/// factors are made in place of a copy of the system: one more).
pub fn script_f_bytes(n: usize) -> u64 {
    6u64.saturating_mul(8)
        .saturating_mul((n as u64).saturating_mul(n as u64))
}

/// C's `%g`: six significant digits, trailing zeros dropped, exponent form outside 1e-4…1e6.
fn format_g(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let e = v.abs().log10().floor() as i32;
    if (-4..6).contains(&e) {
        let decimals = (5 - e).max(0) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let s = format!("{v:.5e}");
        let (m, x) = s.split_once('e').unwrap_or((&s, "0"));
        let m = if m.contains('.') {
            m.trim_end_matches('0').trim_end_matches('.')
        } else {
            m
        };
        let x: i32 = x.parse().unwrap_or(0);
        format!("{m}e{}{:02}", if x < 0 { '-' } else { '+' }, x.abs())
    }
}

/// Hottel's total exchange factors from view factors `f` (row-major N × N) and emissivities:
/// `ε_m [(I − F R)⁻¹ F]_mk ε_k` with R = diag(1 − ε), the fraction of what m would emit as a
/// black body that k absorbs after any number of diffuse reflections (Hottel & Sarofim,
/// *Radiative Transfer*, 1967, ch. 3; the "script-F" of View3D's `emit=1`). In a closed
/// enclosure row m sums to ε_m. Dense LU: O(N³) time and [`script_f_bytes`] of memory, which
/// the caller checks against what is available before calling.
pub fn script_f(f: &[f64], emissivity: &[f64]) -> Vec<f64> {
    use faer::linalg::solvers::Solve;
    let n = emissivity.len();
    // (I − F R) X = F.
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| {
        (i == j) as u8 as f64 - f[i * n + j] * (1.0 - emissivity[j])
    });
    let rhs = faer::Mat::<f64>::from_fn(n, n, |i, j| f[i * n + j]);
    let x = m.partial_piv_lu().solve(&rhs);
    let mut out = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            out[i * n + j] = emissivity[i] * x[(i, j)] * emissivity[j];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast six-decimal writer gives `format!("{v:.6}")`'s bytes: on a sweep of values
    /// (factors, their ties at the seventh decimal, the next representable values either
    /// side, negatives, zeros and values past its range).
    #[test]
    fn fixed_six_decimals_match_the_formatter() {
        let mut values = vec![
            0.0,
            -0.0,
            1.0,
            0.5,
            999.9999995,
            999.9999994,
            1e3,
            1e7,
            -0.25,
        ];
        let mut x = 0x2545_f491_4f6c_dd1d_u64;
        for k in 0..200_000u64 {
            // xorshift for values over [0, 1), then ties (k + 0.5)·10⁻⁶ and their neighbours.
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            values.push((x >> 11) as f64 / (1u64 << 53) as f64);
            let tie = (k as f64 + 0.5) * 1e-6;
            values.extend([
                tie,
                f64::from_bits(tie.to_bits() + 1),
                f64::from_bits(tie.to_bits() - 1),
            ]);
            values.push(k as f64 * 1e-3 + 1e-7);
        }
        let mut fast = String::new();
        for v in values {
            fast.clear();
            push_fixed6(&mut fast, v);
            assert_eq!(fast, format!("{v:.6}"), "{v:e}");
        }
    }

    /// Rows streamed from a closure give the same bytes as the dense table.
    #[test]
    fn streamed_rows_match_the_dense_table() {
        let dir = std::env::temp_dir().join(format!("view3d-rows-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let t = ViewFactorTable {
            area: vec![1.0, 2.5, 1e-5],
            f: (0..9).map(|k| k as f64 / 9.0).collect(),
            emissivity: vec![0.9, 0.5, 1.0],
            enclosure: true,
            emit: false,
        };
        write(&dir.join("a.vs3"), &t).unwrap();
        write_rows(
            &dir.join("b.vs3"),
            &t.area,
            &t.emissivity,
            true,
            false,
            |m, r| {
                for (k, v) in r.iter_mut().enumerate() {
                    *v = (m * 3 + k) as f64 / 9.0;
                }
            },
        )
        .unwrap();
        let a = std::fs::read(dir.join("a.vs3")).unwrap();
        assert_eq!(a, std::fs::read(dir.join("b.vs3")).unwrap());
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(script_f_bytes(100_000), 48 * 10_000_000_000);
    }

    #[test]
    fn g_format_matches_c() {
        for (v, s) in [
            (1.0, "1"),
            (9.0, "9"),
            (0.25, "0.25"),
            (123456.0, "123456"),
            (1234567.0, "1.23457e+06"),
            (0.0001, "0.0001"),
            (0.00001234, "1.234e-05"),
            (1.23456789, "1.23457"),
        ] {
            assert_eq!(format_g(v), s, "{v}");
        }
    }

    /// Two infinite parallel plates (F = 1 each way): the total exchange factor from plate 1
    /// absorbed by plate 2 is the classic 1 / (1/ε₁ + 1/ε₂ − 1); each row sums to ε.
    #[test]
    fn script_f_of_parallel_plates() {
        let f = [0.0, 1.0, 1.0, 0.0];
        let e = [0.8, 0.3];
        let s = script_f(&f, &e);
        let exchange = 1.0 / (1.0 / 0.8 + 1.0 / 0.3 - 1.0);
        assert!((s[1] - exchange).abs() < 1e-12);
        assert!((s[2] - exchange).abs() < 1e-12);
        assert!((s[0] + s[1] - 0.8).abs() < 1e-12);
        assert!((s[2] + s[3] - 0.3).abs() < 1e-12);
    }
}

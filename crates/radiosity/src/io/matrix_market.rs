//! Matrix Market files (NIST, "The Matrix Market Exchange Formats"), coordinate format: a
//! header `%%MatrixMarket matrix coordinate real general` (`integer` and `symmetric` are read
//! too), `%` comments, a size line `rows cols entries`, then one `i j value` line per entry,
//! 1-based. Form factors must be square, finite and non-negative, with row sums at most
//! 1 + 1e-3 (a patch cannot send out more than all of its energy). Duplicate entries are summed.

use super::{at, read_text, InputError};
use super::{write_atomic, OutputError};
use crate::system::SparseMatrix;
use std::io::Write;
use std::path::Path;

/// Largest row sum accepted.
pub const MAX_ROW_SUM: f64 = 1.0 + 1e-3;

/// Read a form-factor matrix.
pub fn read(path: &Path) -> Result<SparseMatrix, InputError> {
    let text = read_text(path)?;
    let mut lines = text.lines().enumerate().map(|(k, l)| (k + 1, l));
    let (_, header) = lines
        .next()
        .ok_or_else(|| at(path, 1, "empty file; expected a %%MatrixMarket header"))?;
    let h: Vec<String> = header
        .split_whitespace()
        .map(str::to_ascii_lowercase)
        .collect();
    if h.len() < 5 || h[0] != "%%matrixmarket" || h[1] != "matrix" {
        return Err(at(path, 1, "not a Matrix Market file: the first line must be '%%MatrixMarket matrix coordinate real general'"));
    }
    if h[2] != "coordinate" {
        return Err(at(
            path,
            1,
            format!("'{}' format is not supported; use coordinate", h[2]),
        ));
    }
    if h[3] != "real" && h[3] != "integer" && h[3] != "double" {
        return Err(at(
            path,
            1,
            format!(
                "'{}' entries are not supported; form factors are real",
                h[3]
            ),
        ));
    }
    let symmetric = match h[4].as_str() {
        "general" => false,
        "symmetric" => true,
        other => {
            return Err(at(
                path,
                1,
                format!("'{other}' symmetry is not supported; use general"),
            ))
        }
    };
    let mut size: Option<(usize, usize, usize)> = None;
    let mut triplets = Vec::new();
    let mut last_line = 1;
    // Bytes consumed so far, to check the counts of the size line against what follows.
    for (line, raw) in lines {
        last_line = line;
        let offset = raw.as_ptr() as usize - text.as_ptr() as usize + raw.len();
        let s = raw.trim();
        if s.is_empty() || s.starts_with('%') {
            continue;
        }
        let toks: Vec<&str> = s.split_whitespace().collect();
        match size {
            None => {
                if toks.len() != 3 {
                    return Err(at(path, line, "size line must be 'rows columns entries'"));
                }
                let p = |t: &str| {
                    t.parse::<usize>().map_err(|_| {
                        at(
                            path,
                            line,
                            format!("malformed count '{t}' in the size line"),
                        )
                    })
                };
                let (r, c, n) = (p(toks[0])?, p(toks[1])?, p(toks[2])?);
                if r != c {
                    return Err(at(
                        path,
                        line,
                        format!("the matrix is {r} × {c}; form factors need a square matrix"),
                    ));
                }
                if r == 0 {
                    return Err(at(path, line, "the matrix has no rows"));
                }
                if r > u32::MAX as usize {
                    return Err(at(path, line, format!("{r} rows are more than supported")));
                }
                // Every entry takes a line of at least 6 bytes ("1 1 0\n"), and a form-factor
                // matrix has at least one byte of data per row: counts the rest of the file
                // cannot hold are refused before anything is allocated for them.
                let rest = text.len() - offset;
                if n > rest / 6 + 1 {
                    return Err(at(
                        path,
                        line,
                        format!("the size line announces {n} entries but only {rest} bytes follow"),
                    ));
                }
                if r > rest + 1 {
                    return Err(at(
                        path,
                        line,
                        format!("the size line announces {r} rows but only {rest} bytes follow"),
                    ));
                }
                size = Some((r, c, n));
                triplets.reserve(n);
            }
            Some((n, _, _)) => {
                if toks.len() != 3 {
                    return Err(at(path, line, "an entry must be 'row column value'"));
                }
                let idx = |t: &str, what: &str| -> Result<u32, InputError> {
                    let v = t
                        .parse::<usize>()
                        .map_err(|_| at(path, line, format!("malformed {what} index '{t}'")))?;
                    if v == 0 || v > n {
                        return Err(at(
                            path,
                            line,
                            format!("{what} index {v} out of range 1..={n}"),
                        ));
                    }
                    Ok((v - 1) as u32)
                };
                let (i, j) = (idx(toks[0], "row")?, idx(toks[1], "column")?);
                let v: f64 = toks[2]
                    .parse()
                    .map_err(|_| at(path, line, format!("malformed number '{}'", toks[2])))?;
                if !v.is_finite() {
                    return Err(at(
                        path,
                        line,
                        format!("form factor '{}' is not finite", toks[2]),
                    ));
                }
                if v < 0.0 {
                    return Err(at(path, line, format!("form factor {v} is negative")));
                }
                triplets.push((i, j, v as f32));
                if symmetric && i != j {
                    triplets.push((j, i, v as f32));
                }
            }
        }
    }
    let (n, _, count) = size.ok_or_else(|| at(path, last_line, "no size line"))?;
    let entries = if symmetric {
        triplets.iter().filter(|t| t.0 <= t.1).count()
    } else {
        triplets.len()
    };
    if entries != count {
        return Err(at(
            path,
            last_line,
            format!("the size line announces {count} entries but the file has {entries}"),
        ));
    }
    let m = SparseMatrix::from_triplets(n, triplets);
    for i in 0..n {
        let s = m.row_sum(i);
        if s > MAX_ROW_SUM {
            return Err(at(path, 0, format!("row {} sums to {s:.6}, above 1 + 1e-3: a patch cannot send out more than all its energy", i + 1)));
        }
    }
    Ok(m)
}

/// Write `m` as `coordinate real general`, 1-based, rows in order; `comment` lines (without
/// the `%`) go after the header.
pub fn write(path: &Path, m: &SparseMatrix, comment: &[String]) -> Result<(), OutputError> {
    write_atomic(path, |out| {
        writeln!(out, "%%MatrixMarket matrix coordinate real general")?;
        for c in comment {
            writeln!(out, "% {c}")?;
        }
        writeln!(out, "{} {} {}", m.n(), m.n(), m.nnz())?;
        for (i, j, v) in m.triplets() {
            writeln!(out, "{} {} {}", i + 1, j + 1, v)?;
        }
        Ok(())
    })
}

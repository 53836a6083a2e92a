//! `radiosity-bench view3d`: our adaptive view factors side by side with NIST View3D (Walton,
//! NISTIR 6925, 2002) on open urban canyons. View3D is built here from its public source (the
//! folder given by `--source`, e.g. a checkout of jasondegraw/View3D) with the system's C
//! compiler at `-O2`, from the files its `src/CMakeLists.txt` lists for the `view3d`
//! executable; nothing is downloaded. Each canyon (3 × 3 buildings 10 m square and 10–30 m
//! high, 10 m streets, a 70 m ground: 121 squares of 10 m, each cut k × k, so 121 k² facets,
//! every facet a View3D surface, the sky open) is written as a `.vs3` file; `radiosity
//! form-factors FILE --method adaptive --format view3d` and `View3D FILE OUT` each run as a
//! child process, timed by `wait4` (user + system CPU seconds and peak resident memory of that
//! child alone) and by the wall clock. The two outputs (View3D's text format, both `%.6f`) are
//! then read row by row, never both whole, and compared: mean and worst |ΔF| over all N²
//! entries, mean and worst |Δ row sum|, and each facet's sky view 1 − Σ_j F_ij (written to
//! `skyview-N.csv`).

use crate::args::View3dArgs;
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufRead, BufReader, Write as _};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

/// The buildings' heights for the side-by-side canyons (metres, row by row): multiples of the
/// 10 m module, 180 m in all, so that every face is whole 10 m squares (121 of them).
pub const HEIGHTS: [f64; 9] = [20.0, 30.0, 10.0, 20.0, 20.0, 30.0, 10.0, 20.0, 20.0];

/// Agreement of two view-factor matrices, accumulated a row at a time (`ours` against
/// `theirs`, the reference). Row sums and sky views (1 − row sum, the share of a facet's
/// hemisphere that sees no surface in an open scene) are summed in f64.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Agreement {
    /// Rows added.
    pub rows: usize,
    /// Entries compared (the sum of the rows' lengths).
    pub entries: usize,
    /// Σ |ΔF| over every entry.
    pub sum_df: f64,
    /// The worst |ΔF| and its (row, column), 0-based.
    pub worst_df: (f64, usize, usize),
    /// Σ over rows of |Σ_j ours − Σ_j theirs|.
    pub sum_drow: f64,
    /// The worst |Δ row sum| and its row.
    pub worst_drow: (f64, usize),
    /// Σ over rows of our sky view.
    pub sky_ours: f64,
    /// Σ over rows of the reference's sky view.
    pub sky_theirs: f64,
}

impl Agreement {
    /// Add one row of each; returns the two rows' sums (ours, theirs). The rows must have the
    /// same length.
    pub fn add_row(&mut self, ours: &[f64], theirs: &[f64]) -> (f64, f64) {
        debug_assert_eq!(ours.len(), theirs.len());
        let i = self.rows;
        let (mut so, mut st) = (0.0, 0.0);
        for (j, (a, b)) in ours.iter().zip(theirs).enumerate() {
            let d = (a - b).abs();
            self.sum_df += d;
            if d > self.worst_df.0 {
                self.worst_df = (d, i, j);
            }
            so += a;
            st += b;
        }
        let d = (so - st).abs();
        self.sum_drow += d;
        if d > self.worst_drow.0 {
            self.worst_drow = (d, i);
        }
        self.sky_ours += 1.0 - so;
        self.sky_theirs += 1.0 - st;
        self.entries += ours.len();
        self.rows += 1;
        (so, st)
    }

    /// Mean |ΔF| over every entry compared.
    pub fn mean_df(&self) -> f64 {
        self.sum_df / self.entries.max(1) as f64
    }

    /// Mean |Δ row sum| over the rows.
    pub fn mean_drow(&self) -> f64 {
        self.sum_drow / self.rows.max(1) as f64
    }

    /// Mean sky view (1 − row sum) of ours and of the reference.
    pub fn mean_sky(&self) -> (f64, f64) {
        let r = self.rows.max(1) as f64;
        (self.sky_ours / r, self.sky_theirs / r)
    }
}

/// The agreement of two dense row-major N × N matrices (the files' rows go through
/// [`Agreement::add_row`] the same way).
#[cfg(test)]
pub fn agreement_dense(ours: &[f64], theirs: &[f64], n: usize) -> Agreement {
    assert_eq!(ours.len(), n * n);
    assert_eq!(theirs.len(), n * n);
    let mut a = Agreement::default();
    for i in 0..n {
        a.add_row(&ours[i * n..(i + 1) * n], &theirs[i * n..(i + 1) * n]);
    }
    a
}

/// The agreement of two sparse matrices of the same order, each row expanded once into a
/// dense buffer (absent entries are zeros).
#[cfg(test)]
pub fn agreement_sparse(
    ours: &radiosity::system::SparseMatrix,
    theirs: &radiosity::system::SparseMatrix,
) -> Agreement {
    let n = ours.n();
    assert_eq!(theirs.n(), n);
    let (mut ro, mut rt) = (vec![0.0; n], vec![0.0; n]);
    let mut a = Agreement::default();
    for i in 0..n {
        ro.fill(0.0);
        rt.fill(0.0);
        for &(j, v) in ours.row_entries(i) {
            ro[j as usize] += v as f64;
        }
        for &(j, v) in theirs.row_entries(i) {
            rt[j as usize] += v as f64;
        }
        a.add_row(&ro, &rt);
    }
    a
}

/// A View3D text view-factor file (`out=0`: header, areas, N rows, emissivities) read one row
/// at a time.
struct VfRows {
    path: PathBuf,
    reader: BufReader<File>,
    line: String,
    line_no: usize,
    n: usize,
    area: Vec<f64>,
}

impl VfRows {
    fn open(path: &Path) -> Result<Self> {
        let file = File::open(path).with_context(|| format!("{}", path.display()))?;
        let mut r = VfRows {
            path: path.to_path_buf(),
            reader: BufReader::with_capacity(1 << 20, file),
            line: String::new(),
            line_no: 0,
            n: 0,
            area: Vec::new(),
        };
        r.next_line()?;
        let words: Vec<&str> = r.line.split_whitespace().collect();
        if words.len() < 6 || !words[0].starts_with("View3D") {
            bail!(
                "{}:1: not a View3D view-factor file (header `{}`)",
                path.display(),
                r.line.trim_end()
            );
        }
        if words[2] != "0" {
            bail!(
                "{}:1: format {} (only View3D's text output, out=0, is read)",
                path.display(),
                words[2]
            );
        }
        r.n = words[5].parse().map_err(|_| {
            anyhow::anyhow!("{}:1: bad surface count `{}`", path.display(), words[5])
        })?;
        let mut area = Vec::with_capacity(r.n);
        r.numbers(&mut area)?;
        r.area = area;
        Ok(r)
    }

    fn next_line(&mut self) -> Result<()> {
        self.line.clear();
        self.line_no += 1;
        let got = self
            .reader
            .read_line(&mut self.line)
            .with_context(|| format!("{}:{}", self.path.display(), self.line_no))?;
        if got == 0 {
            bail!(
                "{}:{}: the file ends early ({} surfaces)",
                self.path.display(),
                self.line_no,
                self.n
            );
        }
        Ok(())
    }

    /// The next line's N numbers into `out`.
    fn numbers(&mut self, out: &mut Vec<f64>) -> Result<()> {
        self.next_line()?;
        out.clear();
        for w in self.line.split_whitespace() {
            out.push(w.parse().map_err(|_| {
                anyhow::anyhow!(
                    "{}:{}: `{w}` is not a number",
                    self.path.display(),
                    self.line_no
                )
            })?);
        }
        if out.len() != self.n {
            bail!(
                "{}:{}: {} values where {} surfaces need {}",
                self.path.display(),
                self.line_no,
                out.len(),
                self.n,
                self.n
            );
        }
        Ok(())
    }
}

/// Read `ours` and (when given) `theirs` row by row: their agreement (against themselves when
/// alone), and each facet's sky view written to `csv` (`facet,sky_view_ours,sky_view_view3d`).
fn compare_files(ours: &Path, theirs: Option<&Path>, csv: &Path) -> Result<Agreement> {
    let mut o = VfRows::open(ours)?;
    let mut t = theirs.map(VfRows::open).transpose()?;
    if let Some(t) = &t {
        if t.n != o.n {
            bail!(
                "{}: {} surfaces, {}: {}",
                ours.display(),
                o.n,
                t.path.display(),
                t.n
            );
        }
        for (k, (a, b)) in o.area.iter().zip(&t.area).enumerate() {
            if (a - b).abs() > 1e-4 * a.abs().max(b.abs()) {
                bail!(
                    "surface {}: area {a} in {}, {b} in {} (not the same scene)",
                    k + 1,
                    ours.display(),
                    t.path.display()
                );
            }
        }
    }
    let (mut ro, mut rt) = (Vec::with_capacity(o.n), Vec::with_capacity(o.n));
    let mut a = Agreement::default();
    let mut sky = String::from("facet,sky_view_ours,sky_view_view3d\n");
    for i in 0..o.n {
        o.numbers(&mut ro)?;
        let (so, st) = match &mut t {
            Some(t) => {
                t.numbers(&mut rt)?;
                a.add_row(&ro, &rt)
            }
            None => a.add_row(&ro, &ro),
        };
        let _ = write!(sky, "{},{:.6},", i + 1, 1.0 - so);
        if t.is_some() {
            let _ = write!(sky, "{:.6}", 1.0 - st);
        }
        sky.push('\n');
    }
    radiosity::io::write_atomic::<radiosity::io::OutputError>(csv, |w| {
        w.write_all(sky.as_bytes())
    })?;
    Ok(a)
}

/// The View3D source folder (the checkout or its `src`) and the C files of the `view3d`
/// executable, as its `CMakeLists.txt` lists them (`set(SRCS …)`).
fn view3d_sources(source: &Path) -> Result<(PathBuf, Vec<PathBuf>)> {
    if !source.is_dir() {
        bail!(
            "{}: no View3D source folder (a checkout of https://github.com/jasondegraw/View3D)",
            source.display()
        );
    }
    let src = [source.join("src"), source.to_path_buf()]
        .into_iter()
        .find(|d| d.join("CMakeLists.txt").is_file() && d.join("v3main.c").is_file())
        .ok_or_else(|| {
            anyhow::anyhow!(
                "{}: no View3D source here (neither it nor its src/ holds CMakeLists.txt and v3main.c)",
                source.display()
            )
        })?;
    let cmake = src.join("CMakeLists.txt");
    let text = std::fs::read_to_string(&cmake).with_context(|| format!("{}", cmake.display()))?;
    let start = text
        .find("set(SRCS")
        .ok_or_else(|| anyhow::anyhow!("{}: no `set(SRCS …)` list", cmake.display()))?;
    let list = &text[start + "set(SRCS".len()..];
    let list = &list[..list
        .find(')')
        .ok_or_else(|| anyhow::anyhow!("{}: `set(SRCS` is not closed", cmake.display()))?];
    let files: Vec<PathBuf> = list.split_whitespace().map(|f| src.join(f)).collect();
    if files.is_empty() {
        bail!("{}: `set(SRCS …)` lists no files", cmake.display());
    }
    if let Some(f) = files.iter().find(|f| !f.is_file()) {
        bail!("{}: listed in {} but missing", f.display(), cmake.display());
    }
    Ok((src, files))
}

/// Build View3D from `source` into `out/View3D` with `$CC` (default `cc`) at `-O2`; returns
/// the executable and the build's wall seconds.
pub fn build_view3d(source: &Path, out: &Path) -> Result<(PathBuf, f64)> {
    let (src, files) = view3d_sources(source)?;
    let cc = std::env::var_os("CC").unwrap_or_else(|| "cc".into());
    let exe = out.join("View3D");
    let t = Instant::now();
    let result = Command::new(&cc)
        .arg("-O2")
        .arg("-w")
        .arg("-o")
        .arg(&exe)
        .args(&files)
        .arg("-lm")
        .current_dir(&src)
        .stdin(Stdio::null())
        .output();
    let output = match result {
        Ok(o) => o,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!(
            "{}: no C compiler (install one, e.g. gcc, or set CC)",
            cc.to_string_lossy()
        ),
        Err(e) => bail!("{}: {e}", cc.to_string_lossy()),
    };
    if !output.status.success() {
        let err = String::from_utf8_lossy(&output.stderr);
        let last = err
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("");
        bail!(
            "{} -O2 failed to build View3D from {} ({}): {last}",
            cc.to_string_lossy(),
            src.display(),
            output.status
        );
    }
    Ok((exe, t.elapsed().as_secs_f64()))
}

/// What one child process used.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Usage {
    pub wall: f64,
    pub cpu: f64,
    pub peak_mib: f64,
}

/// Run `cmd` (its output to `log`), wait for it with `wait4`: wall seconds, user + system CPU
/// seconds and peak resident memory of that child alone.
pub(crate) fn run_measured(mut cmd: Command, log: &Path) -> Result<Usage> {
    let what = format!("{:?}", cmd.get_program());
    let out = File::create(log).with_context(|| format!("{}", log.display()))?;
    let err = out.try_clone()?;
    cmd.stdin(Stdio::null())
        .stdout(Stdio::from(out))
        .stderr(Stdio::from(err));
    let t = Instant::now();
    let child = cmd.spawn().with_context(|| what.clone())?;
    let (ok, cpu, peak_mib) = wait_child(child)?;
    let wall = t.elapsed().as_secs_f64();
    if !ok {
        let text = std::fs::read_to_string(log).unwrap_or_default();
        let last = text
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("");
        bail!("{what} failed (log {}): {last}", log.display());
    }
    Ok(Usage {
        wall,
        cpu,
        peak_mib,
    })
}

/// Reap `child` with `wait4`: (exited with 0, user + system CPU seconds, peak resident MiB).
#[cfg(target_os = "linux")]
#[allow(unsafe_code)]
fn wait_child(child: std::process::Child) -> Result<(bool, f64, f64)> {
    let pid = child.id() as libc::pid_t;
    let mut status: libc::c_int = 0;
    // SAFETY: rusage is plain old data, all zeros is a valid value.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    loop {
        // SAFETY: `status` and `ru` are valid for writes; `pid` is our own unreaped child
        // (std's `Child` never waits on drop).
        let r = unsafe { libc::wait4(pid, &mut status, 0, &mut ru) };
        if r == pid {
            break;
        }
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            bail!("wait4: {e}");
        }
    }
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    let ok = libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0;
    // ru_maxrss is in KiB on Linux (getrusage(2)).
    Ok((
        ok,
        secs(ru.ru_utime) + secs(ru.ru_stime),
        ru.ru_maxrss as f64 / 1024.0,
    ))
}

/// Without `wait4`: the exit status only (CPU time and memory unknown).
#[cfg(not(target_os = "linux"))]
fn wait_child(mut child: std::process::Child) -> Result<(bool, f64, f64)> {
    let s = child.wait()?;
    Ok((s.success(), f64::NAN, f64::NAN))
}

/// The medians of repeated runs.
fn medians(runs: &[Usage]) -> Usage {
    let m = |f: fn(&Usage) -> f64| crate::median(runs.iter().map(f).collect());
    Usage {
        wall: m(|u| u.wall),
        cpu: m(|u| u.cpu),
        peak_mib: m(|u| u.peak_mib),
    }
}

/// Run the mode.
pub fn run(a: &View3dArgs, threads: Option<usize>) -> Result<()> {
    crate::positive(&[("--runs", a.runs)])?;
    if !(1e-10..=0.1).contains(&a.accuracy) {
        bail!("--accuracy {}: must be in [1e-10, 0.1]", a.accuracy);
    }
    if let Some(&s) = a.sizes.iter().find(|&&s| s == 0) {
        bail!("--sizes {s}: must be positive");
    }
    let ours_exe = crate::radiosity_exe()?;
    let needs_view3d = a.sizes.iter().any(|&s| s <= a.view3d_up_to);
    if needs_view3d {
        view3d_sources(&a.source)?;
    }
    let created = !a.out.exists();
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}", a.out.display()))?;
    let out = a
        .out
        .canonicalize()
        .with_context(|| format!("{}", a.out.display()))?;
    let view3d = if needs_view3d {
        let (exe, secs) = build_view3d(&a.source, &out).inspect_err(|_| {
            if created {
                let _ = std::fs::remove_dir(&out);
            }
        })?;
        println!(
            "built {} from {} with cc -O2 in {secs:.1} s",
            exe.display(),
            a.source.display()
        );
        Some(exe)
    } else {
        None
    };
    println!(
        "{:>7} {:>7} {:>8} {:>8} {:>9} {:>10} {:>10} {:>10} {:>10} {:>9}",
        "facets",
        "tool",
        "cpu s",
        "wall s",
        "peak MiB",
        "mean|ΔF|",
        "max|ΔF|",
        "mean|ΔΣ|",
        "max|ΔΣ|",
        "mean sky"
    );
    for &size in &a.sizes {
        let (text, n) = crate::canyon::canyon_vs3_with(size, false, &HEIGHTS);
        let scene = out.join(format!("canyon-{n}.vs3"));
        radiosity::io::write_atomic::<radiosity::io::OutputError>(&scene, |w| {
            w.write_all(text.as_bytes())
        })?;
        let ours_vf = out.join(format!("ours-{n}.vf"));
        let mut ours = Vec::new();
        for _ in 0..a.runs {
            let mut cmd = Command::new(&ours_exe);
            cmd.arg("form-factors")
                .arg(&scene)
                .args(["--method", "adaptive", "--format", "view3d"])
                .arg("--accuracy")
                .arg(a.accuracy.to_string())
                .arg("-o")
                .arg(&ours_vf)
                .current_dir(&out);
            if let Some(t) = threads {
                cmd.arg("--threads").arg(t.to_string());
            }
            ours.push(run_measured(cmd, &out.join(format!("ours-{n}.log")))?);
        }
        let theirs_vf = out.join(format!("view3d-{n}.vf"));
        let mut theirs = Vec::new();
        if let (Some(exe), true) = (&view3d, n <= a.view3d_up_to) {
            for _ in 0..a.runs {
                let mut cmd = Command::new(exe);
                cmd.arg(&scene).arg(&theirs_vf).current_dir(&out);
                theirs.push(run_measured(cmd, &out.join(format!("view3d-{n}.log")))?);
            }
        }
        let csv = out.join(format!("skyview-{n}.csv"));
        let agree = compare_files(
            &ours_vf,
            (!theirs.is_empty()).then_some(theirs_vf.as_path()),
            &csv,
        )?;
        let (sky_ours, sky_theirs) = agree.mean_sky();
        let row = |tool: &str, u: &Usage, cols: [String; 4], sky: f64| {
            println!(
                "{:>7} {:>7} {:>8.2} {:>8.2} {:>9.0} {:>10} {:>10} {:>10} {:>10} {:>9.4}",
                n, tool, u.cpu, u.wall, u.peak_mib, cols[0], cols[1], cols[2], cols[3], sky
            );
        };
        let dash = || ["-".to_string(), "-".into(), "-".into(), "-".into()];
        if !theirs.is_empty() {
            row("View3D", &medians(&theirs), dash(), sky_theirs);
            row(
                "ours",
                &medians(&ours),
                [
                    format!("{:.2e}", agree.mean_df()),
                    format!("{:.2e}", agree.worst_df.0),
                    format!("{:.2e}", agree.mean_drow()),
                    format!("{:.2e}", agree.worst_drow.0),
                ],
                sky_ours,
            );
            let (u, t) = (medians(&ours), medians(&theirs));
            println!(
                "        ours/View3D: cpu {:.3}, wall {:.3}, memory {:.2}; worst |ΔF| at F[{}][{}], worst |ΔΣ| at facet {}; sky view per facet in {}",
                u.cpu / t.cpu,
                u.wall / t.wall,
                u.peak_mib / t.peak_mib,
                agree.worst_df.1 + 1,
                agree.worst_df.2 + 1,
                agree.worst_drow.1 + 1,
                csv.display()
            );
        } else {
            row("ours", &medians(&ours), dash(), sky_ours);
        }
        if !a.keep {
            let _ = std::fs::remove_file(&ours_vf);
            let _ = std::fs::remove_file(&theirs_vf);
        }
        let _ = std::io::stdout().flush();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use radiosity::system::SparseMatrix;

    /// Two 3 × 3 matrices whose differences are worked out by hand.
    fn pair() -> (Vec<f64>, Vec<f64>) {
        #[rustfmt::skip]
        let ours = vec![
            0.0, 0.2, 0.3,
            0.1, 0.0, 0.5,
            0.25, 0.25, 0.0,
        ];
        #[rustfmt::skip]
        let theirs = vec![
            0.0, 0.2, 0.28,
            0.1, 0.0, 0.45,
            0.25, 0.26, 0.0,
        ];
        (ours, theirs)
    }

    /// |ΔF| = 0.02 (row 1), 0.05 (row 2), 0.01 (row 3): sum 0.08 over 9 entries, worst 0.05
    /// at (1, 2). Row sums: ours 0.5, 0.6, 0.5; theirs 0.48, 0.55, 0.51: |Δ| 0.02, 0.05,
    /// 0.01, mean 0.08/3, worst 0.05 at row 1. Sky views: ours 0.5, 0.4, 0.5 (mean 1.4/3);
    /// theirs 0.52, 0.45, 0.49 (mean 1.46/3).
    fn check(a: &Agreement) {
        let close = |x: f64, y: f64| (x - y).abs() < 1e-12;
        assert_eq!((a.rows, a.entries), (3, 9));
        assert!(close(a.mean_df(), 0.08 / 9.0), "{}", a.mean_df());
        assert!(close(a.worst_df.0, 0.05));
        assert_eq!((a.worst_df.1, a.worst_df.2), (1, 2));
        assert!(close(a.mean_drow(), 0.08 / 3.0), "{}", a.mean_drow());
        assert!(close(a.worst_drow.0, 0.05));
        assert_eq!(a.worst_drow.1, 1);
        let (so, st) = a.mean_sky();
        assert!(close(so, 1.4 / 3.0) && close(st, 1.46 / 3.0), "{so} {st}");
    }

    #[test]
    fn agreement_of_dense_matrices_by_hand() {
        let (o, t) = pair();
        check(&agreement_dense(&o, &t, 3));
        // Against itself: nothing differs.
        let same = agreement_dense(&o, &o, 3);
        assert_eq!((same.sum_df, same.sum_drow), (0.0, 0.0));
    }

    /// The same through sparse matrices (zeros absent); the values are f32 there, so the
    /// tolerance is f32's rounding of entries below 1 (6e-8 each, 9 of them).
    #[test]
    fn agreement_of_sparse_matrices_by_hand() {
        let (o, t) = pair();
        let sparse = |m: &[f64]| {
            SparseMatrix::from_rows(
                (0..3)
                    .map(|i| {
                        (0..3)
                            .filter(|&j| m[i * 3 + j] != 0.0)
                            .map(|j| (j as u32, m[i * 3 + j] as f32))
                            .collect()
                    })
                    .collect(),
            )
        };
        let a = agreement_sparse(&sparse(&o), &sparse(&t));
        let close = |x: f64, y: f64| (x - y).abs() < 1e-6;
        assert!(close(a.mean_df(), 0.08 / 9.0));
        assert!(close(a.worst_df.0, 0.05) && (a.worst_df.1, a.worst_df.2) == (1, 2));
        assert!(close(a.mean_drow(), 0.08 / 3.0) && a.worst_drow.1 == 1);
        let (so, st) = a.mean_sky();
        assert!(close(so, 1.4 / 3.0) && close(st, 1.46 / 3.0));
    }

    /// The file reader: View3D's text output with the same matrices gives the same figures,
    /// and a short row or a word that is not a number is named with its file and line.
    #[test]
    fn view3d_files_compared_row_by_row() {
        let dir = std::env::temp_dir().join(format!("bench-view3d-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let write = |name: &str, m: &[f64]| {
            let mut s = String::from("View3D 4.0.0 0 0 0 3\n1 2 3\n");
            for i in 0..3 {
                let row: Vec<String> = m[i * 3..i * 3 + 3]
                    .iter()
                    .map(|v| format!("{v:.6}"))
                    .collect();
                s += &row.join(" ");
                s.push('\n');
            }
            s += "0.900 0.900 0.900\n";
            std::fs::write(dir.join(name), s).unwrap();
        };
        let (o, t) = pair();
        write("o.vf", &o);
        write("t.vf", &t);
        let csv = dir.join("sky.csv");
        let a = compare_files(&dir.join("o.vf"), Some(&dir.join("t.vf")), &csv).unwrap();
        check(&a);
        let sky = std::fs::read_to_string(&csv).unwrap();
        assert_eq!(
            sky,
            "facet,sky_view_ours,sky_view_view3d\n1,0.500000,0.520000\n2,0.400000,0.450000\n3,0.500000,0.490000\n"
        );
        std::fs::write(
            dir.join("bad.vf"),
            "View3D 4.0.0 0 0 0 3\n1 2 3\n0 0.2 0.3\n0.1 x 0.5\n",
        )
        .unwrap();
        let e = compare_files(&dir.join("bad.vf"), None, &csv).unwrap_err();
        assert!(
            format!("{e:#}").contains("bad.vf:4: `x` is not a number"),
            "{e:#}"
        );
        std::fs::write(dir.join("short.vf"), "View3D 4.0.0 0 0 0 3\n1 2 3\n0 0.2\n").unwrap();
        let e = compare_files(&dir.join("short.vf"), None, &csv).unwrap_err();
        assert!(
            format!("{e:#}").contains("short.vf:3: 2 values where 3 surfaces need 3"),
            "{e:#}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// The side-by-side canyon has exactly 121 k² facets: every face is whole 10 m squares.
    #[test]
    fn side_by_side_canyons_have_121_k_squared_facets() {
        for k in [2, 4, 8, 13] {
            let (_, n) = crate::canyon::canyon_vs3_with(121 * k * k, false, &HEIGHTS);
            assert_eq!(n, 121 * k * k);
        }
    }

    #[test]
    fn missing_source_is_one_line() {
        let e = build_view3d(Path::new("/nonexistent/view3d"), &std::env::temp_dir()).unwrap_err();
        let s = format!("{e:#}");
        assert!(
            s.contains("/nonexistent/view3d: no View3D source folder"),
            "{s}"
        );
        assert!(!s.contains('\n'));
    }
}

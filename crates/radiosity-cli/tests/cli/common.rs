//! What every test of the command shares: running the binary in a scratch folder, asserting
//! success (with the arguments and stderr on failure) or a clean failure (one line, no panic,
//! nothing written), and reading what it wrote. `bench.rs` and `fuzz.rs` use nothing else.

// Each test file uses part of this; a test target built from a few of them uses less.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `radiosity` binary of this package, as a command to add arguments to.
pub fn bin() -> Command {
    Command::new(crate::BIN)
}

/// The `radiosity` command itself, beside the binary under test (cargo builds every binary of
/// the workspace into one folder).
pub fn radiosity() -> Command {
    Command::new(Path::new(crate::BIN).with_file_name("radiosity"))
}

/// Run `radiosity ARGS` in `dir` and return its stdout, failing with its stderr.
pub fn radiosity_ok(args: &[&str], dir: &Path) -> String {
    let out = radiosity().args(args).current_dir(dir).output().unwrap();
    succeed(&out)
}

/// A fresh scratch folder for one test.
pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("radiosity-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Run `radiosity ARGS` in `dir`: its exit status, stdout and stderr.
pub fn run(args: &[&str], dir: &Path) -> Output {
    bin().args(args).current_dir(dir).output().unwrap()
}

/// A run's stdout as text.
pub fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A run's stderr as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Assert that a run succeeded (else fail with its stderr); its stdout.
pub fn succeed(out: &Output) -> String {
    assert!(out.status.success(), "{}", stderr(out));
    stdout(out)
}

/// Run `radiosity ARGS` in `dir` and assert that it succeeded (else fail naming the arguments,
/// with its stderr); its stdout.
pub fn run_ok(args: &[&str], dir: &Path) -> String {
    let out = run(args, dir);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    stdout(&out)
}

/// Assert a failure: non-zero exit, exactly one line on stderr containing every `needles`,
/// no panic, and no file left in `dir` besides `keep`.
pub fn assert_fails(out: &Output, needles: &[&str], dir: &Path, keep: &[&str]) {
    let err = stderr(out);
    assert!(!out.status.success(), "succeeded: {err}");
    assert_ne!(out.status.code(), Some(101), "panicked: {err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.contains("warning:")).collect();
    assert_eq!(lines.len(), 1, "expected one line, got: {err}");
    for n in needles {
        assert!(lines[0].contains(n), "'{}' lacks '{n}'", lines[0]);
    }
    let left: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !keep.contains(&n.as_str()))
        .collect();
    assert!(left.is_empty(), "files left behind: {left:?}");
}

/// Run `radiosity ARGS` in `dir` and [`assert_fails`] on it.
pub fn fails(args: &[&str], dir: &Path, needles: &[&str], keep: &[&str]) {
    assert_fails(&run(args, dir), needles, dir, keep);
}

/// Write a file of `dir`.
pub fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap();
}

/// A file of `dir` as text (failing with its path when it cannot be read).
pub fn read(dir: &Path, name: &str) -> String {
    let path = dir.join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A file of `dir` as bytes (failing with its path when it cannot be read).
pub fn read_bytes(dir: &Path, name: &str) -> Vec<u8> {
    let path = dir.join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A CSV as a header and rows of fields.
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect::<Vec<_>>())
        .collect();
    (header, rows)
}

/// The index of the column `name` of a CSV header.
pub fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

/// The share of pixels brighter than 20 of 255 in any channel.
pub fn lit_fraction(png: &Path) -> f64 {
    let img = image::open(png).unwrap().to_rgb8();
    let lit = img.pixels().filter(|p| p.0.iter().any(|c| *c > 20)).count();
    lit as f64 / img.pixels().count() as f64
}

/// Pixels of a PFM the CLI wrote (rows bottom to top; order does not matter here).
pub fn read_pfm_pixels(path: &Path) -> Vec<[f32; 3]> {
    let bytes = std::fs::read(path).unwrap();
    let mut parts = bytes.splitn(4, |&b| b == b'\n');
    assert_eq!(parts.next(), Some(&b"PF"[..]));
    let _size = parts.next().unwrap();
    let _scale = parts.next().unwrap();
    parts
        .next()
        .unwrap()
        .chunks_exact(12)
        .map(|c| {
            let f = |k: usize| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap());
            [f(0), f(1), f(2)]
        })
        .collect()
}

/// The committed glTF and PLY test scenes of the library (`crates/radiosity/tests/data`).
pub fn test_scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../radiosity/tests/data")
        .join(name)
}

/// A file of the scenes in `../shared/scenes` beside the repository (RenderPark's MGF scenes,
/// View3D's examples); failing, naming the folder, when it is absent. The tests that read
/// them are `#[ignore]`d, so that `cargo test` needs only the repository: `--include-ignored`
/// runs them.
pub fn shared_scene(path: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes");
    assert!(
        dir.is_dir(),
        "{} is absent: RenderPark's and View3D's scenes live in the shared folder beside the \
         repository",
        dir.display()
    );
    dir.join(path)
}

/// One of View3D's examples (`../shared/scenes/view3d`).
pub fn shared_view3d(name: &str) -> PathBuf {
    shared_scene(&format!("view3d/{name}"))
}

/// One of RenderPark's scenes (`../shared/scenes/renderpark`).
pub fn shared_renderpark(name: &str) -> PathBuf {
    shared_scene(&format!("renderpark/{name}"))
}

/// `mpirun -np K BIN ARGS` (the binary under test) in `dir` (as root too; oversubscribed, one
/// thread a rank).
#[cfg(feature = "mpi")]
pub fn mpirun(k: usize, args: &[&str], dir: &Path) -> Output {
    Command::new("mpirun")
        .args([
            "--allow-run-as-root",
            "--oversubscribe",
            "-np",
            &k.to_string(),
        ])
        .arg(crate::BIN)
        .args(args)
        .args(["--threads", "1"])
        .current_dir(dir)
        .output()
        .expect("mpirun (Open MPI's openmpi-bin) on the PATH")
}

/// A Matrix Market file the command wrote: (size, 1-based entries).
pub fn read_mtx(path: &Path) -> (usize, Vec<(usize, usize, f64)>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('%'));
    let n: usize = lines
        .next()
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let entries = lines
        .map(|l| {
            let t: Vec<&str> = l.split_whitespace().collect();
            (
                t[0].parse().unwrap(),
                t[1].parse().unwrap(),
                t[2].parse().unwrap(),
            )
        })
        .collect();
    (n, entries)
}

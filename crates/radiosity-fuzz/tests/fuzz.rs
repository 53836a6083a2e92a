//! `radiosity-fuzz`: a short seeded fuzz of the option parser and of one file parser runs
//! clean, and impossible options are refused on one line.

use std::process::Command;

fn fuzz(args: &[&str], dir: &std::path::Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_radiosity-fuzz"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("radiosity-fuzz-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// CI's deterministic slice of the fuzz campaign: 300 seeded cases of every parser and of the
/// option parser, each run to the end with no panic, no case over 10 s and none over 1 GiB of
/// heap (the binary fails otherwise), and every parser listed in the report.
#[test]
fn a_short_fuzz_of_every_parser_and_the_options_runs_clean() {
    let dir = scratch("short");
    let out = fuzz(&["--cases", "300", "--seed", "11", "--out", "fz"], &dir);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split_whitespace().collect())
        .filter(|r: &Vec<&str>| r.len() >= 4 && r[1] == "300")
        .collect();
    for name in [
        "obj",
        "mtl",
        "mgf",
        "gltf",
        "glb",
        "ply-ascii",
        "ply-binary",
        "matrix-market",
        "patches-csv",
        "vs3",
        "vs3a",
        "bc-csv",
        "pfm",
        "ies",
        "ies-b",
        "ies-a",
        "ldt",
        "schedule",
        "points",
        "gltf-lights",
        "epw",
        "options",
    ] {
        let row = rows
            .iter()
            .find(|r| r[0] == name)
            .unwrap_or_else(|| panic!("{name} missing from the report:\n{text}"));
        assert_eq!(row[3], "0", "{name} panicked:\n{text}");
    }
}

#[test]
fn impossible_options_are_refused_on_one_line() {
    let dir = scratch("refused");
    for args in [&["--cases", "0"][..], &["--cases", "ten"][..]] {
        let out = fuzz(args, &dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.starts_with("radiosity-fuzz: error:"), "{err}");
    }
}

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

#[test]
fn a_short_fuzz_of_the_options_and_a_parser_runs_clean() {
    let dir = scratch("short");
    let out = fuzz(
        &["--cases", "500", "--targets", "options,obj", "--out", "fz"],
        &dir,
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("options") && text.contains("obj"), "{text}");
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

//! The Khronos glTF Validator, run over the glTF files the tests write. Shared by the library's
//! and the command's tests (the latter include this file by path).

use std::path::{Path, PathBuf};
use std::process::Command;

/// Run the Khronos glTF Validator (`.ci/validate-gltf.js`, npm package `gltf-validator`) over
/// `files`, asserting no errors. `.ci/run` installs it and sets
/// `RADIOSITY_REQUIRE_GLTF_VALIDATOR=1`, so CI fails without it; elsewhere a missing validator
/// is reported and the check skipped.
pub fn validate_gltf(files: &[PathBuf]) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let module = std::env::var_os("GLTF_VALIDATOR_MODULE")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target/gltf-validator/node_modules/gltf-validator"));
    let required = std::env::var("RADIOSITY_REQUIRE_GLTF_VALIDATOR").is_ok_and(|v| v == "1");
    let node = Command::new("node").arg("--version").output();
    if !module.exists() || node.is_err() {
        assert!(
            !required,
            "the glTF validator is required but {} or node is missing",
            module.display()
        );
        eprintln!(
            "skipping glTF validation: no validator at {} (run .ci/run to install it)",
            module.display()
        );
        return;
    }
    let out = Command::new("node")
        .arg(root.join(".ci/validate-gltf.js"))
        .args(files)
        .env("GLTF_VALIDATOR_MODULE", &module)
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&out.stdout);
    eprintln!("{report}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "glTF validation failed:\n{report}");
    assert_eq!(
        report.matches(": 0 errors").count(),
        files.len(),
        "{report}"
    );
}

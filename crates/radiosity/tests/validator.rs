//! The Khronos glTF Validator, run over the glTF files the tests write. Shared by the library's
//! and the command's tests (the latter include this file by path).

use std::path::{Path, PathBuf};
use std::process::Command;

/// Run the Khronos glTF Validator (`.ci/validate-gltf.js`, npm package `gltf-validator`) over
/// `files`, asserting no errors. `.ci/run` installs it into `target/gltf-validator`; a test
/// that needs it fails, naming the way to install it, when it is missing (no silent skip).
pub fn validate_gltf(files: &[PathBuf]) {
    validate_gltf_report(files);
}

/// [`validate_gltf`], returning the validator's report (one summary line a file, `FILE: N
/// errors, N warnings, …`, then each error and warning) for tests that also refuse warnings.
#[allow(dead_code)]
pub fn validate_gltf_report(files: &[PathBuf]) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let module = std::env::var_os("GLTF_VALIDATOR_MODULE")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target/gltf-validator/node_modules/gltf-validator"));
    let node = Command::new("node").arg("--version").output();
    assert!(
        module.exists() && node.is_ok(),
        "the Khronos glTF validator is missing ({} or node): `bash .ci/run` installs it \
         (npm install --prefix target/gltf-validator gltf-validator@2.0.0-dev.3.10)",
        module.display()
    );
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
    report.into_owned()
}

//! The `radiosity` command as a user runs it: outputs, and bad input that must fail with one
//! line naming the file and the problem, a non-zero exit, and no output file.
//!
//! One file a command; `errors` holds the bad input that every command must refuse alike;
//! the workbench's own tests (crates/radiosity-bench, crates/radiosity-fuzz) share `common`. Tests that need more than the repository (the scenes
//! in `../shared`, Node.js and the glTF validator) are `#[ignore]`d with the reason:
//! `cargo test -- --include-ignored` runs them.

/// The binary under test.
const BIN: &str = env!("CARGO_BIN_EXE_radiosity");

mod common;
#[path = "../../../radiosity/tests/validator.rs"]
mod validator;

mod adaptive;
mod annual;
mod coincident;
mod daylight;
mod daylight_map;
mod errors;
mod experiment;
mod form_factors;
mod form_factors_truncate;
mod gltf_lights;
mod lighting;
mod lighting_pictures;
mod mpi;
mod render;
mod render_lighting;
mod solve;
mod solve_lightmap;
mod solve_system;
mod thermal;
mod validate;
mod view;

//! The `radiosity` command as a user runs it: outputs, and bad input that must fail with one
//! line naming the file and the problem, a non-zero exit, and no output file.
//!
//! One file a command; `errors` holds the bad input that every command must refuse alike;
//! `bench` and `fuzz` use only `common`. Tests that need more than the repository (the scenes
//! in `../shared`, Node.js and the glTF validator) are `#[ignore]`d with the reason:
//! `cargo test -- --include-ignored` runs them.

mod common;
#[path = "../../../radiosity/tests/validator.rs"]
mod validator;

mod bench;
mod errors;
mod experiment;
mod form_factors;
mod fuzz;
mod mpi;
mod render;
mod solve;
mod solve_system;
mod thermal;
mod view;

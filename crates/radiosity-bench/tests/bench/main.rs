//! `radiosity-bench` as a user runs it: each mode's table, and the options it refuses.

/// The binary under test.
const BIN: &str = env!("CARGO_BIN_EXE_radiosity-bench");

#[path = "../../../radiosity-cli/tests/cli/common.rs"]
mod common;
mod modes;
mod view3d;

//! Integration tests of the library: physics against closed forms and invariants.

mod physics;
mod solvers;

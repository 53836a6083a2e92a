//! Integration tests of the library: physics against closed forms and invariants.

mod formfactors;
mod physics;
mod renderpark;
mod solvers;

//! Integration tests of the library: physics against closed forms and invariants.

mod formfactors;
mod renderpark;
mod physics;
mod solvers;

//! Integration tests of the library: physics against closed forms and invariants.

mod adaptive;
mod coincident;
mod distributed;
mod formfactors;
mod interchange;
mod lightmap;
mod physics;
mod renderpark;
mod solvers;
mod validator;

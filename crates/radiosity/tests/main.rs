//! Integration tests of the library: physics against closed forms and invariants.

mod adaptive;
mod coincident;
mod distributed;
mod formfactors;
mod interchange;
mod physics;
mod renderpark;
mod solvers;
mod validator;

//! Diffuse global illumination by the radiosity method.
#![doc = include_str!("../README.md")]

pub mod accel;
pub mod color;
pub mod geom;
pub mod mesh;
pub mod sampling;
pub mod scene;
pub mod formfactor;
pub mod solve;

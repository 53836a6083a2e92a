//! LIGHTMAPS: baked light in textures on a second UV set, what game engines' static lighting
//! reads (issue 59).
//!
//! - [`uv`]: the second UV set (`TEXCOORD_1`): planar charts of the scene's faces, projected
//!   without stretch and packed into one or more atlases at a uniform texel density, with
//!   padding;
//! - [`given`]: the input's own UV set (an existing `TEXCOORD_1`), kept instead (one atlas);
//! - [`lightmap`]: each texel's radiosity by the final gather at the texel's surface point
//!   (exact direct light with shadow rays, the indirect from the radiosity solution), covered
//!   texels dark, the indirect optionally denoised, padding dilated.
//!
//! The glTF that carries it (`MOZ_lightmap`, the atlas as PNG) is written by
//! [`crate::export::bake::write_lightmap_gltf`]; the linear atlas by
//! [`crate::export::bake::write_lightmap_exr`].
//!
//! ```
//! use radiosity::bake::lightmap::{bake, LightmapParams};
//! use radiosity::bake::uv::Density;
//! use radiosity::prelude::*;
//!
//! let scene = builtin::cornell();
//! let s = solve(&scene, &Settings::from(Uniform { mesh: MeshParams::Patches(300), ..Default::default() }), &Silent).unwrap();
//! let vertex = radiosity::render::vertex_radiosity(&s.mesh, &s.radiosity);
//! let params = LightmapParams { density: Density::AtlasSize(64), direct: 2, indirect: 8, ..Default::default() };
//! let map = bake(&scene, s.surfaces(), &vertex, &params).unwrap();
//! assert_eq!((map.width(), map.height()), (64, 64));
//! // Every texel is finite and non-negative.
//! assert!(map.texels.iter().flatten().all(|b| b.is_finite() && *b >= 0.0));
//! ```

pub mod given;
pub mod lightmap;
pub mod uv;

//! `solve --bake lightmap`: flags → [`radiosity::bake::lightmap`] (on a glTF scene's own
//! `TEXCOORD_1` when every primitive has one, [`radiosity::bake::given`]) → the lightmapped glTF
//! ([`radiosity::export::bake::write_lightmap_gltf`]) and, with `--lightmap-out`, the linear
//! atlas ([`radiosity::export::bake::write_lightmap_exr`]).

use crate::args::{BakeArg, SolveCmdArgs};
use anyhow::{bail, Context, Result};
use radiosity::bake::lightmap::{bake_on, Denoise, Lightmap, LightmapParams};
use radiosity::bake::uv::{Density, MAX_ATLAS};
use radiosity::export::bake::{write_lightmap_exr, write_lightmap_gltf, LightmapBake};
use radiosity::io::FileFormat;
use radiosity::pipeline::Solution;
use radiosity::scene::Scene;
use std::path::PathBuf;

/// The lightmap's parameters from the flags, checked before any work; `None` for a vertex bake
/// (and then no lightmap flag may be given).
pub(crate) fn params(a: &SolveCmdArgs) -> Result<Option<LightmapParams>> {
    if a.bake == BakeArg::Vertex {
        for (flag, given) in [
            ("--lightmap-size", a.lightmap_size.is_some()),
            ("--texel-size", a.texel_size.is_some()),
            ("--lightmap-out", a.lightmap_out.is_some()),
            ("--lightmap-denoise", a.lightmap_denoise),
            (
                "--lightmap-denoise-radius",
                a.lightmap_denoise_radius.is_some(),
            ),
        ] {
            if given {
                bail!("{flag}: only a lightmap bake has it (add --bake lightmap)");
            }
        }
        return Ok(None);
    }
    if !matches!(
        FileFormat::from_path(&a.out),
        Some(FileFormat::Glb | FileFormat::Gltf)
    ) {
        bail!(
            "{}: --bake lightmap writes glTF (use .glb or .gltf)",
            a.out.display()
        );
    }
    if let Some(n) = a.lightmap_size {
        if n == 0 || n > MAX_ATLAS {
            bail!("--lightmap-size {n}: must be 1 to {MAX_ATLAS} texels");
        }
    }
    if let Some(l) = a.texel_size {
        if !(l.is_finite() && l > 0.0) {
            bail!("--texel-size {l}: must be a positive length in scene units");
        }
    }
    for (flag, n) in [
        ("--lightmap-direct", a.lightmap_direct),
        ("--lightmap-indirect", a.lightmap_indirect),
        ("--lightmap-spacing", a.lightmap_spacing),
    ] {
        if n == 0 {
            bail!("{flag} 0: at least 1 is needed");
        }
    }
    if let Some(r) = a.lightmap_denoise_radius {
        if !a.lightmap_denoise {
            bail!(
                "--lightmap-denoise-radius: only a denoised bake has it (add --lightmap-denoise)"
            );
        }
        if !(r.is_finite() && r >= 1.0) {
            bail!("--lightmap-denoise-radius {r}: must be at least 1 texel");
        }
    }
    if let Some(p) = &a.lightmap_out {
        if FileFormat::from_path(p) != Some(FileFormat::Exr) {
            bail!("{}: --lightmap-out writes OpenEXR (use .exr)", p.display());
        }
        crate::settings::check_output(p)?;
    }
    let density = match (a.texel_size, a.lightmap_size) {
        (Some(l), Some(n)) => Density::Both(l, n),
        (Some(l), None) => Density::TexelSize(l),
        (None, Some(n)) => Density::AtlasSize(n),
        (None, None) => LightmapParams::default().density,
    };
    Ok(Some(LightmapParams {
        density,
        direct: a.lightmap_direct,
        indirect: a.lightmap_indirect,
        spacing: a.lightmap_spacing,
        seed: a.solve.seed,
        memory_limit: radiosity::pipeline::MemoryLimit::Available.bytes(),
        denoise: a.lightmap_denoise.then(|| {
            a.lightmap_denoise_radius
                .map_or_else(Denoise::default, Denoise::with_radius)
        }),
        ..Default::default()
    }))
}

/// The UV set a glTF scene already has for its lightmap: `TEXCOORD_1` at the corners of each
/// polygon, when every primitive has one (some but not all: a warning, and a generated set).
fn kept_uvs(a: &SolveCmdArgs, scene: &Scene) -> Result<Option<Vec<[[f32; 2]; 3]>>> {
    let path = std::path::Path::new(&a.solve.scene);
    if !matches!(
        FileFormat::from_path(path),
        Some(FileFormat::Glb | FileFormat::Gltf)
    ) || !path.exists()
    {
        return Ok(None);
    }
    let (read, set) = radiosity::scene::gltf::load_lightmap(path, a.solve.one_sided, false)?;
    if read.polygons.len() != scene.polygons.len() {
        bail!(
            "{}: the scene read again has {} polygons, not {}",
            path.display(),
            read.polygons.len(),
            scene.polygons.len()
        );
    }
    let with = set.uv.iter().filter(|u| u.is_some()).count();
    if with == 0 {
        return Ok(None);
    }
    let mut textures: Vec<u32> = set.texture.iter().flatten().copied().collect();
    textures.sort_unstable();
    textures.dedup();
    if textures.len() > 1 {
        eprintln!(
            "radiosity: warning: {}: its TEXCOORD_1 spans {} lightmap atlases (MOZ_lightmap textures), whose UV squares overlap; the lightmap gets a new UV set",
            path.display(),
            textures.len()
        );
        return Ok(None);
    }
    if with < set.uv.len() {
        eprintln!(
            "radiosity: warning: {}: only {with} of {} triangles have TEXCOORD_1; the lightmap gets a new UV set",
            path.display(),
            set.uv.len()
        );
        return Ok(None);
    }
    Ok(Some(set.uv.into_iter().flatten().collect()))
}

/// Bake the lightmap of a solved scene and write it; the lightmap, whether it kept the
/// scene's own `TEXCOORD_1`, and the EXR files written, for the summary.
pub(crate) fn write(
    a: &SolveCmdArgs,
    params: &LightmapParams,
    scene: &Scene,
    solution: &Solution,
) -> Result<(Lightmap, bool, Vec<PathBuf>)> {
    let vertex = radiosity::render::vertex_radiosity(&solution.mesh, &solution.radiosity);
    let kept = kept_uvs(a, scene)?;
    let map = bake_on(scene, solution.surfaces(), &vertex, params, kept.as_deref())
        .with_context(|| a.solve.scene.clone())?;
    let lightmap_bake = LightmapBake {
        scene,
        lightmap: &map,
        scale: solution.auto_exposure() * 2f32.powf(a.exposure),
        camera: Some(solution.default_camera(scene)),
    };
    let binary = FileFormat::from_path(&a.out) == Some(FileFormat::Glb);
    write_lightmap_gltf(&a.out, &lightmap_bake, binary)?;
    let mut exrs = Vec::new();
    if let Some(p) = &a.lightmap_out {
        exrs = write_lightmap_exr(p, &map)?;
    }
    Ok((map, kept.is_some(), exrs))
}

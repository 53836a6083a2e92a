//! Luminaires from a glTF scene's own lights ([`crate::scene::gltf_lights`]), so that a model
//! exported from Blender, Unreal or Omniverse with its lights is lit as it was drawn:
//!
//! - a `KHR_lights_punctual` **point** light is an isotropic luminaire of its `intensity`
//!   (candela) in every direction;
//! - a **spot** light sends its `intensity` within `innerConeAngle` and none past
//!   `outerConeAngle`, and between them the fall-off the extension's specification gives its
//!   implementations: I(θ) = I₀ · s², s = clamp((cos θ − cos θ_outer) / (cos θ_inner −
//!   cos θ_outer), 0, 1), θ the angle from the spot's axis. It is tabulated in γ (every
//!   1/[`SPOT_STEPS`] of the fall-off band; linear interpolation between them is within
//!   3 × 10⁻⁵ of I₀ for any cone, the second derivative of s² in γ over 8 · steps²);
//! - an `EXT_lights_ies` **profile** is its IES file read by [`crate::photometry`], placed as
//!   the extension maps it: (0, 0) (γ = 0 for type C) along the node's −Z, C = 0 along +X;
//!   its `multiplier` scales it.
//!
//! A light's `color` tints it: the luminous intensity is scaled by the photometric Y of the
//! linear colour (ITU-R BT.709 weights, as [`crate::pipeline::luminance`]), which is 1 for
//! white, so a renderer that multiplies colour and intensity and this calculation agree.
//! Every glTF light joins the [`DEFAULT_GROUP`] light scene; scene units are metres.

use super::{Luminaire, DEFAULT_GROUP};
use crate::photometry::{decode, parse_ies, Photometry};
use crate::scene::gltf_lights::{load_lights, LightKind, SceneLight};
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;

/// Tabulated angles across a spot's fall-off band (between its inner and outer cones).
pub const SPOT_STEPS: usize = 180;

/// The luminaires of the glTF file at `path`, and one line per light left out or property
/// ignored. Errors: the scene's (the file and JSON path), a profile's (the profile named).
pub fn gltf_luminaires(path: &Path) -> Result<(Vec<Luminaire>, Vec<String>), crate::Error> {
    let lights = load_lights(path)?;
    let mut out = Vec::with_capacity(lights.lights.len());
    // Profiles shared by several nodes are parsed once.
    let mut parsed: Vec<(String, Arc<Photometry>)> = Vec::new();
    let mut warnings = lights.warnings;
    for light in &lights.lights {
        let (photometry, multiplier) = match &light.kind {
            LightKind::Ies { profile, source } => {
                let photometry = match parsed.iter().find(|(s, _)| s == source) {
                    Some((_, p)) => p.clone(),
                    None => {
                        let p = parse_ies(&decode(profile), source).map_err(|e| {
                            crate::lighting::LightingError::Parameter(format!(
                                "{}: light '{}': {e}",
                                path.display(),
                                light.name
                            ))
                        })?;
                        for w in &p.warnings {
                            warnings.push(format!("{source}: {w}"));
                        }
                        let p = Arc::new(p);
                        parsed.push((source.clone(), p.clone()));
                        p
                    }
                };
                (photometry, light.intensity)
            }
            kind => (Arc::new(punctual(kind, light)?), 1.0),
        };
        let multiplier = multiplier * crate::pipeline::luminance(light.colour);
        let luminaire = Luminaire::new(
            light.name.clone(),
            photometry,
            light.position,
            light.direction,
            Some(light.x_axis),
            multiplier,
            DEFAULT_GROUP,
        )
        // A profile's lamp tilt table (TILT=INCLUDE) applies as installed: glTF is y-up.
        .and_then(|l| l.with_lamp_tilt([0.0, 1.0, 0.0]))
        .map_err(|e| {
            crate::lighting::LightingError::Parameter(format!(
                "{}: light '{}': {e}",
                path.display(),
                light.name
            ))
        })?;
        out.push(luminaire);
    }
    Ok((out, warnings))
}

/// The intensity of a spot light `angle` radians off its axis, relative to its axis's.
pub fn spot_falloff(angle: f64, inner: f64, outer: f64) -> f64 {
    let s = ((angle.cos() - outer.cos()) / (inner.cos() - outer.cos())).clamp(0.0, 1.0);
    s * s
}

/// The distribution of a point or spot light, as a rotationally symmetric type C table
/// (absolute photometry, written as IES text and read by the IES parser, so that it is held
/// and interpolated as every measured file is).
fn punctual(kind: &LightKind, light: &SceneLight) -> Result<Photometry, crate::Error> {
    let i0 = light.intensity;
    let (gamma, candela): (Vec<f64>, Vec<f64>) = match *kind {
        LightKind::Spot { inner, outer } => {
            let mut g = vec![0.0];
            let mut c = vec![i0];
            for k in 0..=SPOT_STEPS {
                let a = inner + (outer - inner) * k as f64 / SPOT_STEPS as f64;
                g.push(a.to_degrees());
                c.push(i0 * spot_falloff(a, inner, outer));
            }
            if inner == 0.0 {
                g.remove(0);
                c.remove(0);
            }
            // LM-63's usual range is 0..90: past the outer cone, darkness to 90°.
            if outer.to_degrees() < 90.0 - 1e-9 {
                g.push(90.0);
                c.push(0.0);
            }
            (g, c)
        }
        _ => (vec![0.0, 180.0], vec![i0, i0]),
    };
    let mut text = String::from("IESNA:LM-63-2002\n[TEST] glTF punctual light\nTILT=NONE\n");
    let _ = writeln!(text, "1 -1 1 {} 1 1 2 0 0 0", gamma.len());
    text.push_str("1 1 0\n");
    let join = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let _ = writeln!(text, "{}", join(&gamma));
    text.push_str("0\n");
    let _ = writeln!(text, "{}", join(&candela));
    let name = format!("{}.ies", light.name);
    parse_ies(&text, &name).map_err(|e| {
        crate::lighting::LightingError::Parameter(format!("light '{}': {e}", light.name)).into()
    })
}

#[cfg(test)]
#[path = "gltf_tests.rs"]
mod tests;

//! Lighting design: illuminance at sensor points from luminaires with measured photometry, the
//! diffuse interreflection included; the energy books of each light group; and what a picture
//! of the lit scene in luminance needs.
//!
//! Per light group (light scene) the pipeline
//! 1. computes each patch's mean direct illuminance from the group's luminaires: the flux of
//!    their distributions over the patch's solid angle with visibility, by an adaptive rule
//!    exact for an unshadowed isotropic source ([`crate::lighting::patch_illuminance`]): the
//!    luminaires' first shot into the patches;
//! 2. solves the interreflection with the engine's solver, the first reflection ρ E_direct as
//!    each patch's initial exitance (B = ρ E_direct + E_scene + ρ F B, in lm/m²);
//! 3. at each sensor point adds, to its exact direct illuminance, the light arriving from the
//!    surfaces, gathered from the solution ([`crate::render::gather::Gather::irradiance_at`]:
//!    cosine rays and points on the reflecting patches, by multiple importance sampling; the
//!    scene's own emitting surfaces by shadow rays).
//!
//! Radiosity is linear in its sources, so the group columns add up to the total and a light
//! scene can be re-dimmed by a weighted sum of columns without solving again. The scene's own
//! emitting surfaces (luminous exitance in lm/m²) are a group of their own, `scene`, when there
//! are luminaires beside them. Colour: reflectances are RGB (linear sRGB) and the luminaires
//! white; illuminance is the photometric Y = 0.2126 R + 0.7152 G + 0.0722 B of the irradiance
//! (ITU-R BT.709 luminance coefficients), so a grey reflectance ρ acts as ρ.
//!
//! # The light arriving at a patch
//!
//! The surfaces table reports each patch's arriving illuminance: its direct illuminance plus
//! what arrived from the surfaces, H_p = Σ_k F_pk B_k (the radiosity equation's own
//! irradiance, B_p = E_p + ρ_p H_p). Where ρ_p > 0 in every channel it is read back from the
//! solution, (B_p − E_p)/ρ_p; a patch black in some channel keeps none of it in B, so there
//! H_p is gathered from the solution along the patch's own row of F (Monte Carlo:
//! [`BLACK_ROW_RAYS`] cosine rays from uniform points of the patch).
//!
//! # The books
//!
//! [`EnergyBooks`], per group and in total: the flux emitted, reaching surfaces directly,
//! absorbed, escaped and left unshot (see [`books`](mod@books) for the definitions and the
//! balance check).
//!
//! # Pictures
//!
//! [`lighting_solution`] also hands back a [`LightingSolution`] (the mesh, the per-patch
//! exitance, the luminaires), whose [`LightingSolution::render`] computes the luminance a
//! camera sees: L = M/π + ρ (E_direct(x) + E_inter(x))/π at each camera sample's hit x, the
//! luminaires' E_direct exactly there (the inverse-square cosine law with a shadow ray, as at
//! the sensor points) and the interreflected E_inter by the final gather over the solution.
//! Luminaires are light sources, not geometry: a camera does not see them.

mod books;
#[cfg(test)]
mod books_tests;
#[cfg(test)]
mod render_tests;

pub use books::{EnergyBooks, ESCAPE_BANDS, ESCAPE_SECTORS};

use super::{patch_system, MemoryLimit};
use crate::accel::Bvh;
use crate::color::Rgb;
use crate::formfactor::{Effort, Estimator, OnDemandRows, Scratch};
use crate::geom::Vec3;
use crate::lighting::{direct_illuminance, patch_illuminance, Luminaire, SensorPoint};
use crate::mesh::{Mesh, MeshParams};
use crate::observe::{Event, Observer, Stage};
use crate::render::gather::{Gather, GatherParams};
use crate::render::light::Surfaces;
use crate::render::{Image, RenderParams};
use crate::sampling::stream;
use crate::scene::{Camera, Scene};
use crate::solve::{Info, Solver, SolverParams};
use crate::system::{Operator, System};
use crate::Error;
use rayon::prelude::*;

/// The group of the scene's own emitting surfaces when luminaires light it too.
pub const SCENE_GROUP: &str = "scene";

/// Monte Carlo rays of the row of F along which a black patch's arriving light is gathered
/// (its relative noise per patch about 1/√(this), far less over a surface's patches).
pub const BLACK_ROW_RAYS: u32 = 1024;

/// Below this a reflectance channel counts as black (nothing of what arrives is in B).
const BLACK: f64 = 1e-9;

/// What decides a lighting calculation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightingSettings {
    /// How surfaces are cut into patches for the interreflection.
    pub mesh: MeshParams,
    /// Form factors of the interreflection (Monte Carlo rows on demand by default).
    pub form_factors: crate::formfactor::Params,
    /// The interreflection's solver.
    pub solver: Solver,
    /// Its parameters (the tolerance is the unshot fraction of the first-shot flux).
    pub params: SolverParams,
    /// Samples of the gather at each sensor point.
    pub gather: GatherParams,
    /// Metres per scene unit: distances in metres make illuminance lux.
    pub unit_metres: f64,
    /// Refuse jobs whose estimated memory exceeds this.
    pub memory_limit: MemoryLimit,
}

impl Default for LightingSettings {
    fn default() -> Self {
        Self {
            mesh: MeshParams::Patches(10_000),
            form_factors: crate::formfactor::Params::shooting(),
            solver: Solver::Progressive,
            params: SolverParams {
                tolerance: 1e-3,
                ..SolverParams::default()
            },
            gather: GatherParams {
                direct: 16,
                indirect: 1024,
                cache_samples: 0,
                ..GatherParams::default()
            },
            unit_metres: 1.0,
            memory_limit: MemoryLimit::Available,
        }
    }
}

/// Illuminance at the sensor points.
#[derive(Clone, Debug)]
pub struct LightingResult {
    /// The light groups, the luminaires' in their first-appearance order, then [`SCENE_GROUP`]
    /// where the scene's own surfaces emit beside luminaires.
    pub groups: Vec<String>,
    /// Lux at each point, every group together.
    pub total: Vec<f64>,
    /// Lux, row-major points × groups.
    pub by_group: Vec<f64>,
    /// Of `total`, what came straight from the luminaires (exact).
    pub direct: Vec<f64>,
    /// The patches of the interreflection.
    pub patches: usize,
    /// Each group's luminaires' flux, lumens (integrated from their distributions, after
    /// multipliers), in `groups` order (0 for [`SCENE_GROUP`]).
    pub flux: Vec<f64>,
    /// One row per material name, in the scene's material order, every group together.
    pub surfaces: Vec<SurfaceLight>,
    /// Where each group's flux goes, lumens, in `groups` order ([`EnergyBooks::total`] sums
    /// them).
    pub books: Vec<EnergyBooks>,
    /// Whether every group's interreflection reached the solver's tolerance.
    pub converged: bool,
}

/// The light on the surfaces of one material name.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceLight {
    /// The material's name.
    pub name: String,
    /// Area, m².
    pub area: f64,
    /// Photometric (luminance-weighted) reflectance.
    pub reflectance: f64,
    /// Area-weighted mean illuminance arriving, lux (direct and interreflected; black
    /// surfaces included, see the module documentation).
    pub illuminance: f64,
    /// Area-weighted mean luminous exitance leaving, lm/m² (emission included).
    pub exitance: f64,
    /// Area-weighted mean luminance, cd/m² (exitance / π: the surfaces are diffuse).
    pub luminance: f64,
}

/// What rendering the lit scene needs: the interreflection's patches and their exitance,
/// every group together, and the luminaires ([`lighting_solution`]).
#[derive(Debug)]
pub struct LightingSolution {
    /// The patches.
    pub mesh: Mesh,
    /// The hierarchy over them.
    pub bvh: Bvh,
    /// Each patch's reflectance.
    pub reflectance: Vec<Rgb>,
    /// Each patch's own emission (the scene's emitting surfaces), lm/m².
    pub emission: Vec<Rgb>,
    /// Each patch's luminous exitance, lm/m²: the luminaires' light reflected once and
    /// interreflected, and the patch's own emission, every group together, as the solver
    /// leaves it.
    pub exitance: Vec<Rgb>,
    /// The luminaires, whose direct light a picture computes at each hit.
    pub luminaires: Vec<Luminaire>,
    /// Metres per scene unit.
    pub unit_metres: f64,
}

/// Illuminance at `points` in `scene` from `luminaires` (and the scene's own emitting
/// surfaces), interreflection included, with the surfaces table and the energy books. Errors:
/// bad settings, a scene without light, meshing.
pub fn lighting(
    scene: &Scene,
    luminaires: &[Luminaire],
    points: &[SensorPoint],
    settings: &LightingSettings,
    observer: &dyn Observer,
) -> Result<LightingResult, Error> {
    Ok(compute(scene, luminaires, points, settings, observer)?.result)
}

/// [`lighting`], and the solution a picture of the lit scene needs ([`LightingSolution`]):
/// the same computation, whose mesh and exitance [`lighting`] drops.
pub fn lighting_solution(
    scene: &Scene,
    luminaires: &[Luminaire],
    points: &[SensorPoint],
    settings: &LightingSettings,
    observer: &dyn Observer,
) -> Result<(LightingResult, LightingSolution), Error> {
    let c = compute(scene, luminaires, points, settings, observer)?;
    let solution = LightingSolution {
        mesh: c.mesh,
        bvh: c.bvh,
        reflectance: c.system.reflectance,
        emission: c.system.emission,
        exitance: c.exitance,
        luminaires: luminaires.to_vec(),
        unit_metres: settings.unit_metres,
    };
    Ok((c.result, solution))
}

impl LightingSolution {
    /// The solution's surfaces for the ray-traced integrators (the scene's own emission as the
    /// emitters).
    pub fn surfaces(&self) -> Surfaces<'_> {
        Surfaces {
            mesh: &self.mesh,
            bvh: &self.bvh,
            reflectance: &self.reflectance,
            emission: &self.emission,
        }
    }

    /// The view for `scene`: its own camera, else one inside it when its vertical is known and
    /// it is an interior, else one framing it (as [`super::Solution::default_camera`]).
    pub fn default_camera(&self, scene: &Scene) -> Camera {
        match (scene.camera, scene.up) {
            (Some(c), _) => c,
            (None, Some(up)) => crate::render::camera::default_camera(&self.bvh, up),
            (None, None) => scene.camera_or_default(),
        }
    }

    /// The lit scene as a camera sees it, RGB radiance whose Y is luminance in cd/m²: at each
    /// camera sample's hit x on a patch of reflectance ρ and emission M,
    /// L = M/π + ρ (E_direct(x) + E_inter(x))/π, with E_direct the luminaires' direct
    /// illuminance at x computed exactly ([`direct_illuminance`], a shadow ray a luminaire; in
    /// one batch per image row) and E_inter the light arriving from the surfaces, gathered
    /// from the solution's exitance by [`Gather`] (its irradiance cache when `gather` keeps
    /// one; the scene's emitting surfaces sampled by shadow rays). A gather ray's near hit
    /// reads the solution there ([`GatherParams::near`] is taken as 0 when there are
    /// luminaires: a level deeper would light the hit by the emitters alone). Luminaires are
    /// not geometry: they light the scene but are not seen. Errors: a scene unit that is not
    /// a finite length > 0.
    pub fn render(
        &self,
        camera: &Camera,
        params: &RenderParams,
        gather: GatherParams,
        observer: &dyn Observer,
    ) -> Result<Image, Error> {
        // The unit is checked once here, so the rows below cannot fail.
        direct_illuminance(&[], &self.luminaires, None, self.unit_metres)?;
        let vertex = crate::render::vertex_radiosity(&self.mesh, &self.exitance);
        // Near hits read the solution rather than going one level deeper, whose direct light
        // would come from the emitters alone, not the luminaires (see [`GatherParams::near`]).
        let gather = if self.luminaires.is_empty() {
            gather
        } else {
            GatherParams {
                near: 0.0,
                ..gather
            }
        };
        let g = Gather::new(self.surfaces(), &vertex, gather);
        Ok(
            g.render_with_irradiance(camera, params, observer, |hits, out| {
                let sensors: Vec<SensorPoint> = hits
                    .iter()
                    .map(|h| SensorPoint {
                        position: h.position.as_dvec3().to_array(),
                        normal: h.normal.as_dvec3().to_array(),
                    })
                    .collect();
                if let Ok(d) = direct_illuminance(
                    &sensors,
                    &self.luminaires,
                    Some(&self.bvh),
                    self.unit_metres,
                ) {
                    *out = d.total;
                }
            }),
        )
    }
}

/// Everything [`lighting`] computes, before its caller picks what it keeps.
struct Computed {
    result: LightingResult,
    mesh: Mesh,
    bvh: Bvh,
    system: System,
    exitance: Vec<Rgb>,
}

/// The computation of [`lighting`] and [`lighting_solution`].
fn compute(
    scene: &Scene,
    luminaires: &[Luminaire],
    points: &[SensorPoint],
    settings: &LightingSettings,
    observer: &dyn Observer,
) -> Result<Computed, Error> {
    scene.validate_geometry()?;
    settings.mesh.validate()?;
    settings.form_factors.validate()?;
    settings.params.validate()?;
    let scene_emits = scene
        .polygons
        .iter()
        .any(|p| scene.materials[p.material].emission.max_channel() > 0.0);
    if luminaires.is_empty() && !scene_emits {
        return Err(crate::lighting::LightingError::Parameter(
            "no light: give luminaires or a scene with emitting surfaces".into(),
        )
        .into());
    }
    let limit = settings.memory_limit.bytes();
    let memory = super::MemoryCheck {
        limit,
        stored_rows: false,
        rays: settings.form_factors.rays,
    };
    memory.before_meshing(scene, settings.mesh)?;
    observer.event(Event::Stage(Stage::Mesh));
    let mesh = Mesh::build(scene, settings.mesh)?;
    memory.check(mesh.len() as u64)?;
    observer.event(Event::Stage(Stage::Bvh));
    let bvh = Bvh::build(&mesh);
    let base = patch_system(scene, &mesh);
    let unit2 = settings.unit_metres * settings.unit_metres;

    // The luminaires' direct light: at the patches (their first shot) and at the points.
    let at_patches = patch_illuminance(&mesh, luminaires, Some(&bvh), settings.unit_metres)?;
    let at_points = direct_illuminance(points, luminaires, Some(&bvh), settings.unit_metres)?;
    let mut groups = at_points.groups.clone();
    let lum_groups = groups.len();
    let mut flux = vec![0.0; lum_groups];
    let mut books = vec![EnergyBooks::default(); lum_groups];
    // Each luminaire's flux, and what of it reaches no front face, counted by rays.
    let reach = books::reach(luminaires, &bvh);
    for (l, r) in luminaires.iter().zip(&reach) {
        let g = groups.iter().position(|g| *g == l.group).unwrap_or(0);
        let phi = l.photometry.flux() * l.multiplier;
        flux[g] += phi;
        books[g].emitted += phi;
        books[g].escaped_counted += phi * (1.0 - r);
    }
    // The first shot: what reaches each patch, and what of it the patch absorbs (the
    // luminaires are white: Y((1 − ρ) E) = (1 − Y(ρ)) E).
    for (p, patch) in mesh.patches.iter().enumerate() {
        let a = patch.area as f64 * unit2;
        let keep = 1.0 - luminance(base.reflectance[p]);
        for (g, b) in books.iter_mut().enumerate() {
            let phi = a * at_patches.by_group[p * lum_groups + g];
            b.direct_to_surfaces += phi;
            b.absorbed += phi * keep;
        }
    }
    if scene_emits {
        if luminaires.is_empty() {
            groups.push(crate::lighting::DEFAULT_GROUP.to_string());
        } else {
            groups.push(SCENE_GROUP.to_string());
        }
        flux.push(0.0);
        books.push(EnergyBooks::default());
    }
    let ng = groups.len();
    let n = points.len();
    let mut by_group = vec![0.0; n * ng];
    let mut direct = vec![0.0; n];
    for (i, d) in direct.iter_mut().enumerate() {
        for g in 0..lum_groups {
            let e = at_points.by_group[i * lum_groups + g];
            by_group[i * ng + g] = e;
            *d += e;
        }
    }
    // Patches black in some channel: their arriving light is gathered along their own rows.
    let black: Vec<usize> = (0..mesh.len())
        .filter(|&p| base.reflectance[p].min_channel() <= BLACK)
        .collect();
    let black_rows = if black.is_empty() {
        None
    } else {
        Some(Estimator::new(&mesh, &bvh, settings.form_factors)?)
    };
    // Per patch, every group together: the illuminance arriving (lux) and the exitance
    // leaving (RGB, lm/m²).
    let mut patch_e = vec![0.0f64; mesh.len()];
    let mut patch_b = vec![Rgb::BLACK; mesh.len()];
    for (p, e) in patch_e.iter_mut().enumerate() {
        *e = at_patches.by_group[p * lum_groups..(p + 1) * lum_groups]
            .iter()
            .sum();
    }
    let mut converged = true;
    for g in 0..ng {
        // The group's initial exitance: the first reflection of its luminaires' light, or the
        // scene's own emission.
        let emission: Vec<Rgb> = if g < lum_groups {
            (0..mesh.len())
                .map(|p| base.reflectance[p] * at_patches.by_group[p * lum_groups + g])
                .collect()
        } else {
            base.emission.clone()
        };
        let system = System {
            area: base.area.clone(),
            reflectance: base.reflectance.clone(),
            emission,
        };
        if system.emission.iter().all(|e| e.max_channel() <= 0.0) {
            continue;
        }
        observer.event(Event::Stage(Stage::Solve));
        let mut rows = OnDemandRows::new(Estimator::new(&mesh, &bvh, settings.form_factors)?);
        let mut params = settings.params;
        params.memory_limit = params.memory_limit.min(limit / 2);
        let mut solver = crate::solve::start(settings.solver, &system, &mut rows, &params)?;
        let info = crate::solve::run(&mut *solver, &mut rows, &params, false, &mut |s, sv| {
            observer.event(Event::Solve(s, sv));
            !observer.cancelled()
        });
        converged &= info.converged;
        let mut b = Vec::new();
        solver.radiosity(&mut b);
        drop(solver);
        book_solve(&mut books[g], &info, unit2);
        if g >= lum_groups {
            // The scene's own emitters: their emission and first shot are the solver's.
            books[g].emitted = luminance(info.emitted) * unit2;
            books[g].direct_to_surfaces = first_shot(&system, &mut rows) * unit2;
        }
        // What arrived after the first shot: (B − initial exitance) / ρ where ρ > 0; gathered
        // along the patch's row of F where it is black in some channel.
        let gathered = match &black_rows {
            Some(est) => gather_rows(est, &black, &b, g as u64),
            None => Vec::new(),
        };
        for p in 0..mesh.len() {
            patch_b[p] += b[p];
            let (rho, m) = (system.reflectance[p], system.emission[p]);
            let arrived = Rgb::new(
                (b[p].r - m.r) / rho.r.max(BLACK),
                (b[p].g - m.g) / rho.g.max(BLACK),
                (b[p].b - m.b) / rho.b.max(BLACK),
            );
            let arrived = match black.binary_search(&p) {
                Ok(k) => gathered[k],
                Err(_) => arrived,
            };
            patch_e[p] += luminance(arrived).max(0.0);
        }
        // The light arriving at each point from the surfaces, gathered.
        if points.is_empty() {
            continue;
        }
        observer.event(Event::Stage(Stage::Render));
        let vertex = crate::render::vertex_radiosity(&mesh, &b);
        // The first reflection of a luminaire's light is the solution's, not an emitter's:
        // gathered by multiple importance sampling, whose estimate stays bounded for a sensor
        // close to a lit wall (emitter sampling alone would weigh a point on it by 1/d²).
        // The scene's own emitting surfaces stay emitters, sampled by shadow rays.
        // A gather ray's near hit is not followed one level deeper for a luminaire group: the
        // deeper level would sample the emitters for the hit's direct light, and the
        // luminaires' is not among them (it is in the solution that the hit reads instead).
        let (emitters, params) = if g < lum_groups {
            let params = GatherParams {
                near: 0.0,
                ..settings.gather
            };
            (vec![Rgb::BLACK; mesh.len()], params)
        } else {
            (system.emission.clone(), settings.gather)
        };
        let gather = Gather::new(
            Surfaces {
                mesh: &mesh,
                bvh: &bvh,
                reflectance: &system.reflectance,
                emission: &emitters,
            },
            &vertex,
            params,
        );
        let from_surfaces: Vec<f64> = points
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let mut rng = stream(settings.params.seed, 0x004c_5558, g as u64, i as u64);
                let x = Vec3::new(
                    p.position[0] as f32,
                    p.position[1] as f32,
                    p.position[2] as f32,
                );
                let nrm = Vec3::new(p.normal[0] as f32, p.normal[1] as f32, p.normal[2] as f32);
                luminance(gather.irradiance_at(x, nrm, &mut rng))
            })
            .collect();
        for (i, e) in from_surfaces.into_iter().enumerate() {
            by_group[i * ng + g] += e;
        }
    }
    for b in &mut books {
        b.escaped = b.emitted - b.absorbed - b.unshot;
    }
    let total = (0..n)
        .map(|i| by_group[i * ng..(i + 1) * ng].iter().sum())
        .collect();
    let surfaces = surface_rows(scene, &mesh, &patch_e, &patch_b, unit2);
    Ok(Computed {
        result: LightingResult {
            groups,
            total,
            by_group,
            direct,
            patches: mesh.len(),
            flux,
            surfaces,
            books,
            converged,
        },
        mesh,
        bvh,
        system: base,
        exitance: patch_b,
    })
}

/// The interreflection's part of a group's books: its solver's absorbed, escaped and unshot
/// power (lm/m² × square scene units, so × `unit2` for lumens).
fn book_solve(books: &mut EnergyBooks, info: &Info, unit2: f64) {
    books.absorbed += luminance(info.absorbed) * unit2;
    books.escaped_counted += luminance(info.escaped) * unit2;
    books.unshot += luminance(info.unshot) * unit2;
}

/// The first shot of emitting patches, Σ_i Y(M_i) A_i Σ_j F_ij (square scene units × lm/m²).
fn first_shot(system: &System, rows: &mut OnDemandRows<'_>) -> f64 {
    let total: f64 = system
        .emission
        .iter()
        .zip(&system.area)
        .map(|(m, a)| luminance(*m).max(0.0) * a)
        .sum();
    let mut shot = 0.0;
    for (i, m) in system.emission.iter().enumerate() {
        let power = luminance(*m).max(0.0) * system.area[i];
        if power <= 0.0 {
            continue;
        }
        let reach: f64 = rows
            .row(i, power / total)
            .iter()
            .map(|&(_, f)| f as f64)
            .sum();
        shot += power * reach;
    }
    shot
}

/// H_p = Σ_k F_pk B_k for each patch of `patches`, along its own row of F ([`BLACK_ROW_RAYS`]
/// Monte Carlo rays, streams of their own for each group `g`). Parallel, deterministic.
fn gather_rows(est: &Estimator<'_>, patches: &[usize], b: &[Rgb], g: u64) -> Vec<Rgb> {
    let effort = Effort {
        rays: BLACK_ROW_RAYS,
        // Streams apart from those the solver's rows draw (versions count up from 0).
        version: (1 << 40) + g,
    };
    patches
        .par_iter()
        .map_init(
            || (Scratch::default(), Vec::new()),
            |(scratch, row), &p| {
                est.row_with(p, effort, scratch, row);
                row.iter().map(|&(k, f)| b[k as usize] * f as f64).sum()
            },
        )
        .collect()
}

/// One row per material name: area-weighted means over its patches.
fn surface_rows(
    scene: &Scene,
    mesh: &Mesh,
    patch_e: &[f64],
    patch_b: &[Rgb],
    unit2: f64,
) -> Vec<SurfaceLight> {
    // The row of each material: materials that share a name share a row.
    let mut rows: Vec<SurfaceLight> = Vec::new();
    let mut row_of = Vec::with_capacity(scene.materials.len());
    let mut by_name: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for m in &scene.materials {
        let k = *by_name.entry(m.name.as_str()).or_insert_with(|| {
            rows.push(SurfaceLight {
                name: m.name.clone(),
                area: 0.0,
                reflectance: luminance(m.reflectance),
                illuminance: 0.0,
                exitance: 0.0,
                luminance: 0.0,
            });
            rows.len() - 1
        });
        row_of.push(k);
    }
    for (p, patch) in mesh.patches.iter().enumerate() {
        let a = patch.area as f64 * unit2;
        let row = &mut rows[row_of[patch.material as usize]];
        row.area += a;
        row.illuminance += a * patch_e[p];
        row.exitance += a * luminance(patch_b[p]);
    }
    for row in &mut rows {
        if row.area > 0.0 {
            row.illuminance /= row.area;
            row.exitance /= row.area;
        }
        row.luminance = row.exitance / std::f64::consts::PI;
    }
    rows.retain(|r| r.area > 0.0);
    rows
}

/// The photometric Y of an RGB quantity (ITU-R BT.709 luminance coefficients).
pub fn luminance(c: Rgb) -> f64 {
    0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photometry::parse_ies;
    use crate::scene::{Material, Scene};
    use std::sync::Arc;

    /// An isotropic source of `i0` candela (IES, one horizontal angle, 0–180°).
    pub(super) fn isotropic(i0: f64) -> Arc<crate::photometry::Photometry> {
        let gammas: Vec<String> = (0..=36).map(|k| (5 * k).to_string()).collect();
        let cd = vec![i0.to_string(); 37];
        let text = format!(
            "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 37 1 1 2 0 0 0\n1 1 0\n{}\n0\n{}\n",
            gammas.join(" "),
            cd.join(" ")
        );
        Arc::new(parse_ies(&text, "iso.ies").unwrap())
    }

    /// An isotropic luminaire of `i0` candela at `at`, aimed down, in `group`.
    pub(super) fn lamp(
        name: &str,
        i0: f64,
        at: [f64; 3],
        multiplier: f64,
        group: &str,
    ) -> Luminaire {
        Luminaire::new(
            name,
            isotropic(i0),
            at,
            [0.0, 0.0, -1.0],
            None,
            multiplier,
            group,
        )
        .unwrap()
    }

    /// A closed cube of side `s` metres, inward faces, one grey reflectance.
    pub(super) fn cube(s: f32, rho: f64) -> Scene {
        let v = |x: f32, y: f32, z: f32| Vec3::new(x * s, y * s, z * s);
        let faces = vec![
            vec![v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
            vec![v(0., 0., 1.), v(0., 1., 1.), v(1., 1., 1.), v(1., 0., 1.)],
            vec![v(0., 0., 0.), v(0., 0., 1.), v(1., 0., 1.), v(1., 0., 0.)],
            vec![v(0., 1., 0.), v(1., 1., 0.), v(1., 1., 1.), v(0., 1., 1.)],
            vec![v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
            vec![v(1., 0., 0.), v(1., 0., 1.), v(1., 1., 1.), v(1., 1., 0.)],
        ];
        Scene::of_polygons("cube", Material::diffuse("grey", Rgb::splat(rho)), faces)
    }

    /// Points on every face of the cube, a `k × k` grid each, facing inwards.
    pub(super) fn wall_points(s: f64, k: usize) -> Vec<SensorPoint> {
        let mut out = Vec::new();
        for a in 0..k {
            for b in 0..k {
                let (u, w) = (
                    (a as f64 + 0.5) / k as f64 * s,
                    (b as f64 + 0.5) / k as f64 * s,
                );
                for (p, n) in [
                    ([u, w, 0.0], [0.0, 0.0, 1.0]),
                    ([u, w, s], [0.0, 0.0, -1.0]),
                    ([u, 0.0, w], [0.0, 1.0, 0.0]),
                    ([u, s, w], [0.0, -1.0, 0.0]),
                    ([0.0, u, w], [1.0, 0.0, 0.0]),
                    ([s, u, w], [-1.0, 0.0, 0.0]),
                ] {
                    out.push(SensorPoint::new(p, n).unwrap());
                }
            }
        }
        out
    }

    /// An isotropic source at the centre of a closed cube of uniform reflectance ρ: by energy
    /// balance the reflected light's mean illuminance over the walls is Φ ρ / (A (1 − ρ)) (the
    /// integrating-sphere result holds for the wall average of any closed enclosure). The grid
    /// points sample the walls uniformly, so their mean indirect illuminance must match it
    /// within the gather's noise (256 pairs a point, 294 points: well under 1 %) and the mesh's
    /// error (the exitance is piecewise constant on ~2,400 patches): 2 %.
    #[test]
    fn a_cube_interreflects_as_an_integrating_sphere() {
        let (s, rho, i0) = (4.0, 0.5, 1000.0);
        let scene = cube(s as f32, rho);
        let lum = lamp("lamp", i0, [s / 2.0; 3], 1.0, "default");
        let points = wall_points(s, 7);
        let settings = LightingSettings {
            mesh: MeshParams::Patches(2400),
            ..Default::default()
        };
        let r = lighting(
            &scene,
            std::slice::from_ref(&lum),
            &points,
            &settings,
            &crate::observe::Silent,
        )
        .unwrap();
        let phi = 4.0 * std::f64::consts::PI * i0;
        assert!((r.flux[0] - phi).abs() < 1e-6 * phi, "{} {phi}", r.flux[0]);
        let area = 6.0 * s * s;
        let want = phi * rho / (area * (1.0 - rho));
        let mean: f64 = r
            .total
            .iter()
            .zip(&r.direct)
            .map(|(t, d)| t - d)
            .sum::<f64>()
            / points.len() as f64;
        assert!(
            (mean - want).abs() < 0.02 * want,
            "mean indirect {mean} lux, integrating sphere {want} lux"
        );
        // The surfaces' table: one material, all 96 m²; its exitance is ρ times what arrives
        // (no emission), and the mean illuminance is the mean direct (Φ / A) plus the
        // integrating sphere's reflected part.
        assert_eq!(r.surfaces.len(), 1);
        let w = &r.surfaces[0];
        assert!((w.area - area).abs() < 1e-3 * area, "{w:?}");
        assert!(
            (w.exitance - rho * w.illuminance).abs() < 1e-9 * w.exitance,
            "{w:?}"
        );
        let e_mean = phi / area + want;
        assert!(
            (w.illuminance - e_mean).abs() < 0.02 * e_mean,
            "{w:?}: {e_mean}"
        );
        assert!((w.luminance - w.exitance / std::f64::consts::PI).abs() < 1e-12);
        // The direct part is the inverse-square cosine law, exactly.
        let p = &points[0];
        let d: Vec<f64> = (0..3).map(|k| s / 2.0 - p.position[k]).collect();
        let r2: f64 = d.iter().map(|x| x * x).sum();
        let cos = (d[0] * p.normal[0] + d[1] * p.normal[1] + d[2] * p.normal[2]) / r2.sqrt();
        assert!((r.direct[0] - i0 * cos / r2).abs() < 1e-9 * r.direct[0]);
    }

    /// Black walls reflect nothing: the total is the direct light alone; two groups add up.
    #[test]
    fn black_walls_leave_the_direct_light_and_groups_add_up() {
        let s = 3.0;
        let scene = cube(s as f32, 0.0);
        let a = lamp("a", 500.0, [1.0, 1.5, 2.5], 1.0, "one");
        let b = lamp("b", 300.0, [2.0, 1.5, 2.5], 2.0, "two");
        let points = wall_points(s, 3);
        let settings = LightingSettings {
            mesh: MeshParams::Patches(300),
            ..Default::default()
        };
        let r = lighting(&scene, &[a, b], &points, &settings, &crate::observe::Silent).unwrap();
        assert_eq!(r.groups, vec!["one".to_string(), "two".to_string()]);
        for i in 0..points.len() {
            assert!((r.total[i] - r.direct[i]).abs() < 1e-12 * r.total[i].max(1.0));
            let sum: f64 = r.by_group[2 * i..2 * i + 2].iter().sum();
            assert_eq!(sum, r.total[i]);
        }
    }

    /// A sensor 10 cm from a wall that a luminaire 30 cm away lights brightly: the light
    /// arriving from the surfaces, estimated 500 times (500 points at the same place, each its
    /// own stream), stays within 50 % of its mean every time. The bright spot is gathered by
    /// multiple importance sampling, whose estimate is bounded; sampled as an emitter, a point
    /// of it close to the sensor would weigh 1/d² and spike.
    #[test]
    fn sensors_near_a_bright_wall_do_not_spike() {
        let (s, rho) = (4.0, 0.5);
        let scene = cube(s as f32, rho);
        let lum = lamp("lamp", 1000.0, [0.3, 2.0, 2.0], 1.0, "default");
        let points = vec![SensorPoint::new([0.1, 2.0, 1.5], [0.0, 0.0, 1.0]).unwrap(); 500];
        let settings = LightingSettings {
            mesh: MeshParams::Patches(1500),
            ..Default::default()
        };
        let r = lighting(
            &scene,
            std::slice::from_ref(&lum),
            &points,
            &settings,
            &crate::observe::Silent,
        )
        .unwrap();
        let ind: Vec<f64> = r.total.iter().zip(&r.direct).map(|(t, d)| t - d).collect();
        let mean = ind.iter().sum::<f64>() / ind.len() as f64;
        let (lo, hi) = ind
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        assert!(
            lo > 0.5 * mean && hi < 1.5 * mean,
            "from the surfaces: mean {mean} lx, {lo} … {hi}"
        );
    }

    /// No luminaires and no emitting surface: refused on one line.
    #[test]
    fn no_light_is_refused() {
        let scene = cube(1.0, 0.5);
        let e = lighting(
            &scene,
            &[],
            &wall_points(1.0, 1),
            &LightingSettings::default(),
            &crate::observe::Silent,
        )
        .unwrap_err();
        assert!(e.to_string().contains("no light"), "{e}");
    }
}

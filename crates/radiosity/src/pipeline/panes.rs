//! Panes in daylight's light paths (issue 58, glazing "both ways in the interreflection").
//!
//! A clear pane ([`Glazing`]) is a specular interface: light meeting it at incidence θ
//! passes with τ(θ), is mirrored with R(θ) and the rest, 1 − τ − R, is absorbed. The panes
//! are kept out of the interreflection's mesh (they have no diffuse radiosity of their own)
//! and every ray of the daylight pipeline that meets one *branches*: the transmitted branch
//! goes on along the ray with weight × τ, the reflected branch along the mirror direction
//! with weight × R, each to its own end, an opaque patch or the sky. This is the
//! extended-form-factor treatment of specular surfaces in radiosity (Wallace, Cohen &
//! Greenberg (1987), "A two-pass solution to the rendering equation", §4; Sillion & Puech
//! (1989), "A general two-pass method integrating specular and diffuse reflection"): the
//! form factor F_ij becomes the share of the energy leaving i that reaches j by any path of
//! pane transmissions and mirror reflections, each path weighted by the product of its τ's
//! and R's. It fits the code because the daylight pipeline's form factors, first shot and
//! gather are all rays: the Monte Carlo rows ([`Panes::rows`], Szirmay-Kalos & Márton's
//! eq. 7 with each ray's weight in place of its count) keep reciprocity in expectation (the
//! weights are symmetric in the path's direction), and the light a pane absorbs is what the
//! rows lose, Σ_j F_ij = 1 − absorbed_i in a closed room (the books, tested). A diffuse
//! emitter facing a large pane passes τ_d = 2 ∫ τ cos θ sin θ dθ of its light
//! ([`Glazing::diffuse`]), to which the rows converge without being told it.
//!
//! Approximations: a branch whose weight falls under [`MIN_WEIGHT`] or that has met
//! [`MAX_EVENTS`] panes ends there, its weight counted as absorbed (a branch's weight is at
//! most 1, so the loss is bounded by the branches cut, each under 1e-4); the pane is thin
//! (its lateral shift of the ray is ignored).

use super::memory::MemoryCheck;
use crate::accel::Bvh;
use crate::formfactor::monte_carlo::{photon_ray, CHUNK};
use crate::geom::{Ray, Vec3};
use crate::lighting::glazing::Glazing;
use crate::mesh::{Mesh, MeshParams};
use crate::observe::{Event, Observer, Stage};
use crate::sampling::stream;
use crate::scene::Scene;
use crate::system::{Entry, SparseMatrix};
use crate::Error;
use rayon::prelude::*;

/// Most panes (crossings and reflections) one branch is followed through.
pub const MAX_EVENTS: u32 = 16;
/// Branches lighter than this end, counted as absorbed.
pub const MIN_WEIGHT: f64 = 1e-4;
/// Branches pending at once; more are cut (counted as absorbed).
const STACK: usize = 32;

/// Where a branch of a ray ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum End {
    /// The front of an opaque patch.
    Front(u32),
    /// The back of an opaque patch (one-sided surfaces: nothing).
    Back,
    /// It leaves the scene in this direction (scene frame).
    Escape(Vec3),
}

/// The panes of a scene: their own mesh and hierarchy, and each material's pane.
pub(crate) struct Panes {
    mesh: Mesh,
    bvh: Bvh,
    /// Per scene material, its pane (None: opaque).
    glazing: Vec<Option<Glazing>>,
    /// One hierarchy over an opaque mesh's patches and then the panes' ([`Panes::join`]),
    /// with that mesh's patch count: a branch then needs one ray cast where it needs two
    /// apart.
    joined: Option<(Bvh, u32)>,
}

impl Panes {
    /// The polygons of `scene` whose material has a pane in `glazing` (one per material), or
    /// None when there are none.
    pub(crate) fn new(
        scene: &Scene,
        glazing: Vec<Option<Glazing>>,
    ) -> Result<Option<Panes>, Error> {
        let mut g = scene.clone();
        g.polygons.retain(|p| glazing[p.material].is_some());
        g.origins.clear();
        if g.polygons.is_empty() {
            return Ok(None);
        }
        let mesh = Mesh::build(&g, MeshParams::Faces)?;
        let bvh = Bvh::build(&mesh);
        Ok(Some(Panes {
            mesh,
            bvh,
            glazing,
            joined: None,
        }))
    }

    /// Build one hierarchy over `opaque` (the mesh whose hierarchy [`Panes::follow`] is then
    /// given) and the panes, so that each branch of a followed ray is one ray cast instead of
    /// two. The ends are the same: the nearest of the two casts' hits is the nearest hit of
    /// the one (the same triangles and the same intersection arithmetic). Costs a copy of the
    /// mesh's vertices and patches for as long as it is built, and the hierarchy.
    pub(crate) fn join(&mut self, opaque: &Mesh) {
        let offset = opaque.vertices.len() as u32;
        let mut vertices = Vec::with_capacity(opaque.vertices.len() + self.mesh.vertices.len());
        vertices.extend_from_slice(&opaque.vertices);
        vertices.extend_from_slice(&self.mesh.vertices);
        let mut patches = Vec::with_capacity(opaque.patches.len() + self.mesh.patches.len());
        patches.extend_from_slice(&opaque.patches);
        patches.extend(self.mesh.patches.iter().map(|p| {
            let mut q = *p;
            for v in &mut q.vertices {
                if *v != crate::mesh::Patch::NONE {
                    *v += offset;
                }
            }
            q
        }));
        let both = Mesh {
            vertices,
            patches,
            max_edge: opaque.max_edge,
            groups: Vec::new(),
            hanging: Vec::new(),
            grids: opaque.grids.clone(),
            coincident: Default::default(),
        };
        self.joined = Some((Bvh::build(&both), opaque.len() as u32));
    }

    /// The panes' mesh (one patch a polygon).
    pub(crate) fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The pane of scene material `material` (a material of a pane patch).
    pub(crate) fn glazing(&self, material: u32) -> Glazing {
        self.glazing[material as usize].expect("pane patches have a pane")
    }

    /// The pane a glass patch is, and its normal.
    fn pane(&self, patch: u32) -> (Glazing, Vec3) {
        let p = &self.mesh.patches[patch as usize];
        let g = self.glazing[p.material as usize].expect("glass patches have a pane");
        (g, p.normal)
    }

    /// The transmittance along a ray that the opaque geometry does not block: the product of
    /// every pane it crosses (the sun's path: its mirrored branches leave the disc's
    /// direction and are not followed).
    pub(crate) fn transmittance(&self, origin: Vec3, d: Vec3) -> f64 {
        let mut tau = 1.0;
        let mut o = origin;
        for _ in 0..MAX_EVENTS {
            let Some(h) = self.bvh.closest_hit(&Ray::new(o, d), f32::INFINITY) else {
                return tau;
            };
            let (g, n) = self.pane(h.patch);
            tau *= g.transmittance(n.dot(d) as f64);
            o = o + d * h.t + d * self.bvh.ray_offset();
        }
        tau
    }

    /// Follow the ray `origin + t d` through the panes and the opaque scene (`opaque`): each
    /// branch's end and weight go to `visit`; returns the weight the panes absorbed (with the
    /// branches cut). No allocation.
    pub(crate) fn follow(
        &self,
        opaque: &Bvh,
        origin: Vec3,
        d: Vec3,
        visit: &mut impl FnMut(End, f64),
    ) -> f64 {
        let offset = opaque.ray_offset().max(self.bvh.ray_offset());
        let mut stack = [(Vec3::ZERO, Vec3::ZERO, 0.0f64, 0u32); STACK];
        stack[0] = (origin, d, 1.0, 0);
        let mut top = 1;
        let mut absorbed = 0.0;
        while top > 0 {
            top -= 1;
            let (o, d, w, events) = stack[top];
            let ray = Ray::new(o, d);
            // The nearest opaque hit and the nearest pane before it: one cast when joined.
            let (wall, pane) = match &self.joined {
                Some((both, n)) => match both.closest_hit(&ray, f32::INFINITY) {
                    Some(h) if h.patch >= *n => (
                        None,
                        Some(crate::accel::Hit {
                            patch: h.patch - n,
                            ..h
                        }),
                    ),
                    other => (other, None),
                },
                None => {
                    let wall = opaque.closest_hit(&ray, f32::INFINITY);
                    let t_wall = wall.map_or(f32::INFINITY, |h| h.t);
                    (wall, self.bvh.closest_hit(&ray, t_wall))
                }
            };
            let Some(h) = pane else {
                visit(
                    match wall {
                        Some(h) if h.front => End::Front(h.patch),
                        Some(_) => End::Back,
                        None => End::Escape(d),
                    },
                    w,
                );
                continue;
            };
            let (g, n) = self.pane(h.patch);
            let c = n.dot(d) as f64;
            let (tau, r) = (g.transmittance(c), g.reflectance(c));
            absorbed += w * (1.0 - tau - r).max(0.0);
            let p = o + d * h.t;
            let mirrored = (d - n * (2.0 * n.dot(d))).normalize();
            for (dir, wb) in [(d, w * tau), (mirrored, w * r)] {
                if wb < MIN_WEIGHT || events + 1 >= MAX_EVENTS || top == STACK {
                    absorbed += wb;
                } else {
                    stack[top] = (p + dir * offset, dir, wb, events + 1);
                    top += 1;
                }
            }
        }
        absorbed
    }

    /// Every row of F on `mesh` (the opaque scene, hierarchy `opaque`) by Monte Carlo rays
    /// through the panes: `rays` rays a row leave uniform points of patch i in cosine
    /// directions (the streams of [`crate::formfactor::monte_carlo`], by chunk), each adding
    /// its branches' weights / `rays` to the patches whose fronts they reach (F_ii included:
    /// a pane can mirror a patch's light back onto it; progressive refinement takes it). Also
    /// each row's absorbed share. Deterministic for a seed, whatever the threads.
    pub(crate) fn rows(
        &self,
        mesh: &Mesh,
        opaque: &Bvh,
        rays: u32,
        seed: u64,
        memory: &MemoryCheck,
        observer: &dyn Observer,
    ) -> Result<(SparseMatrix, Vec<f64>), Error> {
        memory.check(mesh.len() as u64)?;
        observer.event(Event::Stage(Stage::FormFactors));
        let n = mesh.len();
        let inv = 1.0 / rays.max(1) as f64;
        let offset = opaque.ray_offset();
        let rows: Vec<(Vec<Entry>, f64)> = (0..n)
            .into_par_iter()
            .map_init(
                || (vec![0.0f64; n], Vec::<u32>::new()),
                |(accum, touched), i| {
                    let mut absorbed = 0.0;
                    let mut rng = stream(seed, i as u64, 0, 0);
                    for k in 0..rays as usize {
                        if k % CHUNK == 0 && k > 0 {
                            rng = stream(seed, i as u64, 0, (k / CHUNK) as u64);
                        }
                        let ray = photon_ray(mesh, i, offset, &mut rng);
                        absorbed +=
                            self.follow(opaque, ray.origin, ray.direction, &mut |end, w| {
                                if let End::Front(j) = end {
                                    let a = &mut accum[j as usize];
                                    if *a == 0.0 {
                                        touched.push(j);
                                    }
                                    *a += w;
                                }
                            });
                    }
                    touched.sort_unstable();
                    let row = touched
                        .drain(..)
                        .map(|j| (j, (std::mem::take(&mut accum[j as usize]) * inv) as f32))
                        .collect();
                    (row, absorbed * inv)
                },
            )
            .collect();
        let (rows, absorbed): (Vec<Vec<Entry>>, Vec<f64>) = rows.into_iter().unzip();
        Ok((SparseMatrix::from_rows(rows), absorbed))
    }
}

#[cfg(test)]
#[path = "panes_tests.rs"]
mod tests;

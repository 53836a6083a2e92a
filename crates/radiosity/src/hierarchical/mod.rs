//! Hierarchical radiosity with clustering (Hanrahan, Salzman & Aupperle 1991; clusters after
//! Smits, Arvo & Greenberg 1994 and Sillion 1995).
//!
//! Each input piece (convex quad or triangle) is the root of an element quadtree
//! ([`element`]); the roots are grouped into a binary cluster tree ([`cluster`]). Light moves
//! along *links*: a link from receiver element `r` to source `s` (an element or a cluster) says
//! that `r` gathers `k · B_s`, where `k` is the form factor from `r` to `s` ([`kernel`]) and
//! `B_s` what `s` sends.
//!
//! **Source shares.** Once a source element is split, `B_s` is not its children's mean: the
//! link also records the share of `k` that comes from each of the source's four children
//! (exact point-to-polygon factors from four receiver points in the near field, the kernel
//! to each child's centre in the far field), and gathers `Σ share · B_child` (each share
//! weighted by the child's exposed fraction). Where light is concentrated (a small lamp set
//! into a ceiling), the part of a coarse source that faces the receiver is brighter or darker
//! than the source's mean, and the misses do not cancel: gathering means leaves every surface
//! of an open box under such a lamp dark against the exact system of the same leaves,
//! gathering by shares does not (the test `coarse_links_gather_without_bias`; figures in
//! `docs/notes/hierarchical.md`).
//!
//! **Refinement.** Every root element starts with one candidate link to the top cluster. A
//! candidate is culled when the two cannot see each other (one lies behind the other's plane,
//! or both belong to the same input piece), and otherwise estimated at sixteen jittered points
//! of the receiver ([`kernel`]) and judged by the oracle
//!
//! ```text
//! err = ρ_r A_r (B̄_s · K + k · ΔB_s)
//! ```
//!
//! the power that could be misplaced by gathering through this link: `ΔB_s` is the spread of
//! radiosity among the source's leaves (what gathering from their mean hides), and `K` the
//! kernel's uncertainty over the receiver:
//!
//! - far field (centres more than twice the sum of the bounding radii apart), every ray
//!   arrived: the spread `max − min` of the point values, so that steep fall-off refines;
//! - far field, some ray blocked: at least the largest *unoccluded* point value times
//!   `1 − 0.05^(1/n)` (n rays), the lit fraction that n blocked rays leave possible at 95 %
//!   confidence, since sixteen points cannot tell how much of the receiver a shadow covers
//!   (a receiver whose points all fell in shadow would otherwise keep k = 0 however much of
//!   it is lit);
//! - near field, where points cannot bound the kernel: `max(k_max, min(1, A_s/(π d²)))` with
//!   `d` the gap between the bounding spheres.
//!
//! A link with `err` above `link_error × Φ` (Φ the emitted power) is replaced by links from
//! the children of the larger side (by bounding radius); elements are not split below
//! `min_area`, and a cluster that holds the receiver or whose bounding sphere meets the
//! receiver's is always opened (opening clusters out to twice their radius instead cost more
//! than it gained: `docs/notes/hierarchical.md`). A link that is kept takes
//! its coefficient from a second, independent estimate: keeping a link because its points
//! happened to agree must not bias the light it carries.
//!
//! **Invisible links.** A link judged once a solve has given every element its radiosity,
//! and kept, whose every visibility sample was blocked (its factor 0), is dropped rather than
//! stored, as RenderPark stores no interaction of zero visibility: it would carry nothing,
//! and the oracle kept it because even the lit part its rays could have missed leaves the
//! error under the tolerance. Before the first solve, links from surfaces that do not emit
//! are kept whatever they saw (their error is 0 at B = E, so they must be judged again once
//! there is light to judge them by). On a large scene this drops most links without changing
//! the result beyond the draw (`links_that_see_nothing_are_dropped`;
//! `docs/notes/hierarchical.md`).
//!
//! **Clusters** are sources only: a receiver is always an element, so a root gathers from
//! the clusters of everything far from it (O(log N) links a root, as in Barnes–Hut), and no
//! isotropic assumption is made about how a cluster receives. A cluster link's coefficient is
//! a Monte Carlo estimate of the point-to-area factor over the cluster's actual surfaces with
//! both cosines and visibility ([`kernel`]), and the link gathers what the pieces its samples
//! saw send, each in its share of the coefficient: the mean radiosity of the cluster's
//! surfaces that face the receiver (area- and direction-weighted) would count the ones hidden
//! from it too, which are mostly the dark ones (the lower shelves under a lit one, the floor
//! under furniture), while a lamp in view would count by its area alone
//! (`cluster_links_gather_what_they_see`; `docs/notes/hierarchical.md`). The samples are
//! drawn from the cluster's emitters and from its other surfaces separately, so that a lamp,
//! a small part of the area but most of the light, is neither missed by most receivers nor
//! met with a large weight by a few.
//! Within each, the sixteen receiver points share out the area: each draws from its own
//! sixteenth, in a random order, so that the samples cover the cluster (unbiased, with less
//! variance than independent draws: `cluster_factors_are_unbiased`;
//! `docs/notes/hierarchical.md`).
//!
//! **Covered surface.** Part of an element may lie inside a closed solid (the floor under a
//! box standing on it): it neither receives nor sends light. Each element's exposed fraction
//! is estimated by rays ([`kernel::cover`]), and what a source element sends is the mean
//! radiosity of its children weighted by their exposed area, not by their whole area, which
//! would dilute the light of the floor next to the box with the darkness under it. A leaf
//! that straddles the box's edge sends, for the same reason, what its exposed part reflects:
//! the light arriving at it, which its covered points take no part of, divided by its
//! exposed fraction (without this, block sides lit by the floor strip along their base come
//! out dark: `docs/notes/hierarchical.md`). Part of an
//! element may also lie under a surface flush against it (a panel on a wall): points there
//! gather light through the cover, from where they are lifted off the surface. The same
//! sixteen points find the fraction both exposed and open in front (`free`), and what arrives
//! at an element is what it gathered × `free / exposed`. Only a polygon facing the same way
//! covers: the far side of a wall of no thickness (two one-sided polygons back to back, as
//! MGF's two-sided surfaces become) lies flush too but faces away, and hides nothing
//! (`back_to_back_walls_hide_nothing`). Tested at the same points, a solid's
//! face lying flush (a cabinet's bottom on the floor, inside the solid and under the face at
//! once) is not counted twice (`a_flush_bottom_face_covers_nothing_twice`;
//! `docs/notes/hierarchical.md`).
//!
//! **Coincident twins.** A scene that includes an object twice has every polygon of it twice,
//! in the same place ([`Element::twins`]; half the pieces of RenderPark's hospital). Twins are
//! one surface: neither covers or hides the other, the first of each group is refined and
//! solved and sends the light of all (the emission of each, as every method counts every
//! emitter's power, and its reflection once), and the others take its subdivision and the
//! light arriving at each of its elements, reflected with their own material. Left to chance
//! (which of two coincident polygons a ray reports first), a twin would receive with one
//! copy and send with the other, and light would go missing (`docs/notes/hierarchical.md`).
//!
//! **Solution.** Jacobi iterations of gather (every link, in parallel, one value for each
//! quarter of its receiver), push (each quarter's value to the child in that quarter, and on
//! to its descendants) and pull (an element's radiosity is the area mean of its children's; what
//! it sends, their mean over exposed area; a cluster's, its members' area mean, for the
//! oracle), from
//! B = E, until the power the last iteration changed is at most `tolerance × Φ`. Then every link is judged again with
//! the new radiosities and refined where needed, and the solve repeated, until a pass refines
//! nothing (or `max_passes`).
//!
//! The result is the leaf elements with their radiosity ([`output`] turns them into a mesh
//! whose vertex colours are continuous across T-vertices).

pub mod cluster;
pub mod element;
pub mod kernel;
pub mod output;

/// The solve: gather–push–pull iterations.
mod iteration;
/// Links, and the solved hierarchy that stores them.
mod links;
/// Parameters, errors and the report.
mod params;
/// The oracle, refinement passes, and links that see nothing dropped.
mod refinement;
#[cfg(test)]
mod tests;

pub use links::{Hierarchy, Link};
pub use params::{HierarchicalError, Info, Parameter, Params, MIN_LINK_ERROR};

use crate::accel::Bvh;
use crate::color::Rgb;
use crate::mesh::Mesh;
use crate::observe::{Event, Observer, Stage};
use crate::system::System;
use cluster::Clusters;
use element::{Element, Elements};
use links::{ELEMENT_BYTES, LINK_BYTES};
use rayon::prelude::*;
use std::time::Instant;

struct State<'a> {
    h: Hierarchy,
    /// Fraction of each element both exposed and open in front ([`kernel::Cover::free`]).
    free: Vec<f32>,
    /// Which root elements emit.
    emits: Vec<bool>,
    /// Each root's first coincident twin ([`Element::twins`]); itself when it has none.
    twin_of: Vec<u32>,
    /// The roots that are twins of an earlier one: not refined, not receiving or sending on
    /// their own, given their representative's light.
    hidden: Vec<u32>,
    /// Per element, the area mean of what arrives at its leaves (H), and its mean over their
    /// exposed area: what a hidden twin takes from its representative.
    arrived: Vec<Rgb>,
    arrived_sent: Vec<Rgb>,

    /// Spread (max − min, channel mean) of leaf radiosity under each element / cluster.
    spread: Vec<f32>,
    cluster_spread: Vec<f32>,
    reflectance: &'a [Rgb],
    emission: &'a [Rgb],
    bvh: &'a Bvh,
    params: &'a Params,
    eps: f64,
    emitted: f64,
    min_area: f32,
    /// True once a solve has given every element its radiosity: from then on a link whose
    /// visibility samples were all blocked is dropped, not kept ([`State::refine`]).
    settled: bool,
}

fn mean(c: Rgb) -> f64 {
    c.sum() / 3.0
}

/// Solve by hierarchical radiosity over `roots`, the input pieces as one patch each (with
/// their reflectances and emissions in `system`), `bvh` built over them.
pub fn solve(
    roots: &Mesh,
    system: &System,
    bvh: &Bvh,
    params: &Params,
    observer: &dyn Observer,
) -> Result<Hierarchy, HierarchicalError> {
    params.validate()?;
    let mut items = Element::roots(roots);
    let emits: Vec<bool> = system
        .emission
        .iter()
        .map(|e| e.max_channel() > 0.0)
        .collect();
    // Coincident twins: none covers or hides another, and the first of each group stands for
    // the rest, sending the emission of all (every method counts every emitter's power).
    let diagonal = bvh.bounds().diagonal();
    let twin_of = Element::twins(&items, diagonal * 1e-6, |_| true);
    let mut group_emission = system.emission.clone();
    for (t, &r) in twin_of.iter().enumerate() {
        if r as usize != t {
            group_emission[r as usize] += system.emission[t];
        }
    }
    let hidden: Vec<u32> = (0..items.len() as u32)
        .filter(|&r| twin_of[r as usize] != r)
        .collect();
    for &t in &hidden {
        // The representative's corners, so that the two subdivide alike.
        let r = items[twin_of[t as usize] as usize];
        items[t as usize] = Element::new(r.corners, r.tri, t, element::NONE, 0);
    }
    // Strata of cluster sampling: the roots whose group emits.
    let emitting: Vec<bool> = twin_of
        .iter()
        .map(|&r| group_emission[r as usize].max_channel() > 0.0)
        .collect();
    let clusters = Clusters::build(&items).with_emitters(&items, &emitting);
    let covers: Vec<kernel::Cover> = items
        .par_iter()
        .enumerate()
        .map(|(i, e)| kernel::cover(e, i as u32, bvh, &twin_of, params.seed))
        .collect();
    let exposure: Vec<f32> = covers.iter().map(|c| c.exposed).collect();
    let free: Vec<f32> = covers.iter().map(|c| c.free).collect();
    let total_area: f64 = items.iter().map(|e| e.area as f64).sum();
    let min_area = if params.min_area > 0.0 {
        params.min_area
    } else {
        total_area * 1e-6
    };
    let n = items.len();
    let emitted: f64 = system
        .emission
        .iter()
        .zip(&system.area)
        .map(|(e, a)| mean(*e) * a)
        .sum::<f64>()
        .max(f64::MIN_POSITIVE);
    let nc = clusters.nodes.len();
    let top = clusters.top;
    let mut state = State {
        h: Hierarchy {
            radiosity: system.emission.clone(),
            unshot: vec![Rgb::BLACK; n],
            incident: vec![Rgb::BLACK; n],
            cluster_radiosity: vec![Rgb::BLACK; nc],
            cluster_sources: Vec::new(),
            sent: twin_of
                .iter()
                .map(|&r| group_emission[r as usize])
                .collect(),
            group_emission,
            twin_of: Vec::new(),
            exposure,
            elements: Elements { items, roots: n },
            clusters,
            links: Vec::new(),
            info: Info {
                clusters: nc,
                min_area,
                ..Default::default()
            },
        },
        spread: vec![0.0; n],
        cluster_spread: vec![0.0; nc],
        emits,
        twin_of,
        hidden,
        arrived: vec![Rgb::BLACK; n],
        arrived_sent: vec![Rgb::BLACK; n],
        free,
        reflectance: &system.reflectance,
        emission: &system.emission,
        bvh,
        params,
        eps: params.link_error * emitted,
        emitted,
        min_area: min_area as f32,
        settled: false,
    };
    // Cluster radiosities (and spreads) of B = E before the first refinement.
    let lo: Vec<f32> = state.h.radiosity.iter().map(|b| mean(*b) as f32).collect();
    state.pull_clusters(&lo, &lo);
    for (c, s) in state.cluster_spread.iter_mut().enumerate() {
        // Spread of emission under each cluster: max − min of its members' means.
        let node = &state.h.clusters.nodes[c];
        let members =
            &state.h.clusters.order[node.first as usize..(node.first + node.count) as usize];
        let (l, h) = members
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &m| {
                (l.min(lo[m as usize]), h.max(lo[m as usize]))
            });
        *s = h - l;
    }
    observer.event(Event::Stage(Stage::FormFactors));
    let t = Instant::now();
    let receivers: Vec<(u32, u32)> = (0..n as u32)
        .filter(|&r| state.twin_of[r as usize] == r)
        .map(|r| (r, top))
        .collect();
    state.refine(receivers)?;
    state.h.info.refine_seconds += t.elapsed().as_secs_f64();
    state.h.info.passes = 1;
    observer.event(Event::Stage(Stage::Solve));
    loop {
        let t = Instant::now();
        state.h.info.iterations += state.iterate(observer);
        state.settled = true;
        state.h.info.solve_seconds += t.elapsed().as_secs_f64();
        observer.event(Event::Progress {
            stage: Stage::Solve,
            done: state.h.info.passes as u64,
            total: params.max_passes as u64,
        });
        if state.h.info.passes >= params.max_passes || observer.cancelled() {
            break;
        }
        let t = Instant::now();
        let refined = state.rerefine()?;
        state.h.info.refine_seconds += t.elapsed().as_secs_f64();
        if refined == 0 {
            break;
        }
        state.h.info.passes += 1;
    }
    state.mirror_twins();
    state.h.info.twins = state.hidden.len();
    state.h.twin_of = std::mem::take(&mut state.twin_of);
    let mut h = state.h;
    h.info.elements = h.elements.items.len();
    h.info.leaves = h.elements.items.iter().filter(|e| e.is_leaf()).count();
    h.info.links = h.links.len();
    h.info.bytes = h.info.elements as u64 * ELEMENT_BYTES
        + h.info.links as u64 * LINK_BYTES
        + nc as u64 * 64
        + h.cluster_sources.len() as u64 * 8;
    Ok(h)
}

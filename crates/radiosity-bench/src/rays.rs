//! `radiosity-bench rays SCENE [--rays N] [--patches N] [--threads T]`: the ray-casting
//! workload of form-factor estimation on any scene (a patch picked uniformly, a uniform point
//! on it, a cosine-distributed direction, closest hit), the same rays for every backend: the
//! engine's BVH, and Embree when the binary is built with the `embree` feature. Prints M rays/s
//! (median of the runs), hit rate, nanoseconds per ray and thread, and the ratio.

use crate::args::RaysArgs;
use anyhow::{bail, Result};
use radiosity::accel::Bvh;
use radiosity::formfactor::monte_carlo::photon_ray;
use radiosity::geom::Ray;
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::sampling::{stream, uniform};
use rayon::prelude::*;
use std::time::Instant;

/// The workload: `count` rays, deterministic for `seed`, with the patch each starts from.
pub fn workload(mesh: &Mesh, offset: f32, count: usize, seed: u64) -> Vec<(Ray, u32)> {
    let n = mesh.len() as u64;
    (0..count)
        .into_par_iter()
        .chunks(4096)
        .enumerate()
        .flat_map_iter(|(c, idx)| {
            let mut rng = stream(seed, 0x5241_5953, c as u64, 0);
            idx.into_iter()
                .map(|_| {
                    let r = (uniform(&mut rng) as f64 * n as f64) as u64;
                    let i = r.min(n - 1) as usize;
                    (photon_ray(mesh, i, offset, &mut rng), i as u32)
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// A closest-hit ray caster: for each ray, the patch whose front it hits first (or none).
pub trait Caster: Sync {
    /// Name in the table.
    fn name(&self) -> &'static str;
    /// The patch hit first if its front faces the ray (`u32::MAX` for none), and the hit
    /// distance (infinite for a miss).
    fn cast(&self, ray: &Ray) -> (u32, f32);
    /// Name in the table of [`Caster::cast_batch`].
    fn batch_name(&self) -> &'static str;
    /// [`Caster::cast`] on each of a batch of rays, by the backend's query for many rays.
    fn cast_batch(&self, rays: &[Ray], out: &mut [(u32, f32)]);
}

/// The rays one call of [`Caster::cast_batch`] takes.
pub const BATCH: usize = 256;

/// The bounded any-hit queries' reach, as a fraction of the closest hit's distance.
const SHORT_OF_HIT: f32 = 0.999;

impl Caster for Bvh {
    fn name(&self) -> &'static str {
        "radiosity BVH"
    }
    fn cast(&self, ray: &Ray) -> (u32, f32) {
        front_hit(self.closest_hit(ray, f32::INFINITY))
    }
    fn batch_name(&self) -> &'static str {
        const _: () = assert!(radiosity::accel::IN_FLIGHT == 16, "the label names it");
        if self.interleaves() {
            "BVH, 16 in flight"
        } else {
            "BVH, batches"
        }
    }
    /// `Bvh::closest_hits`: several rays in flight on each thread on a large hierarchy, one
    /// at a time on a small one.
    fn cast_batch(&self, rays: &[Ray], out: &mut [(u32, f32)]) {
        let mut hits = [None; BATCH];
        for (r, o) in rays.chunks(BATCH).zip(out.chunks_mut(BATCH)) {
            let hits = &mut hits[..r.len()];
            self.closest_hits(r, f32::INFINITY, hits);
            for (h, o) in hits.iter().zip(o.iter_mut()) {
                *o = front_hit(*h);
            }
        }
    }
}

/// The engine's BVH over every patch's own triangles, the pieces cut into grids included
/// (`Mesh::grids` dropped): the hierarchy the engine built before it met grids whole, and
/// the one Embree is given, for comparing the traversal on the same triangles.
struct EveryPatch(Bvh);

impl Caster for EveryPatch {
    fn name(&self) -> &'static str {
        "BVH of patches"
    }
    fn cast(&self, ray: &Ray) -> (u32, f32) {
        self.0.cast(ray)
    }
    fn batch_name(&self) -> &'static str {
        if self.0.interleaves() {
            "of patches, 16 in flight"
        } else {
            "of patches, batches"
        }
    }
    fn cast_batch(&self, rays: &[Ray], out: &mut [(u32, f32)]) {
        self.0.cast_batch(rays, out)
    }
}

/// A closest hit as [`Caster::cast`] reports it.
fn front_hit(h: Option<radiosity::accel::Hit>) -> (u32, f32) {
    match h {
        Some(h) if h.front => (h.patch, h.t),
        Some(h) => (u32::MAX, h.t),
        None => (u32::MAX, f32::INFINITY),
    }
}

/// A backend's median rate (rays a second) and the hits of its first run.
type Timed = (f64, Vec<(u32, f32)>);

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Time `caster` over `rays`, `runs` times: (median rays/s, hits per patch result).
fn measure(caster: &dyn Caster, rays: &[(Ray, u32)], runs: usize) -> Timed {
    let cast = || -> Vec<(u32, f32)> { rays.par_iter().map(|(r, _)| caster.cast(r)).collect() };
    time_runs(cast, rays.len(), runs)
}

/// Time `bvh.occluded` over `rays`, ray `k` reaching `reach[k]`, `runs` times (at least
/// once): (median rays/s, rays blocked).
fn measure_occluded(bvh: &Bvh, rays: &[(Ray, u32)], reach: &[f32], runs: usize) -> (f64, usize) {
    let mut rates = Vec::new();
    let mut blocked = 0;
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        blocked = rays
            .par_iter()
            .zip(reach)
            .filter(|((r, _), &t_max)| bvh.occluded(r, t_max))
            .count();
        rates.push(rays.len() as f64 / t.elapsed().as_secs_f64());
    }
    (median(rates), blocked)
}

/// [`measure`] through [`Caster::cast_batch`], [`BATCH`] rays a call.
fn measure_batch(caster: &dyn Caster, rays: &[Ray], runs: usize) -> Timed {
    let cast = || -> Vec<(u32, f32)> {
        let mut out = vec![(0, 0.0); rays.len()];
        out.par_chunks_mut(BATCH)
            .zip(rays.par_chunks(BATCH))
            .for_each(|(o, r)| caster.cast_batch(r, o));
        out
    };
    time_runs(cast, rays.len(), runs)
}

/// Run `cast` once to warm up (its hits are returned), then `runs` times: the median rate of
/// `count` rays.
fn time_runs(cast: impl Fn() -> Vec<(u32, f32)>, count: usize, runs: usize) -> Timed {
    let out = cast(); // warm-up, and the hits compared between backends
    let mut rates = Vec::new();
    for _ in 0..runs {
        let t = Instant::now();
        let h = cast();
        rates.push(count as f64 / t.elapsed().as_secs_f64());
        std::hint::black_box(h);
    }
    (median(rates), out)
}

/// Run the ray benchmark on `scene`.
pub fn run(a: &RaysArgs) -> Result<()> {
    use crate::args::BackendArg;
    crate::positive(&[
        ("--runs", a.runs),
        ("--rays", a.rays),
        ("--patches", a.patches),
    ])?;
    let (scene, count) = (&a.scene, a.rays);
    if a.backend == BackendArg::Embree && !cfg!(feature = "embree") {
        bail!("--backend embree: this binary was built without Embree (cargo build --release --features embree, with Debian's libembree-dev)");
    }
    let scene = radiosity_cli::load_scene(scene, a.one_sided)?;
    scene.validate_geometry()?;
    let mesh = Mesh::build(&scene, MeshParams::Patches(a.patches))?;
    let t = Instant::now();
    let bvh = Bvh::build(&mesh);
    let build = t.elapsed().as_secs_f64();
    let rays = workload(&mesh, bvh.ray_offset(), count, 1);
    let threads = rayon::current_num_threads();
    println!(
        "{}: {} patches, {} rays (uniform patch, uniform point, cosine direction, closest hit), {} threads, median of {} runs",
        scene.place(),
        mesh.len(),
        rays.len(),
        threads,
        a.runs
    );
    let info = bvh.info();
    println!(
        "hierarchy: {} triangles ({} pieces met whole for {} of the patches; {} references after spatial splits); {} nodes of {} children ({:.2} MB), {} leaves of {:.2} references on average ({:.2} MB), depth {}; SAH cost {:.2} (nodes) + {:.2} (leaves)",
        info.triangles,
        info.whole_pieces,
        info.patches_in_whole_pieces,
        info.references,
        info.nodes,
        radiosity::accel::WIDTH,
        info.node_bytes as f64 / 1e6,
        info.leaves,
        info.references as f64 / info.leaves.max(1) as f64,
        (info.bytes - info.node_bytes) as f64 / 1e6,
        info.depth,
        info.sah_nodes,
        info.sah_leaves
    );
    println!(
        "{:<16} {:>10} {:>9} {:>14} {:>9}",
        "backend", "M rays/s", "hit rate", "ns/ray/thread", "build s"
    );
    #[allow(unused_mut)]
    let mut backends: Vec<(Box<dyn Caster>, f64)> = Vec::new();
    // Where the engine meets pieces whole, its hierarchy over every patch's triangles too.
    if a.backend != BackendArg::Embree && info.whole_pieces > 0 {
        let mut each = mesh.clone();
        each.grids.clear();
        let t = Instant::now();
        let b = Bvh::build(&each);
        backends.push((Box::new(EveryPatch(b)), t.elapsed().as_secs_f64()));
    }
    #[cfg(feature = "embree")]
    if a.backend != BackendArg::Bvh {
        let t = Instant::now();
        let e = crate::embree::Embree::new(&mesh)?;
        backends.push((Box::new(e), t.elapsed().as_secs_f64()));
    }
    // Per backend: (rays/s one at a time and its hits, rays/s in batches).
    let mut results: Vec<(Timed, f64)> = Vec::new();
    let only: Vec<Ray> = rays.iter().map(|r| r.0).collect();
    // The BVH's hits are the reference every backend is compared with.
    let ours = measure(&bvh, &rays, a.runs);
    let show = |name: &str, rate: f64, hits: &[(u32, f32)], build: f64| {
        let hit = hits.iter().filter(|h| h.0 != u32::MAX).count() as f64 / hits.len() as f64;
        println!(
            "{:<16} {:>10.2} {:>8.1}% {:>14.0} {:>9.3}",
            name,
            rate / 1e6,
            100.0 * hit,
            1e9 * threads as f64 / rate,
            build
        );
    };
    let mut ours_batch = 0.0;
    if a.backend != BackendArg::Embree {
        show(bvh.name(), ours.0, &ours.1, build);
        let (rate, hits) = measure_batch(&bvh, &only, a.runs);
        if hits != ours.1 {
            bail!("the BVH's query for many rays found other hits than its query for one");
        }
        show(bvh.batch_name(), rate, &hits, build);
        ours_batch = rate;
    }
    if a.backend != BackendArg::Embree {
        for (b, build) in &backends {
            let r = measure(b.as_ref(), &rays, a.runs);
            show(b.name(), r.0, &r.1, *build);
            let (rate, hits) = measure_batch(b.as_ref(), &only, a.runs);
            show(b.batch_name(), rate, &hits, *build);
            results.push((r, rate));
        }
    }
    // Two surfaces at the same distance (coincident, overlapping polygons) are a tie either
    // backend may break its own way: counted apart from real disagreements.
    let tie = 1e-5 * mesh_diagonal(&mesh);
    if a.backend == BackendArg::Embree {
        for (b, build) in &backends {
            let r = measure(b.as_ref(), &rays, a.runs);
            show(b.name(), r.0, &r.1, *build);
            let (rate, hits) = measure_batch(b.as_ref(), &only, a.runs);
            show(b.batch_name(), rate, &hits, *build);
        }
        return Ok(());
    }
    // Any-hit (occlusion) queries on the same rays, unbounded: what shadow rays cost.
    let unbounded = vec![f32::INFINITY; rays.len()];
    let (occ, blocked) = measure_occluded(&bvh, &rays, &unbounded, a.runs);
    let any_hit = ours.1.iter().filter(|h| h.1.is_finite()).count();
    // One row of an any-hit timing: rate, share of rays blocked, time a ray, then `note`.
    let any_row = |name: &str, rate: f64, blocked: usize, note: String| {
        println!(
            "{name:<16} {:>10.2} {:>8.1}% {:>14.0}    ({:.2}× closest-hit; {note})",
            rate / 1e6,
            100.0 * blocked as f64 / rays.len() as f64,
            1e9 * threads as f64 / rate,
            rate / ours.0,
        );
    };
    let agree = rays.len() - blocked.abs_diff(any_hit);
    any_row(
        "BVH any-hit",
        occ,
        blocked,
        format!("agrees on {agree} of {} rays", rays.len()),
    );
    // Bounded: each ray stops just short of the point its closest hit found, the shadow ray
    // of a point that is in fact visible (the costly case: nothing blocks it, so every box
    // within reach is searched). Rays that escaped keep an unbounded reach.
    let reach: Vec<f32> = ours.1.iter().map(|h| h.1 * SHORT_OF_HIT).collect();
    let (bounded, bounded_blocked) = measure_occluded(&bvh, &rays, &reach, a.runs);
    any_row(
        "BVH any, bounded",
        bounded,
        bounded_blocked,
        format!("reach {SHORT_OF_HIT} of the closest hit's distance"),
    );
    for ((b, _), ((rate, hits), batch)) in backends.iter().zip(&results) {
        let differ: Vec<_> = hits
            .iter()
            .zip(&ours.1)
            .filter(|(x, y)| x.0 != y.0)
            .collect();
        let ties = differ
            .iter()
            .filter(|(x, y)| (x.1 - y.1).abs() <= tie)
            .count();
        println!(
            "{} / radiosity BVH: {:.2}×; hits differ on {} of {} rays ({:.4}%), {ties} of them ties at equal distance{}",
            b.name(),
            rate / ours.0,
            differ.len(),
            hits.len(),
            100.0 * differ.len() as f64 / hits.len() as f64,
            if b.name() == "BVH of patches" {
                " (the others at patches' edges, within rounding)"
            } else {
                ""
            }
        );
        println!(
            "{} / {}: {:.2}×",
            b.batch_name(),
            bvh.batch_name(),
            batch / ours_batch
        );
    }
    if ours.1.iter().all(|h| h.0 == u32::MAX) {
        bail!("no ray hit a front side: is the scene one-sided and open?");
    }
    #[cfg(not(feature = "embree"))]
    println!("(Embree: build with `--features embree` and Debian's libembree-dev to compare)");
    Ok(())
}

fn mesh_diagonal(mesh: &Mesh) -> f32 {
    radiosity::geom::Aabb::from_points(mesh.vertices.iter()).diagonal()
}

//! Monte Carlo form factors by ray shooting (Szirmay-Kalos & Márton (1995), "Randomized form factor
//! calculation", eq. 7 and its pseudo-code): `n` rays leave patch `i` from points uniform over its
//! area in cosine-distributed directions; if `k_j` of them hit patch `j` first (on its front
//! side), `F̂_ij = k_j / n`, an unbiased estimate with variance `F_ij (1 − F_ij) / n ≤ 1/(4n)`.
//!
//! A ray that escapes the scene or hits the back of a patch transfers nothing: surfaces are
//! one-sided, which keeps `A_i F_ij = A_j F_ji` (a back side neither sends nor receives).
//!
//! [`super::OnDemandRows`] supplies rows to the shooting solvers on demand and caches them
//! (sparse, under a memory budget), so a patch that shoots again costs no rays. The number of
//! rays of a row grows with the power about to be shot from it ([`super::Params::rays_for`]): an
//! emitter that carries a large share of the scene's power gets proportionally more rays, so
//! that each ray carries about the same power everywhere, which is what keeps the noise of the
//! direct lighting at the level of the indirect.
//!
//! Determinism: rays are drawn in chunks of [`CHUNK`], each from its own random stream keyed by
//! `(seed, patch, row version, chunk)`, and traced in parallel tasks of a few chunks; the hits
//! are counted in a fixed order, so a row does not depend on the number of threads.

use super::Entry;
use crate::accel::Bvh;
use crate::geom::orthonormal_basis;
use crate::geom::Ray;
use crate::mesh::Mesh;
use crate::sampling::{cosine_direction_in, stream, uniform, Rng64};
use rayon::prelude::*;

/// Rays per random stream of a row.
pub const CHUNK: usize = 32;
/// Chunks a parallel task of a row traces together, at most.
const CHUNKS_PER_TASK: usize = 8;
const MISS: u32 = u32::MAX;

/// Photons [`sample_photons`] casts in one call of [`Bvh::closest_hits`]: long enough that
/// its rays in flight seldom drain.
pub const PHOTON_BATCH: usize = 256;

/// Reusable buffers for estimating rows (no allocation per row once warmed up).
#[derive(Debug, Default)]
pub struct RowScratch {
    hits: Vec<u32>,
    counts: Vec<u32>,
    /// One bit per patch: hit by the row being counted.
    hit: Vec<u64>,
    /// One bit per word of `hit`: that word has a bit set.
    words: Vec<u64>,
}

/// Estimate row `i` of F with `n` rays (eq. 7) into `out` (cleared first), using the random
/// streams of `(seed, i, version)`. Returns nothing; `out` holds `(j, k_j/n)` sorted by `j`.
pub fn estimate_row(
    mesh: &Mesh,
    bvh: &Bvh,
    i: usize,
    n: u32,
    seed: u64,
    version: u64,
    scratch: &mut RowScratch,
    out: &mut Vec<Entry>,
) {
    let n = n as usize;
    let offset = bvh.ray_offset();
    let patch = &mesh.patches[i];
    let normal = patch.normal;
    let (tangent, bitangent) = orthonormal_basis(normal);
    scratch.hits.clear();
    scratch.hits.resize(n, MISS);
    // A task draws the rays of a few chunks, each chunk's from its own stream, and casts them
    // together: `Bvh::closest_hits` keeps several in flight where the tree outgrows the cache.
    // At least two tasks wherever there are two chunks, so that both threads share even the
    // smallest rows.
    let per_task = (n.div_ceil(CHUNK) / 2).clamp(1, CHUNKS_PER_TASK);
    let trace = |task: usize, hits: &mut [u32]| {
        let mut rays = [Ray::new(glam::Vec3::ZERO, glam::Vec3::Z); CHUNK * CHUNKS_PER_TASK];
        let mut found = [None; CHUNK * CHUNKS_PER_TASK];
        let (rays, found) = (&mut rays[..hits.len()], &mut found[..hits.len()]);
        for (k, chunk) in rays.chunks_mut(CHUNK).enumerate() {
            let mut rng = stream(seed, i as u64, version, (task * per_task + k) as u64);
            for ray in chunk {
                let (u1, u2, u3) = (uniform(&mut rng), uniform(&mut rng), uniform(&mut rng));
                let p = mesh.sample_point(i, u1, u2, u3);
                let d = cosine_direction_in(
                    normal,
                    tangent,
                    bitangent,
                    uniform(&mut rng),
                    uniform(&mut rng),
                );
                *ray = Ray::new(p + normal * offset, d);
            }
        }
        bvh.closest_hits(rays, f32::INFINITY, found);
        for (slot, h) in hits.iter_mut().zip(found.iter()) {
            *slot = match h {
                Some(h) if h.front && h.patch as usize != i => h.patch,
                _ => MISS,
            };
        }
    };
    if n > CHUNK {
        scratch
            .hits
            .par_chunks_mut(CHUNK * per_task)
            .enumerate()
            .for_each(|(task, hits)| trace(task, hits));
    } else {
        trace(0, &mut scratch.hits);
    }
    // Count hits per patch, and mark the patches hit in a two-level bitmap, whose set bits
    // read in order are the row's patches sorted: the hit patches of a row are a few
    // hundred of up to millions, and sorting them cost more than the marks
    // (docs/notes/library.md).
    let n_patches = mesh.len();
    if scratch.counts.len() < n_patches {
        scratch.counts.resize(n_patches, 0);
        scratch.hit.resize(n_patches.div_ceil(64), 0);
        scratch.words.resize(n_patches.div_ceil(64 * 64), 0);
    }
    let mut distinct = 0;
    for &h in &scratch.hits {
        if h != MISS {
            let h = h as usize;
            scratch.hit[h / 64] |= 1 << (h % 64);
            scratch.words[h / 4096] |= 1 << (h / 64 % 64);
            distinct += (scratch.counts[h] == 0) as usize;
            scratch.counts[h] += 1;
        }
    }
    out.clear();
    // Exactly the row's length, so that a caller can keep `out` itself as the row.
    out.reserve_exact(distinct);
    let inv_n = 1.0 / n as f64;
    for (w, word) in scratch.words.iter_mut().enumerate() {
        let mut high = std::mem::take(word);
        while high != 0 {
            let k = w * 64 + high.trailing_zeros() as usize;
            high &= high - 1;
            let mut low = std::mem::take(&mut scratch.hit[k]);
            while low != 0 {
                let j = k * 64 + low.trailing_zeros() as usize;
                low &= low - 1;
                let c = std::mem::take(&mut scratch.counts[j]);
                out.push((j as u32, (c as f64 * inv_n) as f32));
            }
        }
    }
}

/// Where one *gathering* ray from patch `i` first lands: as [`sample_photon`], but a point that
/// another surface covers sees nothing. Covered means: a coincident twin that the BVH reports
/// before `i` (a probe from half a ray offset behind the point meets it first), or a surface
/// within eight ray offsets in front (a panel lying flush on a wall). A shooting ray launched a
/// ray offset above such a point can pass the cover and see the room, but the light arriving
/// there is what the *cover* receives (rays towards the point meet the cover first), so a
/// gather must not see it. The same draws are taken from `rng` either way.
pub fn gather_photon(mesh: &Mesh, bvh: &Bvh, i: usize, rng: &mut Rng64) -> crate::system::Gathered {
    use crate::system::Gathered;
    let draw = GatherDraw::new(mesh, bvh, i, rng);
    let twin = draw.twin(bvh.closest_hit(&draw.twin_probe(), draw.off));
    if twin
        || bvh
            .closest_hit(&draw.cover_probe(), 8.0 * draw.off)
            .is_some()
    {
        return Gathered::Covered;
    }
    draw.gathered(bvh.closest_hit(&draw.ray(), f32::INFINITY))
}

/// One gathering draw at patch `i` ([`gather_photon`]): its point, normal and direction from
/// five draws of a stream, and the rays cast for it.
#[derive(Clone, Copy, Debug)]
struct GatherDraw {
    i: u32,
    p: glam::Vec3,
    n: glam::Vec3,
    d: glam::Vec3,
    off: f32,
}

impl GatherDraw {
    fn new(mesh: &Mesh, bvh: &Bvh, i: usize, rng: &mut Rng64) -> Self {
        let p = mesh.sample_point(i, uniform(rng), uniform(rng), uniform(rng));
        let n = mesh.patches[i].normal;
        let (t, b) = orthonormal_basis(n);
        let d = cosine_direction_in(n, t, b, uniform(rng), uniform(rng));
        let off = bvh.ray_offset();
        Self {
            i: i as u32,
            p,
            n,
            d,
            off,
        }
    }

    /// From half a ray offset behind the point along the normal, reaching one offset: what
    /// it meets first, if not the patch itself, is a coincident twin reported before it.
    fn twin_probe(&self) -> Ray {
        Ray::new(self.p - self.n * (0.5 * self.off), self.n)
    }

    fn twin(&self, hit: Option<crate::accel::Hit>) -> bool {
        matches!(hit, Some(h) if h.patch != self.i)
    }

    /// From half a ray offset in front, reaching eight: anything met lies flush on the patch.
    fn cover_probe(&self) -> Ray {
        Ray::new(self.p + self.n * (0.5 * self.off), self.n)
    }

    /// The gathering ray itself, lifted a ray offset off the patch.
    fn ray(&self) -> Ray {
        Ray::new(self.p + self.n * self.off, self.d)
    }

    /// What the gathering ray that met `hit` found.
    fn gathered(&self, hit: Option<crate::accel::Hit>) -> crate::system::Gathered {
        use crate::system::Gathered;
        match hit {
            Some(h) if h.front && h.patch != self.i => Gathered::Hit(h.patch),
            _ => Gathered::Lost,
        }
    }
}

/// [`gather_photon`] `per` times for each patch of `patches`, patch `p` drawing from
/// `rngs[p]` (so each stream goes on as `per` single calls leave it), into `out[p · per + s]`:
/// the same answers, with the probes and the gathering rays cast [`PHOTON_BATCH`] at a time
/// by [`Bvh::closest_hits`]. They are drawn draw by draw across the patches (each patch's
/// draws in its own order), so the rays in flight together mostly leave different patches;
/// the answers do not depend on that order.
///
/// # Panics
/// If `rngs` is not one stream a patch, or `out` not `per` answers a patch.
pub fn gather_photons(
    mesh: &Mesh,
    bvh: &Bvh,
    patches: &[u32],
    per: usize,
    rngs: &mut [Rng64],
    out: &mut [crate::system::Gathered],
) {
    use crate::system::Gathered;
    assert_eq!(
        rngs.len(),
        patches.len(),
        "gather_photons: one stream a patch"
    );
    assert_eq!(
        out.len(),
        patches.len() * per,
        "gather_photons: per answers a patch"
    );
    let off = bvh.ray_offset();
    let none = GatherDraw {
        i: 0,
        p: glam::Vec3::ZERO,
        n: glam::Vec3::Z,
        d: glam::Vec3::Z,
        off,
    };
    let mut batch = [(0usize, none); PHOTON_BATCH];
    let mut open = [0usize; PHOTON_BATCH];
    let mut rays = [none.ray(); PHOTON_BATCH];
    let mut hits = [None; PHOTON_BATCH];
    // Cast `ray` of each open draw; keep open those `keep` says, close the others.
    let mut cast = |batch: &[(usize, GatherDraw)],
                    open: &mut [usize],
                    ray: fn(&GatherDraw) -> Ray,
                    t_max: f32,
                    keep: &mut dyn FnMut(usize, &GatherDraw, Option<crate::accel::Hit>) -> bool|
     -> usize {
        for (r, &k) in rays.iter_mut().zip(open.iter()) {
            *r = ray(&batch[k].1);
        }
        let m = open.len();
        bvh.closest_hits(&rays[..m], t_max, &mut hits[..m]);
        let mut kept = 0;
        for j in 0..m {
            let k = open[j];
            if keep(batch[k].0, &batch[k].1, hits[j]) {
                open[kept] = k;
                kept += 1;
            }
        }
        kept
    };
    let mut order = (0..per).flat_map(|s| (0..patches.len()).map(move |p| (p, s)));
    loop {
        let mut len = 0;
        for (b, (p, s)) in batch.iter_mut().zip(order.by_ref()) {
            *b = (
                p * per + s,
                GatherDraw::new(mesh, bvh, patches[p] as usize, &mut rngs[p]),
            );
            len += 1;
        }
        if len == 0 {
            return;
        }
        let batch = &batch[..len];
        for (k, o) in open[..len].iter_mut().enumerate() {
            *o = k;
        }
        // The twin probes, the cover probes of the draws not twinned, then the gathering rays
        // of the draws not covered.
        let mut m = cast(
            batch,
            &mut open[..len],
            GatherDraw::twin_probe,
            off,
            &mut |slot, d, h| {
                let twin = d.twin(h);
                if twin {
                    out[slot] = Gathered::Covered;
                }
                !twin
            },
        );
        m = cast(
            batch,
            &mut open[..m],
            GatherDraw::cover_probe,
            8.0 * off,
            &mut |slot, _, h| {
                if h.is_some() {
                    out[slot] = Gathered::Covered;
                }
                h.is_none()
            },
        );
        cast(
            batch,
            &mut open[..m],
            GatherDraw::ray,
            f32::INFINITY,
            &mut |slot, d, h| {
                out[slot] = d.gathered(h);
                false
            },
        );
    }
}

/// The ray of a photon leaving patch `i`, as form-factor estimation casts it: from a uniform
/// point of the patch (three draws from `rng`) lifted `offset` off it along its normal, in a
/// cosine-distributed direction (two more draws).
pub fn photon_ray(mesh: &Mesh, i: usize, offset: f32, rng: &mut Rng64) -> Ray {
    let p = mesh.sample_point(i, uniform(rng), uniform(rng), uniform(rng));
    let n = mesh.patches[i].normal;
    let (t, b) = orthonormal_basis(n);
    let d = cosine_direction_in(n, t, b, uniform(rng), uniform(rng));
    Ray::new(p + n * offset, d)
}

/// [`sample_photon`] for each patch of `sources` in turn, with the same draws from `rng`, into
/// `out` (`u32::MAX` where lost): the rays cast [`PHOTON_BATCH`] at a time by
/// [`Bvh::closest_hits`].
pub fn sample_photons(mesh: &Mesh, bvh: &Bvh, sources: &[u32], rng: &mut Rng64, out: &mut [u32]) {
    let offset = bvh.ray_offset();
    let mut rays = [Ray::new(glam::Vec3::ZERO, glam::Vec3::Z); PHOTON_BATCH];
    let mut hits = [None; PHOTON_BATCH];
    for (from, out) in sources
        .chunks(PHOTON_BATCH)
        .zip(out.chunks_mut(PHOTON_BATCH))
    {
        let rays = &mut rays[..from.len()];
        for (ray, &i) in rays.iter_mut().zip(from) {
            *ray = photon_ray(mesh, i as usize, offset, rng);
        }
        let hits = &mut hits[..from.len()];
        bvh.closest_hits(rays, f32::INFINITY, hits);
        for ((o, h), &i) in out.iter_mut().zip(hits.iter()).zip(from) {
            *o = match h {
                Some(h) if h.front && h.patch != i => h.patch,
                _ => u32::MAX,
            };
        }
    }
}

/// Where one photon leaving patch `i` first lands: a ray from a uniform point of patch i in a
/// cosine-distributed direction; `None` when it escapes or hits a back side.
pub fn sample_photon(mesh: &Mesh, bvh: &Bvh, i: usize, rng: &mut Rng64) -> Option<u32> {
    match bvh.closest_hit(&photon_ray(mesh, i, bvh.ray_offset(), rng), f32::INFINITY) {
        Some(h) if h.front && h.patch as usize != i => Some(h.patch),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::MeshParams;
    use crate::scene::builtin;

    /// Gathering draws cast in batches ([`gather_photons`]) answer what single draws
    /// ([`gather_photon`]) answer, from the same streams, which go on in step: on a floor with
    /// a coincident twin on one part and a panel lying flush on another, so that every answer
    /// (a hit, a lost ray, a twin, a cover) occurs, with more draws than one batch holds.
    #[test]
    fn gathering_in_batches_is_gathering_one_draw_at_a_time() {
        use crate::color::Rgb;
        use crate::scene::{Material, Polygon, Scene};
        use crate::system::Gathered;
        // Facing up, or down for the lamp (material 1).
        let square = |x0: f32, x1: f32, y: f32, material| {
            let mut vertices: Vec<glam::Vec3> =
                [[x0, y, x0], [x0, y, x1], [x1, y, x1], [x1, y, x0]]
                    .iter()
                    .map(|v| glam::Vec3::from_array(*v))
                    .collect();
            if material == 1 {
                vertices.reverse();
            }
            Polygon {
                vertices,
                material,
                line: 0,
                group: 0,
            }
        };
        let build = |flush: f32| {
            let scene = Scene {
                name: "floor, twin and panel".into(),
                materials: vec![
                    Material::diffuse("grey", Rgb::splat(0.5)),
                    Material::emitter("lamp", Rgb::splat(0.0), Rgb::splat(1.0)),
                ],
                polygons: vec![
                    square(0.0, 1.0, 0.0, 0),
                    square(0.05, 0.45, 0.0, 0),
                    square(0.5, 0.9, flush, 0),
                    square(0.2, 0.8, 1.0, 1),
                ],
                ..Scene::default()
            };
            Mesh::build(&scene, MeshParams::Patches(150)).unwrap()
        };
        let off = Bvh::build(&build(0.0)).ray_offset();
        let mesh = build(2.0 * off);
        let bvh = Bvh::build(&mesh);
        let patches: Vec<u32> = (0..mesh.len() as u32).collect();
        let per = 9;
        let streams = || -> Vec<Rng64> {
            patches
                .iter()
                .map(|&j| stream(5, u64::MAX, j as u64, 2))
                .collect()
        };
        let (mut one, mut many) = (streams(), streams());
        let single: Vec<Gathered> = patches
            .iter()
            .zip(&mut one)
            .flat_map(|(&j, rng)| {
                (0..per)
                    .map(|_| gather_photon(&mesh, &bvh, j as usize, rng))
                    .collect::<Vec<_>>()
            })
            .collect();
        let mut batched = vec![Gathered::Lost; patches.len() * per];
        gather_photons(&mesh, &bvh, &patches, per, &mut many, &mut batched);
        assert!(batched.len() > 2 * PHOTON_BATCH);
        assert_eq!(batched, single);
        let count = |f: fn(&Gathered) -> bool| single.iter().filter(|g| f(g)).count();
        assert!(count(|g| matches!(g, Gathered::Hit(_))) > 60);
        assert!(count(|g| *g == Gathered::Lost) > 100);
        assert!(count(|g| *g == Gathered::Covered) > 60);
        for (a, b) in one.iter_mut().zip(&mut many) {
            assert_eq!(uniform(a), uniform(b));
        }
    }

    /// A row is what its rays, drawn chunk by chunk from the chunks' streams and traced one
    /// after another as photons ([`sample_photon`]), count (a plain serial loop, the
    /// estimator's definition): the parallel tasks, the chunks they group and the threads
    /// change nothing. Rows of one chunk, of two (a task each), of a few tasks with a partial
    /// last one, and of many with a partial last chunk.
    #[test]
    fn a_row_counts_what_its_rays_drawn_in_order_hit() {
        let scene = builtin::cornell();
        let mesh = Mesh::build(&scene, MeshParams::Patches(400)).unwrap();
        let bvh = Bvh::build(&mesh);
        let (seed, version) = (7, 2);
        for (i, n) in [(5, 20), (9, 40), (33, 300), (60, 1000), (321, 16_461usize)] {
            let mut counts = std::collections::BTreeMap::<u32, u32>::new();
            for c in 0..n.div_ceil(CHUNK) {
                let mut rng = stream(seed, i as u64, version, c as u64);
                for _ in c * CHUNK..n.min((c + 1) * CHUNK) {
                    // The same five draws and the same ray as a row's, one photon's.
                    if let Some(j) = sample_photon(&mesh, &bvh, i, &mut rng) {
                        *counts.entry(j).or_default() += 1;
                    }
                }
            }
            let expected: Vec<Entry> = counts
                .into_iter()
                // k/n, in the estimator's arithmetic (k times 1/n, in f64, then f32).
                .map(|(j, k)| (j, (k as f64 * (1.0 / n as f64)) as f32))
                .collect();
            let mut scratch = RowScratch::default();
            let mut row = Vec::new();
            for threads in [1, 2] {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| {
                        estimate_row(
                            &mesh,
                            &bvh,
                            i,
                            n as u32,
                            seed,
                            version,
                            &mut scratch,
                            &mut row,
                        )
                    });
                assert_eq!(row, expected, "patch {i}, {n} rays, {threads} threads");
            }
            assert!(row.len() > 5, "{}", row.len());
        }
    }
}

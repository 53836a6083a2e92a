//! Refinement: every candidate link is culled, kept or replaced by links from the children of
//! one side, as the oracle decides (the module docs of [`super`] give it); after each solve
//! every link is judged again with the new radiosities, and links whose every visibility
//! sample was blocked are dropped.

use super::cluster::CLUSTER;
use super::kernel::{self, Context, Estimate};
use super::links::{Link, ELEMENT_BYTES, LINK_BYTES};
use super::params::HierarchicalError;
use super::{mean, State};
use crate::color::Rgb;
use crate::geom::Vec3;
use rayon::prelude::*;

/// What re-refinement does with a link.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Verdict {
    Keep,
    SplitReceiver,
    SplitSource,
}

enum Decision {
    Cull,
    Accept(Estimate, f32, f32),
    SplitReceiver,
    SplitSource,
}

impl State<'_> {
    fn source(&self, s: u32) -> (Rgb, f32, f32, Vec3, f64) {
        if s & CLUSTER != 0 {
            let c = (s & !CLUSTER) as usize;
            let n = &self.h.clusters.nodes[c];
            (
                self.h.cluster_radiosity[c],
                self.cluster_spread[c],
                n.radius,
                n.centre,
                n.area,
            )
        } else {
            let e = &self.h.elements.items[s as usize];
            (
                self.h.sent[s as usize],
                self.spread[s as usize],
                e.radius,
                e.centre,
                e.area as f64,
            )
        }
    }

    fn error(&self, r: u32, s: u32, k: f32, uncertainty: f32) -> f64 {
        let re = &self.h.elements.items[r as usize];
        let (b, spread, ..) = self.source(s);
        mean(self.reflectance[re.root as usize])
            * re.area as f64
            * (mean(b) * uncertainty as f64 + k as f64 * spread as f64)
    }

    fn can_split(&self, e: u32) -> bool {
        e & CLUSTER != 0 || self.h.elements.items[e as usize].area * 0.25 >= self.min_area
    }

    /// Which side to open when a link is not good enough, if either can be.
    fn split(&self, r: u32, s: u32) -> Option<Decision> {
        let rr = self.h.elements.items[r as usize].radius;
        let (_, _, rs, ..) = self.source(s);
        match (self.can_split(r), self.can_split(s)) {
            (true, true) if rr >= rs => Some(Decision::SplitReceiver),
            (true, false) => Some(Decision::SplitReceiver),
            (_, true) => Some(Decision::SplitSource),
            (false, false) => None,
        }
    }

    fn decide(&self, ctx: &Context, r: u32, s: u32) -> Decision {
        let re = &self.h.elements.items[r as usize];
        fn behind(mut points: impl Iterator<Item = Vec3>, o: Vec3, n: Vec3, size: f32) -> bool {
            points.all(|p| (p - o).dot(n) <= 1e-5 * size)
        }
        let (_, _, rs, cs, _) = self.source(s);
        let size = re.radius + rs;
        if s & CLUSTER != 0 {
            let c = s & !CLUSTER;
            let node = &self.h.clusters.nodes[c as usize];
            if self.h.clusters.contains(c, re.root) {
                return Decision::SplitSource;
            }
            let (lo, hi) = (node.bounds.min, node.bounds.max);
            let corners = (0..8).map(|i| {
                Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            });
            if behind(corners, re.centre, re.normal, size) {
                return Decision::Cull;
            }
            if (cs - re.centre).length() <= rs + re.radius {
                return if re.radius > rs && self.can_split(r) {
                    Decision::SplitReceiver
                } else {
                    Decision::SplitSource
                };
            }
        } else {
            let se = &self.h.elements.items[s as usize];
            if se.root == re.root
                || self.twin_of[se.root as usize] != se.root
                || behind(se.polygon().iter().copied(), re.centre, re.normal, size)
                || behind(re.polygon().iter().copied(), se.centre, se.normal, size)
            {
                return Decision::Cull;
            }
        }
        // A bound on the kernel from the bounding spheres alone (no samples): where even it
        // keeps the link's error under the tolerance, the link is kept without the oracle's
        // estimate, and judged by the bound until the radiosities make it too loose
        // ([`State::rerefine`]). Most links of small receivers never need more; before the
        // first solve, every link from a surface that does not emit is kept so (its error is
        // 0 whatever its factor).
        let bound = self.bound(r, s);
        if self.error(r, s, bound, bound) <= self.eps {
            return Decision::Accept(ctx.estimate(r, s, 1, true), -bound, bound);
        }
        let (k_oracle, uncertainty, rays) = self.oracle(ctx, r, s);
        if self.error(r, s, k_oracle, uncertainty) > self.eps {
            if let Some(d) = self.split(r, s) {
                return d;
            }
        }
        // Kept: its coefficient from an estimate independent of the one that decided.
        let mut kept = ctx.estimate(r, s, 1, true);
        kept.rays += rays;
        Decision::Accept(kept, k_oracle, uncertainty)
    }

    /// An upper bound on the point-to-area factor from any point of receiver `r` to source
    /// `s`: `A_s / (π g²)` (at most 1) for the gap `g` between their bounding spheres, 1 where
    /// they meet.
    fn bound(&self, r: u32, s: u32) -> f32 {
        let re = &self.h.elements.items[r as usize];
        let (_, _, rs, cs, area_s) = self.source(s);
        let gap = (cs - re.centre).length() - re.radius - rs;
        if gap > 0.0 {
            (area_s / (std::f64::consts::PI * gap as f64 * gap as f64)).min(1.0) as f32
        } else {
            1.0
        }
    }

    /// The oracle's view of the link from `r` to `s`, from its own estimate (stream 0): the
    /// factor, the kernel uncertainty, and the rays cast.
    fn oracle(&self, ctx: &Context, r: u32, s: u32) -> (f32, f32, u32) {
        let re = &self.h.elements.items[r as usize];
        let (_, _, rs, cs, _) = self.source(s);
        let est = ctx.estimate(r, s, 0, false);
        let d = (cs - re.centre).length();
        let uncertainty = if d > 2.0 * (re.radius + rs) {
            if est.blocked {
                // However many rays were blocked, a lit part the rays missed may remain: at
                // 95 % confidence it is below 1 − 0.05^(1/n) of the receiver for n rays.
                let missed = 1.0 - 0.05f32.powf(1.0 / est.rays.max(1) as f32);
                (est.hi - est.lo).max(est.unoccluded * missed)
            } else {
                est.hi - est.lo
            }
        } else {
            est.hi.max(self.bound(r, s))
        };
        (est.k, uncertainty, est.rays)
    }

    /// What link estimation reads, visibility samples drawn by `power` ([`State::power`]).
    fn context<'a>(&'a self, power: &'a [f32]) -> Context<'a> {
        Context {
            elements: &self.h.elements.items,
            clusters: &self.h.clusters,
            bvh: self.bvh,
            rays: self.params.visibility_rays,
            seed: self.params.seed,
            emits: &self.emits,
            twin_of: &self.twin_of,
            power,
        }
    }

    /// What each element sends (channel mean) times its area: the weights that visibility
    /// samples on a source are drawn by ([`Context::power`]). Over the whole area, exposed or
    /// not: a sample in a covered part is seen by nobody, and so the fraction seen still
    /// counts the part of the source that sends nothing, as the link's factor (over the whole
    /// source) needs.
    fn power(&self) -> Vec<f32> {
        let items = &self.h.elements.items;
        (0..items.len())
            .into_par_iter()
            .map(|e| (mean(self.h.sent[e]) * items[e].area as f64) as f32)
            .collect()
    }

    fn check_memory(&self) -> Result<(), HierarchicalError> {
        let (elements, links) = (self.h.elements.items.len(), self.h.links.len());
        let needed = elements as u64 * ELEMENT_BYTES
            + links as u64 * LINK_BYTES
            + self.h.cluster_sources.len() as u64 * 8
            + self.h.clusters.nodes.len() as u64 * 64;
        if needed > self.params.memory_limit {
            return Err(HierarchicalError::TooLarge {
                elements,
                links,
                needed,
                limit: self.params.memory_limit,
            });
        }
        Ok(())
    }

    pub(super) fn new_elements(&mut self, parent: u32) -> u32 {
        let before = self.h.elements.items.len();
        let first = self.h.elements.subdivide(parent);
        let grown = self.h.elements.items.len() - before;
        let b = self.h.radiosity[parent as usize];
        let sent = self.h.sent[parent as usize];
        for k in 0..grown {
            let id = (before + k) as u32;
            let el = &self.h.elements.items[id as usize];
            let c = kernel::cover(el, id, self.bvh, &self.twin_of, self.params.seed);
            self.h.exposure.push(c.exposed);
            self.free.push(c.free);
            self.h.sent.push(sent);
            self.h.radiosity.push(b);
            self.h.unshot.push(Rgb::BLACK);
            self.h.incident.push(Rgb::BLACK);
            self.spread.push(0.0);
        }
        first
    }

    /// Estimate and judge every candidate, splitting until every one is a link or culled.
    pub(super) fn refine(&mut self, mut todo: Vec<(u32, u32)>) -> Result<(), HierarchicalError> {
        // Candidates are decided a slice at a time, so that the decisions (an estimate each)
        // take a few megabytes, reused, not a fresh gigabyte a round; the elements a slice
        // creates are past the end of `power` and so unseen by later slices of the round
        // ([`Context::power_point`]): the decisions do not depend on the slicing.
        const SLICE: usize = 1 << 16;
        while !todo.is_empty() {
            let power = self.power();
            let mut next = Vec::new();
            for slice in todo.chunks(SLICE) {
                let decisions: Vec<Decision> = {
                    let ctx = self.context(&power);
                    slice
                        .par_iter()
                        .map(|&(r, s)| self.decide(&ctx, r, s))
                        .collect()
                };
                self.take(slice, decisions, &mut next);
            }
            self.check_memory()?;
            todo = next;
        }
        Ok(())
    }

    /// Carry out the decisions on `slice`'s candidates: store the links kept, split what
    /// must be split and queue its candidates in `next`.
    fn take(&mut self, slice: &[(u32, u32)], decisions: Vec<Decision>, next: &mut Vec<(u32, u32)>) {
        for (&(r, s), d) in slice.iter().zip(decisions) {
            match d {
                Decision::Cull => {}
                Decision::Accept(est, ..) if est.k == 0.0 && self.settled => {
                    // Judged with solved radiosities and found to carry nothing: no
                    // link (as RenderPark keeps no interaction of zero visibility).
                    self.h.info.rays += est.rays as u64;
                    self.h.info.invisible += 1;
                }
                Decision::Accept(est, k_oracle, uncertainty) => {
                    self.h.info.rays += est.rays as u64;
                    let from = self.h.cluster_sources.len() as u32;
                    self.h.cluster_sources.extend_from_slice(&est.seen);
                    let seen = [from, self.h.cluster_sources.len() as u32];
                    self.h.links.push(Link {
                        receiver: r,
                        source: s,
                        k: est.k,
                        k_oracle,
                        uncertainty,
                        quarters: est.quarters,
                        sources: est.sources,
                        seen,
                    });
                }
                Decision::SplitReceiver => {
                    self.h.info.refinements += 1;
                    let first = self.new_elements(r);
                    next.extend((first..first + 4).map(|c| (c, s)));
                }
                Decision::SplitSource if s & CLUSTER != 0 => {
                    self.h.info.refinements += 1;
                    let node = &self.h.clusters.nodes[(s & !CLUSTER) as usize];
                    next.extend(node.children.map(|c| (r, c)));
                }
                Decision::SplitSource => {
                    self.h.info.refinements += 1;
                    let first = self.new_elements(s);
                    next.extend((first..first + 4).map(|c| (r, c)));
                }
            }
        }
    }

    /// Judge every link with the current radiosities; replace those that fail by candidates.
    pub(super) fn rerefine(&mut self) -> Result<u64, HierarchicalError> {
        let mut links = std::mem::take(&mut self.h.links);
        let power = self.power();
        let ctx = self.context(&power);
        // A link judged by its bound (k_oracle < 0) that the bound no longer clears is
        // judged again by the oracle's own estimate, as a new link would be (and takes the
        // oracle's view in place). A verdict and the rays cast, a few bytes a link: the
        // links are millions.
        let verdicts: Vec<(Verdict, u32)> = links
            .par_iter_mut()
            .map(|l| {
                let (r, s) = (l.receiver, l.source);
                if self.error(r, s, l.k_oracle.abs(), l.uncertainty) <= self.eps {
                    return (Verdict::Keep, 0);
                }
                let mut rays = 0;
                if l.k_oracle < 0.0 {
                    let (k, u, cast) = self.oracle(&ctx, r, s);
                    (l.k_oracle, l.uncertainty, rays) = (k, u, cast);
                    if self.error(r, s, k, u) <= self.eps {
                        return (Verdict::Keep, rays);
                    }
                }
                let v = match self.split(r, s) {
                    Some(Decision::SplitReceiver) => Verdict::SplitReceiver,
                    Some(Decision::SplitSource) => Verdict::SplitSource,
                    _ => Verdict::Keep,
                };
                (v, rays)
            })
            .collect();
        let mut todo = Vec::new();
        let mut kept = Vec::with_capacity(links.len());
        let mut split = 0;
        for (l, (v, rays)) in links.into_iter().zip(verdicts) {
            self.h.info.rays += rays as u64;
            let (r, s) = (l.receiver, l.source);
            if v != Verdict::Keep {
                split += 1;
            }
            match v {
                Verdict::Keep if l.k == 0.0 => self.h.info.invisible += 1,
                Verdict::Keep => kept.push(l),
                Verdict::SplitReceiver => {
                    let first = self.new_elements(r);
                    todo.extend((first..first + 4).map(|c| (c, s)));
                }
                Verdict::SplitSource if s & CLUSTER != 0 => {
                    let node = &self.h.clusters.nodes[(s & !CLUSTER) as usize];
                    todo.extend(node.children.map(|c| (r, c)));
                }
                Verdict::SplitSource => {
                    let first = self.new_elements(s);
                    todo.extend((first..first + 4).map(|c| (r, c)));
                }
            }
        }
        self.h.info.refinements += split;
        // The pieces seen by the links kept, without those of the links replaced.
        let old = std::mem::take(&mut self.h.cluster_sources);
        for l in &mut kept {
            let from = self.h.cluster_sources.len() as u32;
            self.h
                .cluster_sources
                .extend_from_slice(&old[l.seen[0] as usize..l.seen[1] as usize]);
            l.seen = [from, self.h.cluster_sources.len() as u32];
        }
        self.h.links = kept;
        self.refine(todo)?;
        Ok(split)
    }
}

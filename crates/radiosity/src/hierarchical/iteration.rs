//! The solve: Jacobi iterations of gather, push and pull over the links and the element
//! quadtrees (the module docs of [`super`] describe them), hidden twins given their
//! representatives' light, and clusters' radiosities pulled up for the oracle.

use super::cluster::CLUSTER;
use super::element;
use super::{mean, State};
use crate::color::Rgb;
use crate::observe::Observer;
use rayon::prelude::*;

impl State<'_> {
    /// Gather–push–pull until the tolerance; returns iterations.
    pub(super) fn iterate(&mut self, observer: &dyn Observer) -> u64 {
        // Links grouped by receiver, in a fixed order.
        self.h.links.sort_by_key(|l| (l.receiver, l.source));
        let n = self.h.elements.items.len();
        let mut start = vec![0u32; n + 1];
        for l in &self.h.links {
            start[l.receiver as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut iterations = 0;
        let mut down = vec![Rgb::BLACK; n];
        loop {
            // Gather: every element's links, in parallel, each receiver's sum in link order.
            let h = &self.h;
            let gathered: Vec<[Rgb; 4]> = (0..n)
                .into_par_iter()
                .map(|e| {
                    let mut g = [Rgb::BLACK; 4];
                    for l in &h.links[start[e] as usize..start[e + 1] as usize] {
                        let b = h.link_radiosity(l);
                        for (gq, kq) in g.iter_mut().zip(l.quarters) {
                            *gq += b * kq as f64;
                        }
                    }
                    g
                })
                .collect();
            // Push: parents come before children; child c takes its parent's quarter c.
            let items = &self.h.elements.items;
            for e in 0..n {
                let p = items[e].parent;
                down[e] = if p == element::NONE {
                    Rgb::BLACK
                } else {
                    let p = p as usize;
                    down[p] + gathered[p][e - items[p].children as usize]
                };
            }
            // Leaves: B = E + ρ H; pull: children come after parents, so a reverse pass sees
            // every child before its parent.
            let mut change = 0.0;
            let mut lo = vec![f32::INFINITY; n];
            let mut hi = vec![f32::NEG_INFINITY; n];
            let mut arrived = vec![Rgb::BLACK; n];
            let mut arrived_sent = vec![Rgb::BLACK; n];
            for e in (0..n).rev() {
                let el = &items[e];
                if el.parent == element::NONE && self.twin_of[e] != e as u32 {
                    // A hidden twin: given its representative's light below.
                    continue;
                }
                let g = &gathered[e];
                // The mean over the element's points of what they gathered: zero at points
                // inside a closed solid, the full light at points under a surface flush in
                // front that still see the room. Arriving: over the free part; what the
                // exposed part reflects: the gathered mean over the exposed fraction.
                let gathered_mean = down[e] + (g[0] + g[1] + g[2] + g[3]) * 0.25;
                let (x, free) = (self.h.exposure[e] as f64, self.free[e] as f64);
                let (here, lit) = if x > 0.0 {
                    (gathered_mean * (free / x), gathered_mean / x)
                } else {
                    // No point found exposed, yet a sliver may be (an element across a box's
                    // edge): what its points gathered is already the area mean.
                    (gathered_mean, gathered_mean)
                };
                self.h.incident[e] = here;
                let b = if el.is_leaf() {
                    let root = el.root as usize;
                    let b = self.emission[root] + self.reflectance[root] * here;
                    let d = (b - self.h.radiosity[e]).map(f64::abs);
                    change += d.sum() / 3.0 * el.area as f64;
                    self.h.unshot[e] = d;
                    let m = mean(b) as f32;
                    lo[e] = m;
                    hi[e] = m;
                    self.h.sent[e] = self.h.group_emission[root] + self.reflectance[root] * lit;
                    arrived[e] = here;
                    arrived_sent[e] = lit;
                    b
                } else {
                    let mut s = Rgb::BLACK;
                    let mut a = 0.0;
                    let mut u = Rgb::BLACK;
                    let (mut se, mut ae) = (Rgb::BLACK, 0.0);
                    let (mut ha, mut hs) = (Rgb::BLACK, Rgb::BLACK);
                    for c in el.children..el.children + 4 {
                        let c = c as usize;
                        let ca = items[c].area as f64;
                        s += self.h.radiosity[c] * ca;
                        u += self.h.unshot[c] * ca;
                        ha += arrived[c] * ca;
                        a += ca;
                        let w = ca * self.h.exposure[c] as f64;
                        se += self.h.sent[c] * w;
                        hs += arrived_sent[c] * w;
                        ae += w;
                        if self.h.exposure[c] > 0.0 {
                            lo[e] = lo[e].min(lo[c]);
                            hi[e] = hi[e].max(hi[c]);
                        }
                    }
                    self.h.unshot[e] = if a > 0.0 { u / a } else { Rgb::BLACK };
                    let b = if a > 0.0 { s / a } else { Rgb::BLACK };
                    arrived[e] = if a > 0.0 { ha / a } else { Rgb::BLACK };
                    self.h.sent[e] = if ae > 0.0 { se / ae } else { b };
                    arrived_sent[e] = if ae > 0.0 { hs / ae } else { arrived[e] };
                    b
                };
                self.h.radiosity[e] = b;
            }
            self.arrived = arrived;
            self.arrived_sent = arrived_sent;
            for k in 0..self.hidden.len() {
                let t = self.hidden[k] as usize;
                let r = self.twin_of[t] as usize;
                self.give_twin(t, r);
                lo[t] = lo[r];
                hi[t] = hi[r];
            }
            for e in 0..n {
                self.spread[e] = (hi[e] - lo[e]).max(0.0);
            }
            self.pull_clusters(&lo, &hi);
            iterations += 1;
            let fraction = change / self.emitted;
            self.h.info.unshot_fraction = fraction;
            self.h.info.converged = fraction <= self.params.tolerance;
            if self.h.info.converged
                || iterations >= self.params.max_iterations
                || observer.cancelled()
            {
                return iterations;
            }
        }
    }

    /// Element `t` of a hidden twin takes what arrives at the same element `r` of its
    /// representative, and reflects it with its own material.
    fn give_twin(&mut self, t: usize, r: usize) {
        let root = self.h.elements.items[t].root as usize;
        let (rho, e) = (self.reflectance[root], self.emission[root]);
        self.h.radiosity[t] = e + rho * self.arrived[r];
        // What the group sends, so that a cluster's mean over its surfaces is unchanged.
        self.h.sent[t] = self.h.sent[r];
        self.h.incident[t] = self.arrived[r];
        self.h.unshot[t] = self.h.unshot[r];
        self.arrived[t] = self.arrived[r];
        self.arrived_sent[t] = self.arrived_sent[r];
    }

    /// Give every hidden twin its representative's subdivision and light, element by element.
    pub(super) fn mirror_twins(&mut self) {
        for k in 0..self.hidden.len() {
            let t = self.hidden[k];
            let mut stack = vec![(self.twin_of[t as usize], t)];
            while let Some((r, t)) = stack.pop() {
                let children = self.h.elements.items[r as usize].children;
                if children != element::NONE {
                    let first = self.new_elements(t);
                    self.arrived.extend([Rgb::BLACK; 4]);
                    self.arrived_sent.extend([Rgb::BLACK; 4]);
                    stack.extend((0..4).map(|c| (children + c, first + c)));
                }
                self.give_twin(t as usize, r as usize);
            }
        }
    }

    pub(super) fn pull_clusters(&mut self, lo: &[f32], hi: &[f32]) {
        let nc = self.h.clusters.nodes.len();
        let mut clo = vec![f32::INFINITY; nc];
        let mut chi = vec![f32::NEG_INFINITY; nc];
        for c in 0..nc {
            let node = self.h.clusters.nodes[c];
            let mut s = Rgb::BLACK;
            for child in node.children {
                let (b, l, h, a) = if child & CLUSTER != 0 {
                    let k = (child & !CLUSTER) as usize;
                    (
                        self.h.cluster_radiosity[k],
                        clo[k],
                        chi[k],
                        self.h.clusters.nodes[k].area,
                    )
                } else {
                    let k = child as usize;
                    (
                        self.h.sent[k],
                        lo[k],
                        hi[k],
                        self.h.elements.items[k].area as f64,
                    )
                };
                s += b * a;
                clo[c] = clo[c].min(l);
                chi[c] = chi[c].max(h);
            }
            self.h.cluster_radiosity[c] = if node.area > 0.0 {
                s / node.area
            } else {
                Rgb::BLACK
            };
            self.cluster_spread[c] = chi[c] - clo[c];
        }
    }
}

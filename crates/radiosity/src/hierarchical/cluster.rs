//! The cluster hierarchy over the root elements: a binary tree built top-down by splitting the
//! centroids at their median along the widest axis, so that every cluster holds a contiguous
//! range of [`Clusters::order`] and a point on its surfaces can be drawn by area with one binary
//! search ([`Clusters::pick`]).

use super::element::Element;
use crate::geom::{Aabb, Vec3};

/// The tag of a node id that names a cluster (the other ids name elements).
pub const CLUSTER: u32 = 1 << 31;

/// A node of the cluster tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cluster {
    /// Bounds of its surfaces.
    pub bounds: Aabb,
    /// Centre of the bounds.
    pub centre: Vec3,
    /// Half the bounds' diagonal.
    pub radius: f32,
    /// Total area of its surfaces.
    pub area: f64,
    /// Its two children: element ids, or cluster indices tagged with [`CLUSTER`].
    pub children: [u32; 2],
    /// Its root elements are `order[first .. first + count]`.
    pub first: u32,
    /// How many root elements it holds.
    pub count: u32,
}

/// The cluster tree. Children are stored before their parents, so a pass in index order
/// visits every cluster after its children.
#[derive(Clone, Debug, Default)]
pub struct Clusters {
    /// The clusters.
    pub nodes: Vec<Cluster>,
    /// Root elements in tree order.
    pub order: Vec<u32>,
    /// Position of each root element in `order`.
    pub position: Vec<u32>,
    /// `cumulative[k]`: the area of `order[..k]` (length `order.len() + 1`).
    pub cumulative: Vec<f64>,
    /// `emitting[k]`: the area of the emitters among `order[..k]` ([`Clusters::with_emitters`];
    /// all zero until then).
    pub emitting: Vec<f64>,
    /// The top node (a tagged cluster, or the one element when there is one).
    pub top: u32,
}

impl Clusters {
    /// The tree over `roots` (the root elements, element id = index).
    pub fn build(roots: &[Element]) -> Clusters {
        let mut c = Clusters {
            order: (0..roots.len() as u32).collect(),
            ..Default::default()
        };
        if roots.is_empty() {
            c.cumulative = vec![0.0];
            return c;
        }
        let mut order = std::mem::take(&mut c.order);
        c.top = c.split(roots, &mut order, 0);
        c.order = order;
        c.position = vec![0; roots.len()];
        for (k, &e) in c.order.iter().enumerate() {
            c.position[e as usize] = k as u32;
        }
        c.cumulative = std::iter::once(0.0)
            .chain(c.order.iter().scan(0.0, |s, &e| {
                *s += roots[e as usize].area as f64;
                Some(*s)
            }))
            .collect();
        c.emitting = vec![0.0; c.cumulative.len()];
        c
    }

    /// Mark which roots emit (`emits[root]`), so that a cluster's surfaces can be drawn
    /// from its emitters and from the rest separately ([`Clusters::pick_in`]).
    pub fn with_emitters(mut self, roots: &[Element], emits: &[bool]) -> Clusters {
        self.emitting = std::iter::once(0.0)
            .chain(self.order.iter().scan(0.0, |s, &e| {
                if emits[e as usize] {
                    *s += roots[e as usize].area as f64;
                }
                Some(*s)
            }))
            .collect();
        self
    }

    /// The area of cluster `c`'s emitters (`emitters`) or of its other surfaces.
    pub fn area_in(&self, c: u32, emitters: bool) -> f64 {
        let n = &self.nodes[c as usize];
        let (lo, hi) = (n.first as usize, (n.first + n.count) as usize);
        let e = self.emitting[hi] - self.emitting[lo];
        if emitters {
            e
        } else {
            (self.cumulative[hi] - self.cumulative[lo] - e).max(0.0)
        }
    }

    /// The root element of cluster `c` under the area fraction `u` in `[0, 1)` of its
    /// emitters (`emitters`) or of its other surfaces: drawn in proportion to their area.
    pub fn pick_in(&self, c: u32, emitters: bool, u: f64) -> u32 {
        let n = &self.nodes[c as usize];
        let (lo, hi) = (n.first as usize, (n.first + n.count) as usize);
        if !emitters && self.emitting[hi] == self.emitting[lo] {
            // No emitter here: the plain area pick (one array to search, not two).
            return self.pick(c, u);
        }
        let at = |k: usize| {
            if emitters {
                self.emitting[k]
            } else {
                self.cumulative[k] - self.emitting[k]
            }
        };
        let target = at(lo) + u * (at(hi) - at(lo));
        // The last k in [lo, hi) with at(k) <= target < at(k + 1), by bisection.
        let (mut a, mut b) = (lo, hi);
        while b - a > 1 {
            let mid = (a + b) / 2;
            if at(mid) <= target {
                a = mid;
            } else {
                b = mid;
            }
        }
        self.order[a]
    }

    fn split(&mut self, roots: &[Element], ids: &mut [u32], first: usize) -> u32 {
        if ids.len() == 1 {
            return ids[0];
        }
        let centres = Aabb::from_points(ids.iter().map(|&e| &roots[e as usize].centre));
        let axis = centres.extent().max_position();
        let mid = ids.len() / 2;
        ids.select_nth_unstable_by(mid, |&a, &b| {
            let (pa, pb) = (
                roots[a as usize].centre[axis],
                roots[b as usize].centre[axis],
            );
            pa.total_cmp(&pb).then(a.cmp(&b))
        });
        let (lo, hi) = ids.split_at_mut(mid);
        let left = self.split(roots, lo, first);
        let right = self.split(roots, hi, first + mid);
        let bounds = ids
            .iter()
            .flat_map(|&e| roots[e as usize].polygon())
            .fold(Aabb::EMPTY, |b, p| b.grow(*p));
        let area = ids.iter().map(|&e| roots[e as usize].area as f64).sum();
        self.nodes.push(Cluster {
            bounds,
            centre: bounds.centre(),
            radius: bounds.diagonal() * 0.5,
            area,
            children: [left, right],
            first: first as u32,
            count: ids.len() as u32,
        });
        (self.nodes.len() - 1) as u32 | CLUSTER
    }

    /// True when cluster `c` holds root element `root`.
    pub fn contains(&self, c: u32, root: u32) -> bool {
        let n = &self.nodes[c as usize];
        let p = self.position[root as usize];
        p >= n.first && p < n.first + n.count
    }

    /// The root element of cluster `c` under the area fraction `u` in `[0, 1)`: root elements
    /// are drawn in proportion to their area.
    pub fn pick(&self, c: u32, u: f64) -> u32 {
        let n = &self.nodes[c as usize];
        let (lo, hi) = (n.first as usize, (n.first + n.count) as usize);
        let target = self.cumulative[lo] + u * (self.cumulative[hi] - self.cumulative[lo]);
        // The last k in [lo, hi) with cumulative[k] <= target.
        let k = lo + self.cumulative[lo + 1..=hi].partition_point(|&s| s <= target);
        self.order[k.min(hi - 1)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hierarchical::element::NONE;

    fn square(x: f32, size: f32) -> Element {
        Element::new(
            [
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + size, 0.0, 0.0),
                Vec3::new(x + size, 0.0, -size),
                Vec3::new(x, 0.0, -size),
            ],
            false,
            0,
            NONE,
            0,
        )
    }

    #[test]
    fn clusters_hold_contiguous_ranges_and_pick_by_area() {
        let roots: Vec<Element> = (0..7)
            .map(|i| square(i as f32 * 3.0, 1.0 + i as f32))
            .collect();
        let c = Clusters::build(&roots);
        assert_eq!(c.nodes.len(), 6);
        let top = &c.nodes[(c.top & !CLUSTER) as usize];
        assert_eq!(top.count, 7);
        let total: f64 = roots.iter().map(|r| r.area as f64).sum();
        assert!((top.area - total).abs() < 1e-9 * total);
        // Children come before parents and partition their parent's range.
        for (i, n) in c.nodes.iter().enumerate() {
            let count = |x: u32| {
                if x & CLUSTER != 0 {
                    assert!(((x & !CLUSTER) as usize) < i);
                    c.nodes[(x & !CLUSTER) as usize].count
                } else {
                    1
                }
            };
            assert_eq!(count(n.children[0]) + count(n.children[1]), n.count);
        }
        // Area-proportional picking: over a fine grid of u, each root's share is its area's.
        let t = c.top & !CLUSTER;
        let mut hits = [0usize; 7];
        let m = 100_000;
        for k in 0..m {
            hits[c.pick(t, (k as f64 + 0.5) / m as f64) as usize] += 1;
        }
        for (i, r) in roots.iter().enumerate() {
            let share = hits[i] as f64 / m as f64;
            assert!((share - r.area as f64 / total).abs() < 1e-4, "{i}: {share}");
            assert!(c.contains(t, i as u32));
        }
        // The two strata: roots 1, 4 and 5 emit; each stratum picks its own roots alone, in
        // proportion to their area, in every cluster.
        let emits = [false, true, false, false, true, true, false];
        let c = c.with_emitters(&roots, &emits);
        for (k, n) in c.nodes.iter().enumerate() {
            for stratum in [true, false] {
                let members: Vec<u32> = c.order[n.first as usize..(n.first + n.count) as usize]
                    .iter()
                    .copied()
                    .filter(|&e| emits[e as usize] == stratum)
                    .collect();
                let area: f64 = members.iter().map(|&e| roots[e as usize].area as f64).sum();
                assert!((c.area_in(k as u32, stratum) - area).abs() < 1e-9 * total);
                if members.is_empty() {
                    continue;
                }
                let mut hits = [0usize; 7];
                for j in 0..m {
                    hits[c.pick_in(k as u32, stratum, (j as f64 + 0.5) / m as f64) as usize] += 1;
                }
                for (i, r) in roots.iter().enumerate() {
                    let share = hits[i] as f64 / m as f64;
                    let want = if members.contains(&(i as u32)) {
                        r.area as f64 / area
                    } else {
                        0.0
                    };
                    assert!((share - want).abs() < 1e-4, "{k} {stratum} {i}: {share}");
                }
            }
        }
    }
}

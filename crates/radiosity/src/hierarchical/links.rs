//! Links and where they are kept: a [`Link`] carries light from a source (an element or a
//! cluster) to a receiving element; the solved [`Hierarchy`] stores the links grouped by
//! receiver, beside the elements, the clusters and the pieces that cluster links saw
//! ([`Hierarchy::cluster_sources`]), and reads what a link gathers
//! ([`Hierarchy::link_radiosity`]).

use super::cluster::{Clusters, CLUSTER};
use super::element::{self, Element, Elements};
use super::params::Info;
use crate::color::Rgb;

/// A link: `receiver` gathers `k · B(source)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Link {
    /// The receiving element.
    pub receiver: u32,
    /// The source: an element id, or a cluster index tagged with [`CLUSTER`].
    pub source: u32,
    /// The form factor from receiver to source.
    pub k: f32,
    /// The oracle's own estimate of it, independent of `k` (so that which links are kept
    /// does not depend on the values they carry); negative for a link kept on the bound
    /// `−k_oracle` from the bounding spheres alone, before any estimate was needed.
    pub k_oracle: f32,
    /// The oracle's kernel uncertainty `K` (see the [`hierarchical`](super) module docs).
    pub uncertainty: f32,
    /// `k` over each of the receiver's four children (their mean is `k`): what is pushed to
    /// each, so that a link at a coarse receiver still lights its parts unevenly where the
    /// kernel varies.
    pub quarters: [f32; 4],
    /// From an element: the share of `k` that each of the source's four children sends
    /// ([`kernel::Estimate::sources`](super::kernel::Estimate::sources)). Once the source is
    /// split, the link gathers from its children in these shares (each child's share weighted
    /// by its exposed fraction), not from their mean: a coarse link then still sees the bright
    /// or dark part of its source that faces it.
    pub sources: [f32; 4],
    /// From a cluster: the range of [`Hierarchy::cluster_sources`] that holds the root pieces
    /// the link's samples saw from the receiver, and the share of `k` that each sends.
    pub seen: [u32; 2],
}

/// A solved hierarchy.
#[derive(Clone, Debug)]
pub struct Hierarchy {
    /// Every element (roots first: root `i` is piece `i` of the input mesh).
    pub elements: Elements,
    /// The clusters.
    pub clusters: Clusters,
    /// The links, grouped by receiver.
    pub links: Vec<Link>,
    /// Radiosity of each element (the area mean of its leaves).
    pub radiosity: Vec<Rgb>,
    /// What the last iteration changed at each element (leaves: not yet gathered light).
    pub unshot: Vec<Rgb>,
    /// What arrived at each element per unit area (`H`, with B = E + ρ H at a leaf): through
    /// its own links and its ancestors'.
    pub incident: Vec<Rgb>,
    /// Radiosity of each cluster (the area mean of its surfaces).
    pub cluster_radiosity: Vec<Rgb>,
    /// The root pieces that cluster links saw, with their shares ([`Link::seen`]).
    pub cluster_sources: Vec<(u32, f32)>,
    /// Each root's emission and that of the coincident twins it stands for: what it sends
    /// beside its reflected light.
    pub group_emission: Vec<Rgb>,
    /// What each element sends: the mean of its children's weighted by their exposed area; at
    /// a leaf, its emission plus the light its exposed part reflects (what arrives divided by
    /// the exposed fraction, since the leaf's covered points gather nothing).
    pub sent: Vec<Rgb>,
    /// Exposed fraction of each element
    /// ([`kernel::Cover::exposed`](super::kernel::Cover::exposed)).
    pub exposure: Vec<f32>,
    /// Each root's coincident-twin representative ([`Element::twins`]), itself when it has
    /// none. A twin is the same surface as its representative: it takes the same light and
    /// subdivision, and sends nothing of its own.
    pub twin_of: Vec<u32>,
    /// The report.
    pub info: Info,
}

impl Hierarchy {
    /// The leaf elements, tree by tree, depth first.
    pub fn leaves(&self) -> Vec<u32> {
        let mut out = Vec::new();
        for r in 0..self.elements.roots as u32 {
            self.elements.leaves_below(r, &mut out);
        }
        out
    }

    /// The radiosity a link gathers: what its source element sends (from a split source,
    /// its children's by the link's [`Link::sources`] shares), or from a source cluster, what
    /// the pieces its samples saw send, in their shares ([`Link::seen`]).
    pub fn link_radiosity(&self, l: &Link) -> Rgb {
        if l.source & CLUSTER == 0 {
            let s = l.source as usize;
            let first = self.elements.items[s].children;
            if first == element::NONE {
                return self.sent[s];
            }
            let (mut b, mut w) = (Rgb::BLACK, 0.0);
            for (q, share) in l.sources.iter().enumerate() {
                let c = first as usize + q;
                let wq = *share as f64 * self.exposure[c] as f64;
                b += self.sent[c] * wq;
                w += wq;
            }
            return if w > 0.0 { b / w } else { self.sent[s] };
        }
        let seen = &self.cluster_sources[l.seen[0] as usize..l.seen[1] as usize];
        if seen.is_empty() {
            // Nothing seen: the link carries nothing (k = 0).
            return self.cluster_radiosity[(l.source & !CLUSTER) as usize];
        }
        seen.iter()
            .map(|&(p, share)| self.sent[p as usize] * share as f64)
            .sum()
    }
}

/// Bytes a link and an element hold (with their per-element solution vectors).
pub(super) const LINK_BYTES: u64 = std::mem::size_of::<Link>() as u64;
pub(super) const ELEMENT_BYTES: u64 = std::mem::size_of::<Element>() as u64 + 4 * 24 + 8;

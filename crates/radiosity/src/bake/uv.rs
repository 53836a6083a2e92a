//! The second UV set of a lightmap: charts that follow the geometry, packed into one or more
//! atlases at a uniform texel density.
//!
//! **Charts.** The triangles and convex quads of the scene's pieces ([`MeshParams::Faces`]) are
//! joined into a chart when they share an edge (both end points at the same position), have
//! the same material, and lie in one plane (normals within [`COPLANAR_COS`], plane offsets
//! within [`COPLANAR_OFFSET`] of the scene's diagonal). A chart is projected orthogonally onto
//! its plane, so its stretch is exactly 1 in every direction: every texel covers `L × L` of the
//! surface, with `L` the texel size. Its in-plane axes are the direction of its longest edge
//! and the normal's cross product with it, swapped so that the chart lies wider than tall.
//!
//! **Packing.** Each chart is a rectangle of `⌈extent / L⌉` texels plus [`PADDING`] texels on
//! every side (so that bilinear filtering near a chart's border reads only that chart's
//! dilated texels, [`super::lightmap`]). Rectangles are packed by shelves (sorted by height,
//! laid left to right, a new shelf when a row is full; Igarashi & Cosgrove's "next fit
//! decreasing height"), into a given width. For a fixed atlas size the texel size is the
//! smallest (found by bisection) whose packing fits.
//!
//! **Several atlases.** When the charts at a given texel size do not fit one atlas of the
//! given side ([`Density::Both`]), or of [`MAX_ATLAS`] for a texel size alone, the shelves
//! continue into a second atlas of the same side, and so on ([`Chart::atlas`]): a shelf that
//! would cross the atlas's bottom starts the next one. The charts' order and sizes do not
//! depend on where they land, so a chart's texels are the same in one atlas or in several.

use crate::geom::{Aabb, Vec3};
use crate::mesh::{Mesh, MeshParams};
use crate::scene::{Scene, SceneError};
use std::collections::HashMap;

/// Texels of padding on each side of a chart.
pub const PADDING: u32 = 2;

/// Cosine of the largest angle between two faces' normals that still counts as one plane.
pub const COPLANAR_COS: f32 = 0.999_99;

/// Largest difference of two faces' plane offsets, over the scene's diagonal, that still counts
/// as one plane.
pub const COPLANAR_OFFSET: f32 = 1e-5;

/// Largest atlas side, texels (what GPUs sample; 16384 is the common limit).
pub const MAX_ATLAS: u32 = 16_384;

/// One chart: faces of one plane, their projection, and where it lies in the atlas.
#[derive(Clone, Debug)]
pub struct Chart {
    /// The faces ([`Unwrap::mesh`] patches) in the chart.
    pub faces: Vec<u32>,
    /// The material of its faces.
    pub material: u32,
    /// Unit normal of its plane (front side).
    pub normal: Vec3,
    /// Plane point at chart texel coordinates `(PADDING, PADDING)`.
    pub origin: Vec3,
    /// Unit in-plane axis along the atlas's x.
    pub axis_u: Vec3,
    /// Unit in-plane axis along the atlas's y.
    pub axis_v: Vec3,
    /// Extent along `axis_u` and `axis_v`, scene units.
    pub extent: [f32; 2],
    /// The atlas it lies in (0 when there is one).
    pub atlas: u32,
    /// Its rectangle's first texel column and row in its atlas.
    pub x0: u32,
    /// See `x0`.
    pub y0: u32,
    /// Its rectangle's width and height in texels, padding included.
    pub width: u32,
    /// See `width`.
    pub height: u32,
}

impl Chart {
    /// Chart texel coordinates (continuous: texel `(i, j)` covers `[i, i+1) × [j, j+1)`) of a
    /// point of its plane, at texel size `texel`.
    pub fn texel_coords(&self, p: Vec3, texel: f32) -> [f32; 2] {
        let d = p - self.origin;
        [
            d.dot(self.axis_u) / texel + PADDING as f32,
            d.dot(self.axis_v) / texel + PADDING as f32,
        ]
    }

    /// The plane point at chart texel coordinates `s`.
    pub fn point(&self, s: [f32; 2], texel: f32) -> Vec3 {
        self.origin
            + self.axis_u * ((s[0] - PADDING as f32) * texel)
            + self.axis_v * ((s[1] - PADDING as f32) * texel)
    }
}

/// A scene's faces with their second UV set.
#[derive(Clone, Debug)]
pub struct Unwrap {
    /// The faces: one patch per piece of each input polygon (triangles and convex quads).
    pub mesh: Mesh,
    /// The charts, in packing order.
    pub charts: Vec<Chart>,
    /// The chart of each face.
    pub chart_of: Vec<u32>,
    /// Texel size, scene units.
    pub texel: f32,
    /// Width and height of each atlas, texels (all atlases have the same).
    pub width: u32,
    /// See `width`.
    pub height: u32,
    /// How many atlases the charts fill (1 unless they did not fit one).
    pub atlases: u32,
    /// `TEXCOORD_1` of each [`Unwrap::mesh`] vertex, in `[0, 1]²` of the atlas of its chart
    /// (glTF: `(0, 0)` is the image's top-left corner).
    pub uv: Vec<[f32; 2]>,
}

impl Unwrap {
    /// The atlas of a face ([`Unwrap::mesh`] patch).
    pub fn atlas_of(&self, face: u32) -> u32 {
        self.charts[self.chart_of[face as usize] as usize].atlas
    }
}

/// How the atlas's density is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Density {
    /// Texels of this size (scene units); the atlas as large as they need, several of
    /// [`MAX_ATLAS`] a side when one that large does not hold them.
    TexelSize(f32),
    /// The finest density whose atlas fits this many texels a side.
    AtlasSize(u32),
    /// Texels of this size in atlases of this side: as many as they need.
    Both(f32, u32),
}

/// Why the charts could not be made or packed.
#[derive(Debug, thiserror::Error)]
pub enum UnwrapError {
    /// An atlas side of 0 or above [`MAX_ATLAS`].
    #[error("atlas size {0}: must be 1 to {MAX_ATLAS} texels")]
    AtlasSize(u32),
    /// A texel size that is not a positive finite length.
    #[error("texel size {0}: must be a positive length")]
    TexelSize(f32),
    /// Nothing to map: no face with area.
    #[error("the scene has no surface with area to map")]
    NoArea,
    /// The charts (or one chart alone) need a larger atlas than allowed.
    #[error(
        "at texel size {texel} the charts need an atlas of {need} texels a side, more than {limit}"
    )]
    TooLarge {
        /// Texel size tried.
        texel: f32,
        /// Side the packing needed.
        need: u32,
        /// Side allowed.
        limit: u32,
    },
    /// The scene's faces could not be cut.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The input's own UV set cannot be kept ([`super::given`]).
    #[error("the input's TEXCOORD_1: {0}")]
    Given(String),
}

/// Chart the scene's faces and pack them at `density`.
pub fn unwrap(scene: &Scene, density: Density) -> Result<Unwrap, UnwrapError> {
    match density {
        Density::AtlasSize(n) | Density::Both(_, n) if n == 0 || n > MAX_ATLAS => {
            return Err(UnwrapError::AtlasSize(n))
        }
        Density::TexelSize(l) | Density::Both(l, _) if !(l.is_finite() && l > 0.0) => {
            return Err(UnwrapError::TexelSize(l))
        }
        _ => {}
    }
    let mesh = Mesh::build(scene, MeshParams::Faces)?;
    let area: f64 = mesh.patches.iter().map(|p| p.area as f64).sum();
    if mesh.is_empty() || area.is_nan() || area <= 0.0 {
        return Err(UnwrapError::NoArea);
    }
    let mut charts = charts(&mesh);
    let (texel, width, height, atlases) = match density {
        Density::TexelSize(l) => {
            let (w, h) = pack_square(&mut charts, l);
            if w.max(h) > MAX_ATLAS {
                let atlases = pack_atlases(&mut charts, l, MAX_ATLAS)?;
                (l, MAX_ATLAS, MAX_ATLAS, atlases)
            } else {
                (l, w, h, 1)
            }
        }
        Density::Both(l, n) => {
            let atlases = pack_atlases(&mut charts, l, n)?;
            (l, n, n, atlases)
        }
        Density::AtlasSize(n) => {
            // Bisection on the texel size between one that cannot fit (area alone) and one
            // that surely does (the largest chart's extent over a texel or two).
            let mut lo = (area / (n as f64 * n as f64)).sqrt() as f32;
            let diag = Aabb::from_points(mesh.vertices.iter())
                .diagonal()
                .max(1e-30);
            let mut hi = diag.max(lo * 2.0);
            if pack(&mut charts, hi, n) > n {
                // Even one texel a chart does not fit: too many charts for this atlas.
                let need = (charts.len() as f64).sqrt().ceil() as u32 * (2 * PADDING + 2);
                return Err(UnwrapError::TooLarge {
                    texel: hi,
                    need,
                    limit: n,
                });
            }
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if pack(&mut charts, mid, n) <= n {
                    hi = mid;
                } else {
                    lo = mid;
                }
                if hi - lo <= 1e-4 * hi {
                    break;
                }
            }
            pack(&mut charts, hi, n);
            (hi, n, n, 1)
        }
    };
    let mut chart_of = vec![0u32; mesh.len()];
    let mut uv = vec![[0.0f32; 2]; mesh.vertices.len()];
    for (c, chart) in charts.iter().enumerate() {
        for &f in &chart.faces {
            chart_of[f as usize] = c as u32;
            let p = &mesh.patches[f as usize];
            for &v in p.vertices.iter().take(if p.is_triangle() { 3 } else { 4 }) {
                let s = chart.texel_coords(mesh.vertices[v as usize], texel);
                uv[v as usize] = [
                    (chart.x0 as f32 + s[0]) / width as f32,
                    (chart.y0 as f32 + s[1]) / height as f32,
                ];
            }
        }
    }
    Ok(Unwrap {
        mesh,
        charts,
        chart_of,
        texel,
        width,
        height,
        atlases,
        uv,
    })
}

/// Union–find root with path halving.
fn root(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        parent[i as usize] = parent[parent[i as usize] as usize];
        i = parent[i as usize];
    }
    i
}

/// The faces joined into planar charts, each with its plane frame (not yet placed).
fn charts(mesh: &Mesh) -> Vec<Chart> {
    let n = mesh.len();
    let diag = Aabb::from_points(mesh.vertices.iter())
        .diagonal()
        .max(1e-30);
    let key = |p: Vec3| {
        [
            (p.x + 0.0).to_bits(),
            (p.y + 0.0).to_bits(),
            (p.z + 0.0).to_bits(),
        ]
    };
    let mut parent: Vec<u32> = (0..n as u32).collect();
    // Each edge, by its ends' positions in order, to the first face that has it.
    let mut edges: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::with_capacity(n * 4);
    for (f, p) in mesh.patches.iter().enumerate() {
        if p.area.is_nan() || p.area <= 0.0 {
            continue;
        }
        let m = if p.is_triangle() { 3 } else { 4 };
        for k in 0..m {
            let a = key(mesh.vertices[p.vertices[k] as usize]);
            let b = key(mesh.vertices[p.vertices[(k + 1) % m] as usize]);
            let e = if a < b { (a, b) } else { (b, a) };
            match edges.get(&e) {
                None => {
                    edges.insert(e, f as u32);
                }
                Some(&g) => {
                    let q = &mesh.patches[g as usize];
                    let same_plane = q.material == p.material
                        && q.normal.dot(p.normal) >= COPLANAR_COS
                        && (p.normal.dot(q.centre - p.centre)).abs() <= COPLANAR_OFFSET * diag;
                    if same_plane {
                        let (ra, rb) = (root(&mut parent, f as u32), root(&mut parent, g));
                        if ra != rb {
                            parent[ra.max(rb) as usize] = ra.min(rb);
                        }
                    }
                }
            }
        }
    }
    let mut index = vec![u32::MAX; n];
    let mut out: Vec<Chart> = Vec::new();
    for f in 0..n as u32 {
        if mesh.patches[f as usize].area.is_nan() || mesh.patches[f as usize].area <= 0.0 {
            continue;
        }
        let r = root(&mut parent, f) as usize;
        if index[r] == u32::MAX {
            index[r] = out.len() as u32;
            let p = &mesh.patches[r];
            out.push(Chart {
                faces: Vec::new(),
                material: p.material,
                atlas: 0,
                normal: p.normal,
                origin: Vec3::ZERO,
                axis_u: Vec3::ZERO,
                axis_v: Vec3::ZERO,
                extent: [0.0; 2],
                x0: 0,
                y0: 0,
                width: 0,
                height: 0,
            });
        }
        out[index[r] as usize].faces.push(f);
    }
    for c in &mut out {
        frame(mesh, c);
    }
    out
}

/// A chart's plane frame: axes along its longest edge, origin at the minimum corner.
fn frame(mesh: &Mesh, c: &mut Chart) {
    // The normal: area-weighted over the faces.
    let n = c
        .faces
        .iter()
        .map(|&f| mesh.patches[f as usize].normal * mesh.patches[f as usize].area)
        .sum::<Vec3>()
        .normalize_or_zero();
    let n = if n == Vec3::ZERO { c.normal } else { n };
    let (mut longest, mut dir) = (0.0f32, Vec3::ZERO);
    for &f in &c.faces {
        let p = &mesh.patches[f as usize];
        let m = if p.is_triangle() { 3 } else { 4 };
        for k in 0..m {
            let e = mesh.vertices[p.vertices[(k + 1) % m] as usize]
                - mesh.vertices[p.vertices[k] as usize];
            let e = e - n * n.dot(e);
            if e.length() > longest {
                longest = e.length();
                dir = e / longest;
            }
        }
    }
    if longest == 0.0 {
        dir = crate::geom::orthonormal_basis(n).0;
    }
    let mut u = dir;
    let mut v = n.cross(u).normalize_or_zero();
    let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
    for &f in &c.faces {
        let p = &mesh.patches[f as usize];
        for &k in p.vertices.iter().take(if p.is_triangle() { 3 } else { 4 }) {
            let q = mesh.vertices[k as usize];
            let s = [q.dot(u), q.dot(v)];
            for a in 0..2 {
                lo[a] = lo[a].min(s[a]);
                hi[a] = hi[a].max(s[a]);
            }
        }
    }
    let mut extent = [hi[0] - lo[0], hi[1] - lo[1]];
    let mut corner = [lo[0], lo[1]];
    if extent[1] > extent[0] {
        std::mem::swap(&mut u, &mut v);
        extent.swap(0, 1);
        corner.swap(0, 1);
    }
    // The plane point of the minimum corner: its in-plane coordinates, and the offset along n.
    let plane = mesh.patches[c.faces[0] as usize].centre.dot(n);
    c.normal = n;
    c.axis_u = u;
    c.axis_v = v;
    c.extent = extent;
    c.origin = u * corner[0] + v * corner[1] + n * plane;
}

/// The rectangle of a chart at texel size `l`, padding included.
fn size(c: &Chart, l: f32) -> (u32, u32) {
    let t = |e: f32| ((e / l).ceil() as u64).clamp(1, 1 << 40) + 2 * PADDING as u64;
    let (w, h) = (t(c.extent[0]), t(c.extent[1]));
    (
        w.min(u32::MAX as u64 / 4) as u32,
        h.min(u32::MAX as u64 / 4) as u32,
    )
}

/// Shelf packing into `width` texels: places every chart (sorted by height, tallest first) and
/// returns the height used (above `width` when a chart is wider than the atlas).
fn pack(charts: &mut [Chart], l: f32, width: u32) -> u32 {
    for c in charts.iter_mut() {
        (c.width, c.height) = size(c, l);
    }
    charts.sort_by(|a, b| b.height.cmp(&a.height).then(b.width.cmp(&a.width)));
    let (mut x, mut y, mut shelf) = (0u64, 0u64, 0u64);
    let mut too_wide = false;
    for c in charts.iter_mut() {
        if c.width > width {
            too_wide = true;
        }
        if x + c.width as u64 > width as u64 && x > 0 {
            y += shelf;
            x = 0;
            shelf = 0;
        }
        c.atlas = 0;
        c.x0 = x as u32;
        c.y0 = y.min(u32::MAX as u64) as u32;
        x += c.width as u64;
        shelf = shelf.max(c.height as u64);
    }
    let h = (y + shelf).min(u32::MAX as u64 / 2) as u32;
    if too_wide {
        h.max(width + 1)
    } else {
        h
    }
}

/// Shelf packing into atlases of `n × n` texels, as [`pack`] but a shelf that would cross an
/// atlas's bottom starts the next atlas; the number of atlases used. An error when a chart
/// alone is larger than an atlas.
fn pack_atlases(charts: &mut [Chart], l: f32, n: u32) -> Result<u32, UnwrapError> {
    for c in charts.iter_mut() {
        (c.width, c.height) = size(c, l);
    }
    charts.sort_by(|a, b| b.height.cmp(&a.height).then(b.width.cmp(&a.width)));
    if let Some(c) = charts.iter().find(|c| c.width.max(c.height) > n) {
        return Err(UnwrapError::TooLarge {
            texel: l,
            need: c.width.max(c.height),
            limit: n,
        });
    }
    let (mut atlas, mut x, mut y, mut shelf) = (0u32, 0u32, 0u32, 0u32);
    for c in charts.iter_mut() {
        if x + c.width > n && x > 0 {
            y += shelf;
            x = 0;
            shelf = 0;
        }
        if y + c.height > n {
            atlas += 1;
            (x, y, shelf) = (0, 0, 0);
        }
        c.atlas = atlas;
        c.x0 = x;
        c.y0 = y;
        x += c.width;
        shelf = shelf.max(c.height);
    }
    Ok(atlas + 1)
}

/// Packing for a texel size alone: a width near the square root of the charts' total area (at
/// least the widest chart), the height what the shelves use.
fn pack_square(charts: &mut [Chart], l: f32) -> (u32, u32) {
    let mut total = 0u64;
    let mut widest = 0u32;
    for c in charts.iter() {
        let (w, h) = size(c, l);
        total += w as u64 * h as u64;
        widest = widest.max(w);
    }
    let mut w = ((total as f64 * 1.1).sqrt().ceil() as u64).max(widest as u64);
    w = w.div_ceil(4) * 4;
    let w = w.min(u32::MAX as u64 / 2) as u32;
    let h = pack(charts, l, w).max(1);
    (w, h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    /// Every face's vertices map inside its chart's rectangle (padding kept), rectangles do not
    /// overlap, and the texel size is uniform: each face's area in texels is its area over L².
    #[test]
    fn charts_are_isometric_and_disjoint() {
        let scene = builtin::cornell();
        let u = unwrap(&scene, Density::AtlasSize(256)).unwrap();
        assert!(u.width == 256 && u.height == 256);
        for (f, p) in u.mesh.patches.iter().enumerate() {
            let c = &u.charts[u.chart_of[f] as usize];
            let m = if p.is_triangle() { 3 } else { 4 };
            let q: Vec<[f32; 2]> = p.vertices[..m]
                .iter()
                .map(|&v| {
                    let t = u.uv[v as usize];
                    [t[0] * u.width as f32, t[1] * u.height as f32]
                })
                .collect();
            for t in &q {
                assert!(t[0] >= (c.x0 + PADDING) as f32 - 1e-3);
                assert!(t[0] <= (c.x0 + c.width - PADDING) as f32 + 1e-3);
                assert!(t[1] >= (c.y0 + PADDING) as f32 - 1e-3);
                assert!(t[1] <= (c.y0 + c.height - PADDING) as f32 + 1e-3);
            }
            // Shoelace area in texels against the face's area.
            let mut a = 0.0f32;
            for k in 0..m {
                let (s, t) = (q[k], q[(k + 1) % m]);
                a += s[0] * t[1] - t[0] * s[1];
            }
            let want = p.area / (u.texel * u.texel);
            assert!(
                (a.abs() * 0.5 - want).abs() <= 1e-3 * want + 1e-2,
                "{a} vs {want}"
            );
        }
        for (i, a) in u.charts.iter().enumerate() {
            for b in &u.charts[i + 1..] {
                let apart = a.x0 + a.width <= b.x0
                    || b.x0 + b.width <= a.x0
                    || a.y0 + a.height <= b.y0
                    || b.y0 + b.height <= a.y0;
                assert!(apart, "charts overlap");
            }
            assert!(a.x0 + a.width <= u.width && a.y0 + a.height <= u.height);
        }
        // The Cornell box's faces are planar quads: one chart per polygon face of a wall or
        // block side (the walls meet at right angles, so none join).
        assert_eq!(u.charts.len(), u.mesh.len());
    }

    /// A fixed texel size packs into an atlas about as large as the charts' area; bad sizes are
    /// refused.
    #[test]
    fn texel_size_and_bad_sizes() {
        let scene = builtin::cornell();
        let u = unwrap(&scene, Density::TexelSize(5.0)).unwrap();
        let used: u64 = u
            .charts
            .iter()
            .map(|c| c.width as u64 * c.height as u64)
            .sum();
        assert!(used as f64 >= 0.5 * (u.width as f64 * u.height as f64));
        assert!(matches!(
            unwrap(&scene, Density::AtlasSize(0)),
            Err(UnwrapError::AtlasSize(0))
        ));
        assert!(matches!(
            unwrap(&scene, Density::AtlasSize(1_000_000)),
            Err(UnwrapError::AtlasSize(1_000_000))
        ));
        assert!(matches!(
            unwrap(&scene, Density::TexelSize(1e-6)),
            Err(UnwrapError::TooLarge { .. })
        ));
        assert!(matches!(
            unwrap(&scene, Density::TexelSize(f32::NAN)),
            Err(UnwrapError::TexelSize(_))
        ));
    }
}

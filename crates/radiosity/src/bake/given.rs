//! A lightmap on the input's own UV set (an existing `TEXCOORD_1`), kept instead of generated.
//!
//! **Faces and UVs.** The faces are the scene's triangles ([`MeshParams::Faces`]: one face a
//! triangle, each mesh vertex given the UV of the polygon corner at its position). Nothing is
//! projected or packed: a texel belongs to the face whose UV triangle holds its centre (or
//! touches its square), and its surface point is the face's point with those barycentric
//! coordinates, so any UV layout works, stretched or not.
//!
//! **Atlas size.** One atlas (a kept UV set is one texture's coordinates). The side `N` is `--lightmap-size` when given; from a texel size `L` alone
//! it is `⌈√(A / a) / L⌉`, with `A` the faces' area and `a` their UV area (as a share of the
//! unit square), so that the mean texel covers `L × L`; with both, `N` must hold that density.
//! [`Unwrap::texel`] is then the mean texel size `√(A / a) / N`.
//!
//! **Charts** are the faces joined where they share an edge whose ends have the same position
//! and the same UVs (an island of the UV set); each is the rectangle around its UVs plus
//! [`PADDING`] texels, clipped to the atlas. Dilation and the indirect records stay within a
//! chart ([`super::lightmap`]). An island closer than [`PADDING`] texels to another may have
//! its padding averaged with the other's, as in any baker given too little gutter.
//!
//! **Bounds.** A UV set that overlaps itself heavily (rectangles or triangles whose bounding
//! boxes cover the atlas more than [`MAX_COVER`] times) is refused before any texel is
//! rasterised: a lightmap needs each texel on one surface, and the work would be unbounded.

use super::uv::{Chart, Density, Unwrap, UnwrapError, MAX_ATLAS, PADDING};
use crate::geom::Vec3;
use crate::mesh::{Mesh, MeshParams};
use crate::scene::Scene;
use std::collections::HashMap;

/// Most times the charts' rectangles (and, separately, the faces' UV bounding boxes, in
/// texels) may cover the atlas.
pub const MAX_COVER: u64 = 16;

/// The corner of `corners` nearest to `p`.
fn nearest(corners: &[Vec3], p: Vec3) -> usize {
    let mut best = (0, f32::INFINITY);
    for (j, q) in corners.iter().enumerate() {
        let d = q.distance_squared(p);
        if d < best.1 {
            best = (j, d);
        }
    }
    best.0
}

/// Union–find root with path halving.
fn root(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        parent[i as usize] = parent[parent[i as usize] as usize];
        i = parent[i as usize];
    }
    i
}

/// The unwrap of `scene` on its own UV set: `corners[i]` the UVs at the three corners of
/// polygon `i` (every polygon a triangle), at `density`.
pub fn unwrap_given(
    scene: &Scene,
    density: Density,
    corners: &[[[f32; 2]; 3]],
) -> Result<Unwrap, UnwrapError> {
    let given = |m: String| UnwrapError::Given(m);
    match density {
        Density::AtlasSize(n) | Density::Both(_, n) if n == 0 || n > MAX_ATLAS => {
            return Err(UnwrapError::AtlasSize(n))
        }
        Density::TexelSize(l) | Density::Both(l, _) if !(l.is_finite() && l > 0.0) => {
            return Err(UnwrapError::TexelSize(l))
        }
        _ => {}
    }
    if corners.len() != scene.polygons.len() {
        return Err(given(format!(
            "{} corner sets for {} polygons",
            corners.len(),
            scene.polygons.len()
        )));
    }
    if let Some(i) = scene.polygons.iter().position(|p| p.vertices.len() != 3) {
        return Err(given(format!(
            "polygon {i} has {} vertices; a kept UV set needs triangles",
            scene.polygons[i].vertices.len()
        )));
    }
    if corners.iter().flatten().flatten().any(|x| !x.is_finite()) {
        return Err(given("a UV is not finite".into()));
    }
    let mesh = Mesh::build(scene, MeshParams::Faces)?;
    let area: f64 = mesh.patches.iter().map(|p| p.area as f64).sum();
    if mesh.is_empty() || area.is_nan() || area <= 0.0 {
        return Err(UnwrapError::NoArea);
    }
    let mut uv = vec![[0.0f32; 2]; mesh.vertices.len()];
    let mut uv_area = 0.0f64;
    for p in &mesh.patches {
        if !p.is_triangle() {
            return Err(given("a face is not a triangle".into()));
        }
        let poly = &scene.polygons[p.surface as usize];
        let c = &corners[p.surface as usize];
        for &v in &p.vertices[..3] {
            uv[v as usize] = c[nearest(&poly.vertices, mesh.vertices[v as usize])];
        }
        let [a, b, d] = [0, 1, 2].map(|k| uv[p.vertices[k] as usize]);
        uv_area += 0.5
            * ((b[0] - a[0]) as f64 * (d[1] - a[1]) as f64
                - (d[0] - a[0]) as f64 * (b[1] - a[1]) as f64)
                .abs();
    }
    if !(uv_area > 0.0 && uv_area.is_finite()) {
        return Err(given("the UV set has no area".into()));
    }
    // Surface length a unit of UV stands for.
    let unit = (area / uv_area).sqrt();
    let side_for = |l: f32| (unit / l as f64).ceil().clamp(1.0, 1e12) as u64;
    let n = match density {
        Density::AtlasSize(n) => n,
        Density::TexelSize(l) => {
            let need = side_for(l);
            if need > MAX_ATLAS as u64 {
                return Err(UnwrapError::TooLarge {
                    texel: l,
                    need: need.min(u32::MAX as u64) as u32,
                    limit: MAX_ATLAS,
                });
            }
            need as u32
        }
        Density::Both(l, n) => {
            let need = side_for(l);
            if need > n as u64 {
                return Err(UnwrapError::TooLarge {
                    texel: l,
                    need: need.min(u32::MAX as u64) as u32,
                    limit: n,
                });
            }
            n
        }
    };
    let nf = n as f64;
    // Charts: faces sharing an edge with equal positions and UVs at both ends.
    let key = |v: u32| {
        let (p, t) = (mesh.vertices[v as usize], uv[v as usize]);
        [
            (p.x + 0.0).to_bits(),
            (p.y + 0.0).to_bits(),
            (p.z + 0.0).to_bits(),
            (t[0] + 0.0).to_bits(),
            (t[1] + 0.0).to_bits(),
        ]
    };
    let faces = mesh.len();
    let mut parent: Vec<u32> = (0..faces as u32).collect();
    let mut edges: HashMap<([u32; 5], [u32; 5]), u32> = HashMap::with_capacity(faces * 3);
    for (f, p) in mesh.patches.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (key(p.vertices[k]), key(p.vertices[(k + 1) % 3]));
            let e = if a < b { (a, b) } else { (b, a) };
            match edges.get(&e) {
                None => {
                    edges.insert(e, f as u32);
                }
                Some(&g) => {
                    let (ra, rb) = (root(&mut parent, f as u32), root(&mut parent, g));
                    if ra != rb {
                        parent[ra.max(rb) as usize] = ra.min(rb);
                    }
                }
            }
        }
    }
    let mut index = vec![u32::MAX; faces];
    let mut charts: Vec<Chart> = Vec::new();
    let mut chart_of = vec![0u32; faces];
    let mut lo: Vec<[f64; 2]> = Vec::new();
    let mut hi: Vec<[f64; 2]> = Vec::new();
    let mut face_boxes = 0u64;
    for f in 0..faces {
        let r = root(&mut parent, f as u32) as usize;
        if index[r] == u32::MAX {
            index[r] = charts.len() as u32;
            let p = &mesh.patches[r];
            charts.push(Chart {
                faces: Vec::new(),
                material: p.material,
                normal: Vec3::ZERO,
                origin: Vec3::ZERO,
                axis_u: Vec3::ZERO,
                axis_v: Vec3::ZERO,
                extent: [0.0; 2],
                atlas: 0,
                x0: 0,
                y0: 0,
                width: 0,
                height: 0,
            });
            lo.push([f64::INFINITY; 2]);
            hi.push([f64::NEG_INFINITY; 2]);
        }
        let c = index[r] as usize;
        chart_of[f] = c as u32;
        let p = &mesh.patches[f];
        charts[c].faces.push(f as u32);
        charts[c].normal += p.normal * p.area;
        let (mut flo, mut fhi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for &v in &p.vertices[..3] {
            for a in 0..2 {
                let t = uv[v as usize][a] as f64 * nf;
                flo[a] = flo[a].min(t);
                fhi[a] = fhi[a].max(t);
            }
        }
        for a in 0..2 {
            lo[c][a] = lo[c][a].min(flo[a]);
            hi[c][a] = hi[c][a].max(fhi[a]);
        }
        // The rasteriser's box: one texel more each side, clipped to the atlas.
        let span = |a: usize| {
            let x0 = (flo[a] - 1.0).floor().clamp(0.0, nf);
            let x1 = (fhi[a] + 1.0).ceil().clamp(0.0, nf);
            (x1 - x0).max(0.0) as u64
        };
        face_boxes = face_boxes.saturating_add(span(0) * span(1));
    }
    let mut rects = 0u64;
    for (c, chart) in charts.iter_mut().enumerate() {
        chart.normal = chart.normal.normalize_or_zero();
        let pad = PADDING as f64;
        let x0 = (lo[c][0].floor() - pad).clamp(0.0, nf) as u32;
        let y0 = (lo[c][1].floor() - pad).clamp(0.0, nf) as u32;
        let x1 = (hi[c][0].ceil() + pad).clamp(0.0, nf) as u32;
        let y1 = (hi[c][1].ceil() + pad).clamp(0.0, nf) as u32;
        chart.x0 = x0.min(n - 1);
        chart.y0 = y0.min(n - 1);
        chart.width = x1.saturating_sub(chart.x0);
        chart.height = y1.saturating_sub(chart.y0);
        rects = rects.saturating_add(chart.width as u64 * chart.height as u64);
    }
    let atlas = nf as u64 * nf as u64;
    for (what, total) in [("islands' rectangles", rects), ("triangles", face_boxes)] {
        if total > MAX_COVER * atlas + (1 << 20) {
            return Err(given(format!(
                "its {what} cover the {n} × {n} atlas {:.0} times (at most {MAX_COVER}): the UV set overlaps itself, and a lightmap needs each texel on one surface",
                total as f64 / atlas as f64
            )));
        }
    }
    Ok(Unwrap {
        mesh,
        charts,
        chart_of,
        texel: (unit / nf) as f32,
        width: n,
        height: n,
        atlases: 1,
        uv,
    })
}

//! Lightmap texels: the radiosity `B` where each texel lies on the surface, by the final
//! gather ([`crate::render::gather`]), then dilation into the padding.
//!
//! **Where a texel lies.** Each chart's triangles are rasterised into its texel grid
//! ([`super::uv`]). A texel whose centre is inside a triangle is evaluated at its centre; one
//! whose centre is outside every triangle but whose square touches one (centre within half a
//! texel diagonal) is evaluated at the closest point of that triangle, moved a thousandth of a
//! texel inwards: never at a point off the surface, which is how light leaks into contact
//! corners. The rest is padding, filled by dilation.
//!
//! **The value.** At the point x (normal n, material ρ, E):
//!
//! ```text
//! B(x) = E + ρ (H_direct(x) + H_indirect(x))
//! ```
//!
//! `H_direct` the sampled emitters' irradiance by [`LightmapParams::direct`] shadow rays a
//! texel (exact visibility: shadows as sharp as the texel), `H_indirect` the solution's
//! reflected light gathered by [`LightmapParams::indirect`] sample pairs
//! ([`Gather::irradiance_parts`]). The indirect irradiance varies slowly, so it is gathered at
//! *records*, every [`LightmapParams::spacing`]-th texel of a chart in each direction, and
//! interpolated bilinearly between the four records around a texel, each record's weight
//! kept only when a ray between the two points (lifted off the plane) is unblocked and the
//! record is not covered: no indirect light is carried through a wall standing on the chart.
//! A texel with no usable record gathers its own.
//!
//! **Covered texels** follow the covered-point rules of the radiosity gather
//! ([`crate::formfactor::monte_carlo::gather_photon`]): a point with a surface lying flush on
//! it (met by a probe from half a ray offset in front, reaching eight) or resting on it facing
//! the other way (a probe from half an offset behind) receives nothing, so `B = E`: the floor
//! under a box stays dark. Unlike the solver's rule, a coincident *twin* facing the same way
//! does not cover (both copies of a doubled surface get its light, as a viewer shows either).
//!
//! **Dilation.** Padding texels take, pass after pass, the mean of their evaluated or already
//! filled 8-neighbours in the same chart, [`super::uv::PADDING`] + 1 passes, so bilinear
//! filtering at a chart's border never reads an empty texel or another chart.
//!
//! **Denoising** (optional, [`Denoise`]): a cross-bilateral filter of the records' indirect
//! irradiance, guided by their positions, normals, chart and mutual visibility, before the
//! interpolation; the direct light is never filtered.
//!
//! **Order and memory.** The charts are baked one after the other within a band of atlas rows
//! that no other chart crosses (a shelf of the packing), the bands in parallel and each
//! chart's rows in parallel: rasterise (each texel's face), gather the records, evaluate the
//! texels, dilate. A texel keeps only its value (`f32` RGB), face and two flags; its surface
//! point is recomputed from the chart's frame when needed ([`Lightmap::point`]), so the bake
//! holds [`bytes_per_texel`] bytes a texel (22 at the default spacing).
//!
//! Every texel draws from its own streams keyed by its chart and its place in the chart, so
//! the atlas does not depend on the thread count nor on where the chart is packed.

use super::uv::{unwrap, Chart, Density, Unwrap, UnwrapError, PADDING};
use crate::color::Rgb;
use crate::geom::{Ray, Vec3};
use crate::render::gather::{Gather, GatherParams};
use crate::render::light::Surfaces;
use crate::sampling::stream;
use crate::scene::Scene;
use rayon::prelude::*;

/// How a lightmap is sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightmapParams {
    /// The atlas's density.
    pub density: Density,
    /// Shadow rays to the emitters per texel.
    pub direct: u32,
    /// Indirect sample pairs per record.
    pub indirect: u32,
    /// Texels between indirect records along each chart axis (1: every texel gathers).
    pub spacing: u32,
    /// Gather rays that hit closer than this many patch sizes are followed one level deeper
    /// ([`GatherParams::near`]). 3, not a picture's 1: a texel at a contact (a block's side
    /// near the floor) otherwise reads the solution's interpolated radiosity of patches that
    /// straddle the contact, which held the Cornell box's block sides 2 % low.
    pub near: f32,
    /// Seed of the texels' streams.
    pub seed: u64,
    /// Most bytes the bake may hold for its texels ([`bytes_per_texel`] each); an atlas that
    /// needs more is refused before any is allocated.
    pub memory_limit: u64,
    /// The edge-preserving filter of the indirect light, if any (off by default).
    pub denoise: Option<Denoise>,
}

/// The cross-bilateral filter of the indirect irradiance at the records, before it is
/// interpolated to the texels (Eisemann & Durand 2004, Petschnigg et al. 2004: a bilateral
/// filter whose range weights come from a guide, here the records' geometry, not from the
/// noisy values).
///
/// Each record's indirect irradiance `H_i` is replaced by
///
/// ```text
/// H_i' = Σ_j w_ij H_j / Σ_j w_ij,
/// w_ij = exp(−|x_i − x_j|² / (2 σ_x² L²)) · exp(−|n_i − n_j|² / (2 σ_n²)) · V_ij
/// ```
///
/// over the records `j` of the same chart (one plane, one material: records of other charts,
/// even neighbours in the atlas, never mix) whose texel lies within [`Denoise::radius`] texels,
/// with `x` the record's surface point, `n` its normal, `L` the texel size, and `V_ij` 1 when a
/// ray between the two points (lifted off the surface) is unblocked and `j` is not covered,
/// else 0: no light crosses a wall standing on the chart, covered records (under a block)
/// never mix with lit ones. The direct light is not filtered: each texel's shadow rays are
/// kept, so shadow boundaries keep the texel's sharpness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Denoise {
    /// Window radius, texels.
    pub radius: f32,
    /// Spatial standard deviation `σ_x` of the world distance between two records, in texel
    /// sizes.
    pub sigma_position: f32,
    /// Standard deviation `σ_n` of the difference of the unit normals.
    pub sigma_normal: f32,
}

impl Default for Denoise {
    fn default() -> Self {
        Self::with_radius(8.0)
    }
}

impl Denoise {
    /// A window of `radius` texels, the spatial sigma half of it, the normal sigma 0.1 (two
    /// normals 10° apart weigh 0.22).
    pub fn with_radius(radius: f32) -> Self {
        Self {
            radius,
            sigma_position: 0.5 * radius,
            sigma_normal: 0.1,
        }
    }
}

/// The bytes the bake holds for each texel of its atlases: what the [`Lightmap`] keeps (value
/// as `f32` RGB, face, kind, inside: 18), a dilation flag, and the indirect records of a chart
/// being baked (one every `spacing²` texels; with `denoise`, a second copy of their values),
/// rounded up. A chart's surface points are computed from its frame when needed, not stored.
pub fn bytes_per_texel(spacing: u32, denoise: bool) -> u64 {
    use std::mem::size_of;
    let kept = size_of::<[f32; 3]>() + size_of::<u32>() + size_of::<Texel>() + size_of::<bool>();
    let record = size_of::<Record>() + if denoise { size_of::<[f32; 3]>() } else { 0 };
    let s2 = (spacing.max(1) as u64).pow(2);
    (kept + 1) as u64 + (record as u64).div_ceil(s2)
}

impl Default for LightmapParams {
    fn default() -> Self {
        Self {
            density: Density::AtlasSize(1024),
            direct: 16,
            indirect: 256,
            spacing: 4,
            near: 3.0,
            seed: 1,
            memory_limit: u64::MAX,
            denoise: None,
        }
    }
}

/// Why a lightmap could not be baked.
#[derive(Debug, thiserror::Error)]
pub enum LightmapError {
    /// The charts could not be made or packed.
    #[error(transparent)]
    Unwrap(#[from] UnwrapError),
    /// Zero samples asked for.
    #[error("{what} 0: at least one is needed")]
    NoSamples {
        /// Which count.
        what: &'static str,
    },
    /// A denoising parameter that is not a positive finite number.
    #[error("denoising {what} {value}: must be a positive number")]
    Denoise {
        /// Which parameter.
        what: &'static str,
        /// Its value.
        value: f32,
    },
    /// The atlas's texels would need more memory than the limit.
    #[error("a {width} × {height} lightmap{} needs about {} MiB for its texels but only {} MiB are available; use a larger --texel-size or a smaller --lightmap-size", if *atlases > 1 { format!(" in {atlases} atlases") } else { String::new() }, needed >> 20, limit >> 20)]
    TooLarge {
        /// Atlas width, texels.
        width: u32,
        /// Atlas height, texels.
        height: u32,
        /// Atlases.
        atlases: u32,
        /// Bytes needed.
        needed: u64,
        /// Bytes allowed.
        limit: u64,
    },
}

/// What a texel of the atlas is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Texel {
    /// Outside every chart's surface: filled by dilation (or black outside every chart).
    Padding,
    /// On the surface and lit by the gather.
    Surface,
    /// On the surface under another surface: receives nothing.
    Covered,
}

/// A baked lightmap: the charts and their atlases of radiosity.
///
/// The per-texel arrays hold the atlases one after the other: texel `(x, y)` (rows top to
/// bottom) of atlas `a` is at `a · width · height + y · width + x`.
#[derive(Clone, Debug)]
pub struct Lightmap {
    /// The faces, their charts and their second UV set.
    pub unwrap: Unwrap,
    /// Radiosity B per texel (W/m² per channel, linear).
    pub texels: Vec<[f32; 3]>,
    /// What each texel is.
    pub kind: Vec<Texel>,
    /// The face ([`Unwrap::mesh`] patch) each evaluated texel lies on (padding: `u32::MAX`).
    pub faces: Vec<u32>,
    /// Whether each evaluated texel's centre lies inside its face (else its point is the
    /// face's closest to the centre: a border texel the face only partly covers).
    pub inside: Vec<bool>,
    /// Indirect records gathered (each [`LightmapParams::indirect`] pairs).
    pub records: usize,
}

impl Lightmap {
    /// Atlas width, texels.
    pub fn width(&self) -> u32 {
        self.unwrap.width
    }

    /// Atlas height, texels.
    pub fn height(&self) -> u32 {
        self.unwrap.height
    }

    /// How many atlases.
    pub fn atlases(&self) -> u32 {
        self.unwrap.atlases
    }

    /// The texels of atlas `a`, rows top to bottom.
    pub fn atlas_texels(&self, a: u32) -> &[[f32; 3]] {
        let n = self.width() as usize * self.height() as usize;
        &self.texels[a as usize * n..(a as usize + 1) * n]
    }

    /// Texel `k`'s radiosity.
    pub fn texel(&self, k: usize) -> Rgb {
        let [r, g, b] = self.texels[k];
        Rgb::new(r as f64, g as f64, b as f64)
    }

    /// Texels evaluated on the surface (lit or covered).
    pub fn surface_texels(&self) -> usize {
        self.kind.iter().filter(|k| **k != Texel::Padding).count()
    }

    /// The surface point texel `k` stands for (padding: `None`), computed from its chart's
    /// frame: the texel's centre on its face's plane, or the face's point closest to it.
    /// (The bake moves the point onto the solution's own patch, which differs from this only
    /// on a non-planar polygon.)
    pub fn point(&self, k: usize) -> Option<TexelPoint> {
        let face = *self.faces.get(k)?;
        if face == u32::MAX {
            return None;
        }
        let u = &self.unwrap;
        let per = u.width as usize * u.height as usize;
        let rem = k % per;
        let (x, y) = (
            (rem % u.width as usize) as u32,
            (rem / u.width as usize) as u32,
        );
        let chart = &u.charts[u.chart_of[face as usize] as usize];
        let (i, j) = (x - chart.x0, y - chart.y0);
        Some(TexelPoint {
            x: texel_point(u, chart, face, i, j),
            n: u.mesh.patches[face as usize].normal,
            face,
            inside: self.inside[k],
        })
    }

    /// The point texel `k` was evaluated at, as the bake found it: [`Lightmap::point`] moved
    /// along the normal onto the solution's own patches of its polygon (`surfaces`, the
    /// solution's that baked it), with that patch's normal. On a planar polygon the same
    /// point as [`Lightmap::point`].
    pub fn point_on(&self, k: usize, scene: &Scene, surfaces: &Surfaces<'_>) -> Option<TexelPoint> {
        let p = self.point(k)?;
        let f = &self.unwrap.mesh.patches[p.face as usize];
        let lift = lift(scene, f, surfaces.bvh.ray_offset());
        let pr = probe(surfaces, p.x, f.normal, f.surface, lift);
        Some(TexelPoint {
            x: pr.x,
            n: pr.n,
            ..p
        })
    }

    /// Atlas `a` bilinearly sampled at `uv` (glTF texture coordinates, clamped to the edge),
    /// as a GPU samples it.
    pub fn sample(&self, a: u32, uv: [f32; 2]) -> Rgb {
        let (w, h) = (self.width() as f32, self.height() as f32);
        let x = (uv[0] * w - 0.5).clamp(0.0, w - 1.0);
        let y = (uv[1] * h - 0.5).clamp(0.0, h - 1.0);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f64, (y - y0) as f64);
        let (x0, y0) = (x0 as u32, y0 as u32);
        let (x1, y1) = (
            (x0 + 1).min(self.width() - 1),
            (y0 + 1).min(self.height() - 1),
        );
        let atlas = self.atlas_texels(a);
        let at = |x: u32, y: u32| {
            let [r, g, b] = atlas[(y * self.width() + x) as usize];
            Rgb::new(r as f64, g as f64, b as f64)
        };
        at(x0, y0) * ((1.0 - fx) * (1.0 - fy))
            + at(x1, y0) * (fx * (1.0 - fy))
            + at(x0, y1) * ((1.0 - fx) * fy)
            + at(x1, y1) * (fx * fy)
    }
}

/// Where an evaluated texel lies on the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexelPoint {
    /// The point.
    pub x: Vec3,
    /// The surface's normal there.
    pub n: Vec3,
    /// The face ([`Unwrap::mesh`] patch) it lies on.
    pub face: u32,
    /// Whether the texel's centre is inside the face (else the point is the face's closest
    /// to it: a border texel the face only partly covers).
    pub inside: bool,
}

/// Closest point of the 2-D segment `ab` to `p`.
fn closest_on_segment(p: [f32; 2], a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    [a[0] + t * dx, a[1] + t * dy]
}

/// The point of triangle `t` standing for the texel centre `p`, and its distance (0 inside).
fn stand_in(p: [f32; 2], t: &[[f32; 2]; 3]) -> ([f32; 2], f32) {
    let cross = |a: [f32; 2], b: [f32; 2], c: [f32; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let area = cross(t[0], t[1], t[2]);
    let s = area.signum();
    let inside = (0..3).all(|k| cross(t[k], t[(k + 1) % 3], p) * s >= 0.0);
    if inside && area != 0.0 {
        return (p, 0.0);
    }
    let mut best = (p, f32::INFINITY);
    for k in 0..3 {
        let q = closest_on_segment(p, t[k], t[(k + 1) % 3]);
        let d = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
        if d < best.1 {
            best = (q, d);
        }
    }
    // Moved a thousandth of a texel towards the centroid: inside, not on the edge.
    let c = [
        (t[0][0] + t[1][0] + t[2][0]) / 3.0,
        (t[0][1] + t[1][1] + t[2][1]) / 3.0,
    ];
    let (dx, dy) = (c[0] - best.0[0], c[1] - best.0[1]);
    let l = (dx * dx + dy * dy).sqrt();
    if l > 0.0 {
        let m = (1e-3 / l).min(1.0);
        best.0 = [best.0[0] + dx * m, best.0[1] + dy * m];
    }
    best
}

/// Barycentric weights of `p` in the 2-D triangle `t` (the centroid's when it has no area).
fn barycentric(p: [f32; 2], t: &[[f32; 2]; 3]) -> [f32; 3] {
    let cross = |a: [f32; 2], b: [f32; 2], c: [f32; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let area = cross(t[0], t[1], t[2]);
    if area == 0.0 {
        return [1.0 / 3.0; 3];
    }
    let w0 = cross(p, t[1], t[2]) / area;
    let w1 = cross(t[0], p, t[2]) / area;
    [w0, w1, 1.0 - w0 - w1]
}

/// Whether `chart` is one of a kept UV set ([`super::given`]): no plane frame (zero axes), its
/// texels mapped to the faces by their UVs.
fn is_given(chart: &Chart) -> bool {
    chart.axis_u == Vec3::ZERO
}

/// Chart texel coordinates of mesh vertex `v` of a face of `chart`: projected on the chart's
/// plane, or, for a kept UV set, its UV in the atlas's texels less the chart's corner.
fn vertex_coords(u: &Unwrap, chart: &Chart, v: u32) -> [f32; 2] {
    if is_given(chart) {
        let q = u.uv[v as usize];
        [
            q[0] * u.width as f32 - chart.x0 as f32,
            q[1] * u.height as f32 - chart.y0 as f32,
        ]
    } else {
        chart.texel_coords(u.mesh.vertices[v as usize], u.texel)
    }
}

/// The triangles of a face in its chart's texel coordinates, with their mesh vertices.
fn face_triangles<'a>(
    u: &'a Unwrap,
    chart: &'a Chart,
    face: u32,
) -> impl Iterator<Item = [[f32; 2]; 3]> + 'a {
    face_triangles_of(u, chart, face).map(|(t, _)| t)
}

/// [`face_triangles`] with each triangle's mesh vertices.
fn face_triangles_of<'a>(
    u: &'a Unwrap,
    chart: &'a Chart,
    face: u32,
) -> impl Iterator<Item = ([[f32; 2]; 3], [u32; 3])> + 'a {
    u.mesh.patches[face as usize]
        .triangles()
        .map(move |tri| (tri.map(|v| vertex_coords(u, chart, v)), tri))
}

/// The surface point of texel `(i, j)` of `chart` on `face`: the texel's centre, or the face's
/// point closest to it. On a generated chart, on the face's own plane (a chart of nearly
/// coplanar faces has their mean plane: moved along the chart's normal onto the face); on a
/// kept UV set's chart, the face's point with that texel point's barycentric coordinates in
/// the face's UV triangle.
fn texel_point(u: &Unwrap, chart: &Chart, face: u32, i: u32, j: u32) -> Vec3 {
    let centre = [i as f32 + 0.5, j as f32 + 0.5];
    let mut best = (centre, f32::INFINITY, None);
    for (t, tri) in face_triangles_of(u, chart, face) {
        let (q, d) = stand_in(centre, &t);
        if d < best.1 {
            best = (q, d, Some((t, tri)));
        }
    }
    if is_given(chart) {
        let Some((t, tri)) = best.2 else {
            return u.mesh.patches[face as usize].centre;
        };
        let b = barycentric(best.0, &t);
        return tri
            .iter()
            .zip(b)
            .map(|(&v, b)| u.mesh.vertices[v as usize] * b)
            .sum::<Vec3>();
    }
    let p = chart.point(best.0, u.texel);
    let f = &u.mesh.patches[face as usize];
    let along = chart.normal.dot(f.normal);
    if along > 0.5 {
        p + chart.normal * (f.normal.dot(f.centre - p) / along)
    } else {
        p
    }
}

/// Where a texel's point lies on the solution's own surface, and what covers it.
#[derive(Clone, Copy, Debug)]
struct Probe {
    /// Whether another surface covers the point.
    covered: bool,
    /// The solution's patch under the point (`u32::MAX` when none is found).
    own: u32,
    /// The point, on that patch when found.
    x: Vec3,
    /// Its normal.
    n: Vec3,
}

/// Put the point `x` of a face of `surface` (normal `n`) onto the solution's patches of the
/// same input polygon, found along the normal within `lift` (a non-planar quad's patches lie
/// on its bilinear surface, off the face's mean plane), then ask whether it is covered.
fn probe(s: &Surfaces<'_>, x: Vec3, n: Vec3, surface: u32, lift: f32) -> Probe {
    let off = s.bvh.ray_offset();
    let mesh = s.mesh;
    let own_surface = |k: u32| mesh.patches[k as usize].surface == surface;
    let down = Ray::new(x + n * lift, -n);
    let (x, n, own) = match s.bvh.closest_hit(&down, 2.0 * lift) {
        Some(h) if h.front && own_surface(h.patch) => {
            (down.at(h.t), mesh.patches[h.patch as usize].normal, h.patch)
        }
        _ => (x, n, u32::MAX),
    };
    // Its own input polygon never covers it (a non-planar polygon's pieces meet at a crease).
    // Flush on it, facing it: a surface from half an offset behind, within one offset, whose
    // front faces the other way (the same way: the point's own patch or a twin).
    let behind = Ray::new(x - n * (0.5 * off), n);
    let resting = s
        .bvh
        .any_hit_except(&behind, off, |k| {
            own_surface(k) || mesh.patches[k as usize].normal.dot(n) > 0.0
        })
        .is_some();
    // Lying flush on it, within eight offsets in front.
    let front = Ray::new(x + n * (0.5 * off), n);
    let flush = s
        .bvh
        .any_hit_except(&front, 8.0 * off, own_surface)
        .is_some();
    Probe {
        covered: resting || flush,
        own,
        x,
        n,
    }
}

/// How far the probe of a point of face `f` looks along the normal for the solution's
/// patches: how far the face's polygon strays from the face's plane, plus four ray offsets.
fn lift(scene: &Scene, f: &crate::mesh::Patch, off: f32) -> f32 {
    let poly = &scene.polygons[f.surface as usize];
    let stray = poly
        .vertices
        .iter()
        .map(|v| f.normal.dot(*v - f.centre).abs())
        .fold(0.0f32, f32::max);
    1.01 * stray + 4.0 * off
}

/// An indirect record of a chart: where it lies and its indirect irradiance.
#[derive(Clone, Copy, Debug)]
struct Record {
    /// Surface point (on the solution's patch).
    x: Vec3,
    /// Normal there.
    n: Vec3,
    /// Indirect irradiance per channel.
    value: [f32; 3],
    /// Whether the record was gathered (on the surface and not covered).
    valid: bool,
}

impl Record {
    const NONE: Record = Record {
        x: Vec3::ZERO,
        n: Vec3::ZERO,
        value: [0.0; 3],
        valid: false,
    };
}

/// What every chart's bake shares.
struct Context<'a> {
    scene: &'a Scene,
    u: &'a Unwrap,
    surfaces: Surfaces<'a>,
    gather: Gather<'a>,
    params: &'a LightmapParams,
    /// How far each face's polygon strays from the face's plane, plus four ray offsets.
    lift: Vec<f32>,
}

/// One chart's rows of the atlases' arrays: row `j` of the chart is `[row j][x0 .. x0 + w]`.
struct Rows<'s> {
    texels: &'s mut [[f32; 3]],
    kind: &'s mut [Texel],
    faces: &'s mut [u32],
    inside: &'s mut [bool],
}

impl Context<'_> {
    fn rng_key(&self, chart: u32, w: u32, i: u32, j: u32) -> (u64, u64) {
        (chart as u64, (j as u64) * w as u64 + i as u64)
    }

    /// Probe the point of texel `(i, j)` of `chart` on `face`.
    fn probe_at(&self, chart: &Chart, face: u32, i: u32, j: u32) -> Probe {
        let x = texel_point(self.u, chart, face, i, j);
        let f = &self.u.mesh.patches[face as usize];
        probe(
            &self.surfaces,
            x,
            f.normal,
            f.surface,
            self.lift[face as usize],
        )
    }

    /// Bake chart `c` into its rows (`row0`: the chart's first row within `rows`); the
    /// number of records gathered.
    fn bake_chart(&self, c: u32, rows: &mut Rows<'_>, row0: usize) -> usize {
        let u = self.u;
        let chart = &u.charts[c as usize];
        let (w, h) = (chart.width, chart.height);
        let aw = u.width as usize;
        let (x0, x1) = (chart.x0 as usize, chart.x0 as usize + w as usize);
        let span = row0 * aw..(row0 + h as usize) * aw;
        // 1. Rasterise: each texel's face (the one whose closest point is nearest the
        //    centre, within half a texel diagonal), row by row. The arrays start as padding;
        //    a texel another chart already holds (a kept UV set's rectangles may overlap) is
        //    left to it.
        let mine = |f: u32| u.chart_of[f as usize] == c;
        let reach = std::f32::consts::FRAC_1_SQRT_2;
        let tris: Vec<([[f32; 2]; 3], u32)> = chart
            .faces
            .iter()
            .flat_map(|&f| face_triangles(u, chart, f).map(move |t| (t, f)))
            .collect();
        (
            rows.faces[span.clone()].par_chunks_mut(aw),
            rows.inside[span.clone()].par_chunks_mut(aw),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(j, (faces, inside))| {
                let (faces, inside) = (&mut faces[x0..x1], &mut inside[x0..x1]);
                let cy = j as f32 + 0.5;
                for (t, f) in &tris {
                    let lo = |k: usize| t.iter().map(|q| q[k]).fold(f32::INFINITY, f32::min);
                    let hi = |k: usize| t.iter().map(|q| q[k]).fold(f32::NEG_INFINITY, f32::max);
                    if cy < lo(1) - 1.0 || cy > hi(1) + 1.0 {
                        continue;
                    }
                    let i0 = (lo(0) - 1.0).floor().max(0.0) as u32;
                    let i1 = ((hi(0) + 1.0).ceil().max(0.0) as u32).min(w);
                    for i in i0..i1 {
                        let (_, d) = stand_in([i as f32 + 0.5, cy], t);
                        let k = i as usize;
                        if faces[k] != u32::MAX && !mine(faces[k]) {
                            continue;
                        }
                        // The best distance so far: 0 inside, else recomputed (rare: border
                        // texels that two faces touch).
                        let best = if faces[k] == u32::MAX {
                            f32::INFINITY
                        } else if inside[k] {
                            0.0
                        } else {
                            face_triangles(u, chart, faces[k])
                                .map(|t| stand_in([i as f32 + 0.5, cy], &t).1)
                                .fold(f32::INFINITY, f32::min)
                        };
                        if d <= reach && d < best {
                            faces[k] = *f;
                            inside[k] = d == 0.0;
                        }
                    }
                }
            });
        // 2. The records: every `spacing`-th texel from `PADDING % spacing`.
        let s = self.params.spacing.max(1);
        let p = PADDING % s;
        let (rw, rh) = (
            w.saturating_sub(p).div_ceil(s),
            h.saturating_sub(p).div_ceil(s),
        );
        let faces = &rows.faces[span.clone()];
        let face_at = |i: u32, j: u32| faces[j as usize * aw + x0 + i as usize];
        let mut records: Vec<Record> = (0..rw * rh)
            .into_par_iter()
            .map(|r| {
                let (i, j) = (p + (r % rw) * s, p + (r / rw) * s);
                let f = face_at(i, j);
                // Padding, or another chart's texel (kept UV rectangles may overlap).
                if f == u32::MAX || !mine(f) {
                    return Record::NONE;
                }
                let pr = self.probe_at(chart, f, i, j);
                if pr.covered {
                    return Record {
                        x: pr.x,
                        ..Record::NONE
                    };
                }
                let (a, b) = self.rng_key(c, w, i, j);
                let mut rng = stream(self.params.seed, 0x4c4d_4150, a, b);
                let v = self
                    .gather
                    .irradiance_parts(pr.x, pr.n, pr.own, (1, self.params.indirect), &mut rng)
                    .1;
                Record {
                    x: pr.x,
                    n: pr.n,
                    value: [v.r as f32, v.g as f32, v.b as f32],
                    valid: true,
                }
            })
            .collect();
        let n_records = records.iter().filter(|r| r.valid).count();
        if let Some(d) = &self.params.denoise {
            self.denoise(&mut records, (rw, rh), d);
        }
        // 3. The texels: direct light at each, the indirect from the records around.
        let off = self.surfaces.bvh.ray_offset();
        let m_of = |f: u32| &self.scene.materials[u.mesh.patches[f as usize].material as usize];
        (
            rows.texels[span.clone()].par_chunks_mut(aw),
            rows.kind[span.clone()].par_chunks_mut(aw),
            rows.faces[span.clone()].par_chunks(aw),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(j, (texels, kind, faces))| {
                let j = j as u32;
                for i in 0..w {
                    let k = x0 + i as usize;
                    let f = faces[k];
                    if f == u32::MAX {
                        texels[k] = [0.0; 3];
                        kind[k] = Texel::Padding;
                        continue;
                    }
                    if !mine(f) {
                        continue;
                    }
                    let m = m_of(f);
                    let pr = self.probe_at(chart, f, i, j);
                    kind[k] = if pr.covered {
                        Texel::Covered
                    } else {
                        Texel::Surface
                    };
                    let b = if pr.covered || m.reflectance.max_channel() <= 0.0 {
                        m.emission
                    } else {
                        let (a, b) = self.rng_key(c, w, i, j);
                        let mut rng = stream(self.params.seed, 0x4449_5245, a, b);
                        let (direct, _) = self.gather.irradiance_parts(
                            pr.x,
                            pr.n,
                            pr.own,
                            (self.params.direct, 0),
                            &mut rng,
                        );
                        let indirect = self
                            .interpolate(&records, (rw, rh), (i, j), &pr, off)
                            .unwrap_or_else(|| {
                                let mut rng = stream(self.params.seed, 0x4c4d_4150, a, b);
                                self.gather
                                    .irradiance_parts(
                                        pr.x,
                                        pr.n,
                                        pr.own,
                                        (1, self.params.indirect),
                                        &mut rng,
                                    )
                                    .1
                            });
                        m.emission + m.reflectance * (direct + indirect)
                    };
                    texels[k] = [b.r as f32, b.g as f32, b.b as f32];
                }
            });
        // 4. Dilation into the padding.
        dilate(rows, span, (x0, w, h), aw, mine);
        n_records
    }

    /// The indirect irradiance at texel `(i, j)` (probed as `pr`): its own record, else the
    /// records around weighted bilinearly and by visibility; `None` when none serves.
    fn interpolate(
        &self,
        records: &[Record],
        (rw, rh): (u32, u32),
        (i, j): (u32, u32),
        pr: &Probe,
        off: f32,
    ) -> Option<Rgb> {
        let s = self.params.spacing.max(1) as i64;
        let p = PADDING as i64 % s;
        let (i, j) = (i as i64, j as i64);
        let rgb = |v: [f32; 3]| Rgb::new(v[0] as f64, v[1] as f64, v[2] as f64);
        if (i - p).rem_euclid(s) == 0 && (j - p).rem_euclid(s) == 0 && i >= p && j >= p {
            let r = &records[((j - p) / s * rw as i64 + (i - p) / s) as usize];
            if r.valid {
                return Some(rgb(r.value));
            }
        }
        let (a0, b0) = ((i - p).div_euclid(s), (j - p).div_euclid(s));
        let (fx, fy) = (
            (i - p - a0 * s) as f64 / s as f64,
            (j - p - b0 * s) as f64 / s as f64,
        );
        let (mut sum, mut wsum) = (Rgb::BLACK, 0.0f64);
        for (da, db, w) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (0, 1, (1.0 - fx) * fy),
            (1, 1, fx * fy),
        ] {
            let (a, b) = (a0 + da, b0 + db);
            if w <= 0.0 || a < 0 || b < 0 || a >= rw as i64 || b >= rh as i64 {
                continue;
            }
            let r = &records[(b * rw as i64 + a) as usize];
            if !r.valid {
                continue;
            }
            let d = r.x - pr.x;
            let dist = d.length();
            if dist > 0.0 {
                let ray = Ray::new(pr.x + pr.n * off, d / dist);
                if self.surfaces.bvh.occluded(&ray, dist) {
                    continue;
                }
            }
            sum += rgb(r.value) * w;
            wsum += w;
        }
        (wsum > 1e-3).then(|| sum / wsum)
    }

    /// The cross-bilateral filter of a chart's records ([`Denoise`]).
    fn denoise(&self, records: &mut [Record], (rw, rh): (u32, u32), d: &Denoise) {
        let s = self.params.spacing.max(1) as f32;
        let reach = (d.radius / s).floor() as i64;
        let l = self.u.texel;
        let off = self.surfaces.bvh.ray_offset();
        let (two_sx2, two_sn2) = (
            2.0 * (d.sigma_position * l).powi(2),
            2.0 * d.sigma_normal.powi(2),
        );
        let r2 = d.radius * d.radius;
        let filtered: Vec<[f32; 3]> = (0..records.len())
            .into_par_iter()
            .map(|k| {
                let r = &records[k];
                if !r.valid {
                    return r.value;
                }
                let (a, b) = ((k as u32 % rw) as i64, (k as u32 / rw) as i64);
                let (mut sum, mut wsum) = ([0.0f64; 3], 0.0f64);
                for db in -reach..=reach {
                    for da in -reach..=reach {
                        let (qa, qb) = (a + da, b + db);
                        if qa < 0 || qb < 0 || qa >= rw as i64 || qb >= rh as i64 {
                            continue;
                        }
                        if ((da * da + db * db) as f32) * s * s > r2 {
                            continue;
                        }
                        let q = &records[(qb * rw as i64 + qa) as usize];
                        if !q.valid {
                            continue;
                        }
                        let dx = q.x - r.x;
                        let dist2 = dx.length_squared();
                        let w = (-(dist2 / two_sx2) - (q.n - r.n).length_squared() / two_sn2).exp()
                            as f64;
                        if w < 1e-4 {
                            continue;
                        }
                        if dist2 > 0.0 {
                            let dist = dist2.sqrt();
                            let ray = Ray::new(r.x + r.n * off, dx / dist);
                            if self.surfaces.bvh.occluded(&ray, dist) {
                                continue;
                            }
                        }
                        for c in 0..3 {
                            sum[c] += w * q.value[c] as f64;
                        }
                        wsum += w;
                    }
                }
                sum.map(|v| (v / wsum) as f32)
            })
            .collect();
        for (r, v) in records.iter_mut().zip(filtered) {
            r.value = v;
        }
    }
}

/// Bake the lightmap of `scene` from a solution's surfaces and its radiosity at the mesh
/// vertices (without ambient term; [`crate::render::vertex_radiosity`]).
pub fn bake(
    scene: &Scene,
    surfaces: Surfaces<'_>,
    vertex_radiosity: &[Rgb],
    params: &LightmapParams,
) -> Result<Lightmap, LightmapError> {
    bake_on(scene, surfaces, vertex_radiosity, params, None)
}

/// [`bake`] on the scene's own UV set when `given` holds one (the UVs at each polygon's three
/// corners, [`super::given`]), else on a generated one.
pub fn bake_on(
    scene: &Scene,
    surfaces: Surfaces<'_>,
    vertex_radiosity: &[Rgb],
    params: &LightmapParams,
    given: Option<&[[[f32; 2]; 3]]>,
) -> Result<Lightmap, LightmapError> {
    if params.direct == 0 {
        return Err(LightmapError::NoSamples {
            what: "shadow rays a texel",
        });
    }
    if params.indirect == 0 {
        return Err(LightmapError::NoSamples {
            what: "indirect samples a record",
        });
    }
    if let Some(d) = &params.denoise {
        for (what, value) in [
            ("radius", d.radius),
            ("position sigma", d.sigma_position),
            ("normal sigma", d.sigma_normal),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(LightmapError::Denoise { what, value });
            }
        }
    }
    let u = match given {
        Some(uv) => super::given::unwrap_given(scene, params.density, uv)?,
        None => unwrap(scene, params.density)?,
    };
    let per_atlas = u.width as u64 * u.height as u64;
    let n_texels = per_atlas.saturating_mul(u.atlases as u64);
    let needed = n_texels.saturating_mul(bytes_per_texel(params.spacing, params.denoise.is_some()));
    if needed > params.memory_limit {
        return Err(LightmapError::TooLarge {
            width: u.width,
            height: u.height,
            atlases: u.atlases,
            needed,
            limit: params.memory_limit,
        });
    }
    let n_texels = n_texels as usize;
    let gather = Gather::new(
        surfaces,
        vertex_radiosity,
        GatherParams {
            direct: params.direct,
            indirect: params.indirect,
            near: params.near,
            cache_samples: 0,
            ..Default::default()
        },
    );
    let off = surfaces.bvh.ray_offset();
    let lift: Vec<f32> = u.mesh.patches.iter().map(|f| lift(scene, f, off)).collect();
    let mut texels = vec![[0.0f32; 3]; n_texels];
    let mut kind = vec![Texel::Padding; n_texels];
    let mut faces = vec![u32::MAX; n_texels];
    let mut inside = vec![false; n_texels];
    let cx = Context {
        scene,
        u: &u,
        surfaces,
        gather,
        params,
        lift,
    };
    // Bands: the atlases' rows cut where no chart crosses (a shelf of the packing), each
    // band's charts baked one after the other into its own rows, the bands in parallel.
    let mut order: Vec<u32> = (0..u.charts.len() as u32).collect();
    let row_of = |c: &Chart| c.atlas as u64 * u.height as u64 + c.y0 as u64;
    order.sort_by_key(|&c| row_of(&u.charts[c as usize]));
    let mut bands: Vec<(u64, u64, Vec<u32>)> = Vec::new();
    for c in order {
        let ch = &u.charts[c as usize];
        let (lo, hi) = (row_of(ch), row_of(ch) + ch.height as u64);
        match bands.last_mut() {
            Some(b) if lo < b.1 => {
                b.1 = b.1.max(hi);
                b.2.push(c);
            }
            _ => bands.push((lo, hi, vec![c])),
        }
    }
    let aw = u.width as usize;
    let mut work: Vec<(usize, Rows<'_>, Vec<u32>)> = Vec::with_capacity(bands.len());
    {
        let (mut t, mut k, mut f, mut s) = (
            texels.as_mut_slice(),
            kind.as_mut_slice(),
            faces.as_mut_slice(),
            inside.as_mut_slice(),
        );
        let mut at = 0usize;
        for (lo, hi, charts) in bands {
            let (lo, hi) = (lo as usize * aw, hi as usize * aw);
            let skip = lo - at;
            let len = hi - lo;
            let (_, rest) = std::mem::take(&mut t).split_at_mut(skip);
            let (bt, rest) = rest.split_at_mut(len);
            t = rest;
            let (_, rest) = std::mem::take(&mut k).split_at_mut(skip);
            let (bk, rest) = rest.split_at_mut(len);
            k = rest;
            let (_, rest) = std::mem::take(&mut f).split_at_mut(skip);
            let (bf, rest) = rest.split_at_mut(len);
            f = rest;
            let (_, rest) = std::mem::take(&mut s).split_at_mut(skip);
            let (bs, rest) = rest.split_at_mut(len);
            s = rest;
            at = hi;
            work.push((
                lo / aw,
                Rows {
                    texels: bt,
                    kind: bk,
                    faces: bf,
                    inside: bs,
                },
                charts,
            ));
        }
    }
    let records: usize = work
        .into_par_iter()
        .map(|(first_row, mut rows, charts)| {
            charts
                .iter()
                .map(|&c| {
                    let ch = &u.charts[c as usize];
                    let row0 = (row_of(ch) as usize) - first_row;
                    cx.bake_chart(c, &mut rows, row0)
                })
                .sum::<usize>()
        })
        .sum();
    drop(cx);
    Ok(Lightmap {
        unwrap: u,
        texels,
        kind,
        faces,
        inside,
        records,
    })
}

/// Fill a chart's padding from its evaluated texels ([`PADDING`] + 1 passes of the mean of
/// the filled 8-neighbours within the chart). `span`: the chart's rows in `rows`; `(x0, w,
/// h)`: its columns and size; `mine`: whether a face is the chart's (texels of another chart
/// within the rectangle, where a kept UV set's rectangles overlap, are neither read nor
/// written).
fn dilate(
    rows: &mut Rows<'_>,
    span: std::ops::Range<usize>,
    (x0, w, h): (usize, u32, u32),
    aw: usize,
    mine: impl Fn(u32) -> bool,
) {
    let (cw, ch) = (w as usize, h as usize);
    let base = span.start;
    let at = |i: usize, j: usize| base + j * aw + x0 + i;
    let other = |q: usize| {
        let f = rows.faces[at(q % cw, q / cw)];
        f != u32::MAX && !mine(f)
    };
    // Filled: the chart's evaluated texels, and (never written) another chart's.
    let skip: Vec<bool> = (0..cw * ch).map(other).collect();
    let mut filled: Vec<bool> = (0..cw * ch)
        .map(|q| !skip[q] && rows.kind[at(q % cw, q / cw)] != Texel::Padding)
        .collect();
    let mut add: Vec<(usize, [f32; 3])> = Vec::new();
    for _ in 0..=PADDING {
        add.clear();
        for j in 0..ch {
            for i in 0..cw {
                if filled[j * cw + i] || skip[j * cw + i] {
                    continue;
                }
                let (mut sum, mut n) = ([0.0f64; 3], 0u32);
                for dj in -1i64..=1 {
                    for di in -1i64..=1 {
                        let (a, b) = (i as i64 + di, j as i64 + dj);
                        if a < 0 || b < 0 || a >= cw as i64 || b >= ch as i64 {
                            continue;
                        }
                        let (a, b) = (a as usize, b as usize);
                        if filled[b * cw + a] {
                            let v = rows.texels[at(a, b)];
                            for c in 0..3 {
                                sum[c] += v[c] as f64;
                            }
                            n += 1;
                        }
                    }
                }
                if n > 0 {
                    add.push((j * cw + i, sum.map(|v| (v / n as f64) as f32)));
                }
            }
        }
        if add.is_empty() {
            break;
        }
        for &(q, v) in &add {
            rows.texels[at(q % cw, q / cw)] = v;
            filled[q] = true;
        }
    }
}

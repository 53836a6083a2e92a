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
//! Every texel draws from its own stream keyed by chart and texel, so the atlas does not depend
//! on the thread count.

use super::uv::{unwrap, Density, Unwrap, UnwrapError, PADDING};
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
}

/// The bytes the bake holds for each texel of the atlas, at most: its sample and probe, its
/// slot, value, kind and surface point.
pub fn bytes_per_texel() -> u64 {
    use std::mem::size_of;
    (size_of::<Sample>()
        + size_of::<Probe>()
        + size_of::<u32>()
        + size_of::<Rgb>()
        + size_of::<Texel>()
        + size_of::<Option<TexelPoint>>()
        + size_of::<(f32, [f32; 2], u32)>()) as u64
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
    /// The atlas's texels would need more memory than the limit.
    #[error("a {width} × {height} lightmap needs about {} MiB for its texels but only {} MiB are available; use a larger --texel-size or a smaller --lightmap-size", needed >> 20, limit >> 20)]
    TooLarge {
        /// Atlas width, texels.
        width: u32,
        /// Atlas height, texels.
        height: u32,
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

/// A baked lightmap: the charts and the atlas of radiosity.
#[derive(Clone, Debug)]
pub struct Lightmap {
    /// The faces, their charts and their second UV set.
    pub unwrap: Unwrap,
    /// Radiosity B per texel (W/m² per channel), rows top to bottom, `width × height`.
    pub texels: Vec<Rgb>,
    /// What each texel is.
    pub kind: Vec<Texel>,
    /// The surface point each evaluated texel stands for (padding: `None`).
    pub points: Vec<Option<TexelPoint>>,
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

    /// Texels evaluated on the surface (lit or covered).
    pub fn surface_texels(&self) -> usize {
        self.kind.iter().filter(|k| **k != Texel::Padding).count()
    }

    /// The atlas bilinearly sampled at `uv` (glTF texture coordinates, clamped to the edge),
    /// as a GPU samples it.
    pub fn sample(&self, uv: [f32; 2]) -> Rgb {
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
        let at = |x: u32, y: u32| self.texels[(y * self.width() + x) as usize];
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

/// One evaluated texel: where it is in the atlas and on the surface.
#[derive(Clone, Copy, Debug)]
struct Sample {
    /// Atlas index.
    index: u32,
    /// Chart.
    chart: u32,
    /// Texel column and row in the chart.
    local: (u32, u32),
    /// Face of the unwrap.
    face: u32,
    /// Surface point.
    x: Vec3,
    /// Whether the texel's centre is inside the face.
    inside: bool,
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

/// The evaluated texels of one chart, in row order. A generated chart ([`super::uv`]) maps
/// texels to its plane; a chart of a kept UV set ([`super::given`], no plane frame: zero
/// axes) maps each face's UV triangle to the face by barycentric coordinates.
fn chart_samples(u: &Unwrap, c: u32) -> Vec<Sample> {
    let chart = &u.charts[c as usize];
    let given = chart.axis_u == Vec3::ZERO;
    let (w, h) = (chart.width, chart.height);
    let reach = std::f32::consts::FRAC_1_SQRT_2;
    let mut best: Vec<(f32, [f32; 2], u32)> = vec![(f32::INFINITY, [0.0; 2], 0); (w * h) as usize];
    let texel_of = |v: u32| {
        if given {
            let q = u.uv[v as usize];
            [
                q[0] * u.width as f32 - chart.x0 as f32,
                q[1] * u.height as f32 - chart.y0 as f32,
            ]
        } else {
            chart.texel_coords(u.mesh.vertices[v as usize], u.texel)
        }
    };
    for &f in &chart.faces {
        let p = &u.mesh.patches[f as usize];
        for tri in p.triangles() {
            let t = tri.map(texel_of);
            let lo = |k: usize| t.iter().map(|q| q[k]).fold(f32::INFINITY, f32::min);
            let hi = |k: usize| t.iter().map(|q| q[k]).fold(f32::NEG_INFINITY, f32::max);
            let x0 = (lo(0) - 1.0).floor().max(0.0) as u32;
            let y0 = (lo(1) - 1.0).floor().max(0.0) as u32;
            let x1 = ((hi(0) + 1.0).ceil().max(0.0) as u32).min(w);
            let y1 = ((hi(1) + 1.0).ceil().max(0.0) as u32).min(h);
            for j in y0..y1 {
                for i in x0..x1 {
                    let centre = [i as f32 + 0.5, j as f32 + 0.5];
                    let (q, d) = stand_in(centre, &t);
                    let b = &mut best[(j * w + i) as usize];
                    if d <= reach && d < b.0 {
                        *b = (d, q, f);
                    }
                }
            }
        }
    }
    let mut out = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let (d, q, f) = best[(j * w + i) as usize];
            if d.is_finite() && given {
                let face = &u.mesh.patches[f as usize];
                let tri = [face.vertices[0], face.vertices[1], face.vertices[2]];
                let b = barycentric(q, &tri.map(texel_of));
                let x = tri
                    .iter()
                    .zip(b)
                    .map(|(&v, b)| u.mesh.vertices[v as usize] * b)
                    .sum::<Vec3>();
                out.push(Sample {
                    index: (chart.y0 + j) * u.width + chart.x0 + i,
                    chart: c,
                    local: (i, j),
                    face: f,
                    x,
                    inside: d == 0.0,
                });
            } else if d.is_finite() {
                // On the face's own plane (a chart of nearly coplanar faces has their mean
                // plane): along the chart's normal onto the face.
                let p = chart.point(q, u.texel);
                let face = &u.mesh.patches[f as usize];
                let along = chart.normal.dot(face.normal);
                let x = if along > 0.5 {
                    p + chart.normal * (face.normal.dot(face.centre - p) / along)
                } else {
                    p
                };
                out.push(Sample {
                    index: (chart.y0 + j) * u.width + chart.x0 + i,
                    chart: c,
                    local: (i, j),
                    face: f,
                    x,
                    inside: d == 0.0,
                });
            }
        }
    }
    out
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
    let u = match given {
        Some(uv) => super::given::unwrap_given(scene, params.density, uv)?,
        None => unwrap(scene, params.density)?,
    };
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
    let spacing = params.spacing.max(1);
    let n_texels = u.width as usize * u.height as usize;
    let needed = (n_texels as u64).saturating_mul(bytes_per_texel());
    if needed > params.memory_limit {
        return Err(LightmapError::TooLarge {
            width: u.width,
            height: u.height,
            needed,
            limit: params.memory_limit,
        });
    }
    let mut samples: Vec<Sample> = (0..u.charts.len() as u32)
        .into_par_iter()
        .flat_map_iter(|c| chart_samples(&u, c))
        .collect();
    // Covered or not, and the patch under each point.
    let off = surfaces.bvh.ray_offset();
    // How far each face's polygon strays from the face's plane.
    let lift: Vec<f32> = u
        .mesh
        .patches
        .iter()
        .map(|f| {
            let poly = &scene.polygons[f.surface as usize];
            let stray = poly
                .vertices
                .iter()
                .map(|v| f.normal.dot(*v - f.centre).abs())
                .fold(0.0f32, f32::max);
            1.01 * stray + 4.0 * off
        })
        .collect();
    let mut probes: Vec<Probe> = samples
        .par_iter()
        .map(|s| {
            let face = &u.mesh.patches[s.face as usize];
            probe(
                &surfaces,
                s.x,
                face.normal,
                face.surface,
                lift[s.face as usize],
            )
        })
        .collect();
    for (s, p) in samples.iter_mut().zip(&mut probes) {
        s.x = p.x;
    }
    // Where each sample sits in the atlas.
    let mut slot = vec![u32::MAX; n_texels];
    for (k, s) in samples.iter().enumerate() {
        slot[s.index as usize] = k as u32;
    }
    let is_record = |s: &Sample| {
        s.local.0 % spacing == PADDING % spacing && s.local.1 % spacing == PADDING % spacing
    };
    let seed = params.seed;
    let indirect_at = |k: usize| {
        let s = &samples[k];
        let p = &probes[k];
        let mut rng = stream(seed, 0x4c4d_4150, s.chart as u64, s.index as u64);
        gather
            .irradiance_parts(p.x, p.n, p.own, (1, params.indirect), &mut rng)
            .1
    };
    // The records' indirect irradiance (None: not a record, or covered).
    let records: Vec<Option<Rgb>> = (0..samples.len())
        .into_par_iter()
        .map(|k| (is_record(&samples[k]) && !probes[k].covered).then(|| indirect_at(k)))
        .collect();
    let n_records = records.iter().filter(|r| r.is_some()).count();
    let values: Vec<Rgb> = (0..samples.len())
        .into_par_iter()
        .map(|k| {
            let s = &samples[k];
            let m = &scene.materials[u.mesh.patches[s.face as usize].material as usize];
            let Probe {
                covered, own, n, ..
            } = probes[k];
            if covered || m.reflectance.max_channel() <= 0.0 {
                return m.emission;
            }
            let chart = &u.charts[s.chart as usize];
            let mut rng = stream(seed, 0x4449_5245, s.chart as u64, s.index as u64);
            let (direct, _) = gather.irradiance_parts(s.x, n, own, (params.direct, 0), &mut rng);
            // The indirect: the record itself, else the records around, weighted bilinearly
            // and by visibility, else gathered here.
            let indirect = if let Some(r) = records[k] {
                r
            } else {
                let (i, j) = (s.local.0 as i64, s.local.1 as i64);
                let (p, sp) = (PADDING as i64 % spacing as i64, spacing as i64);
                let (i0, j0) = (
                    p + (i - p).div_euclid(sp) * sp,
                    p + (j - p).div_euclid(sp) * sp,
                );
                let (fx, fy) = ((i - i0) as f64 / sp as f64, (j - j0) as f64 / sp as f64);
                let (mut sum, mut wsum) = (Rgb::BLACK, 0.0f64);
                for (di, dj, w) in [
                    (0, 0, (1.0 - fx) * (1.0 - fy)),
                    (sp, 0, fx * (1.0 - fy)),
                    (0, sp, (1.0 - fx) * fy),
                    (sp, sp, fx * fy),
                ] {
                    let (ri, rj) = (i0 + di, j0 + dj);
                    if w <= 0.0
                        || ri < 0
                        || rj < 0
                        || ri >= chart.width as i64
                        || rj >= chart.height as i64
                    {
                        continue;
                    }
                    let index = (chart.y0 as i64 + rj) * u.width as i64 + chart.x0 as i64 + ri;
                    let rk = slot[index as usize];
                    if rk == u32::MAX {
                        continue;
                    }
                    // Another chart's texel (a kept UV set's rectangles may overlap).
                    if samples[rk as usize].chart != s.chart {
                        continue;
                    }
                    let Some(r) = records[rk as usize] else {
                        continue;
                    };
                    let y = samples[rk as usize].x;
                    let d = y - s.x;
                    let dist = d.length();
                    if dist > 0.0 {
                        let ray = Ray::new(s.x + n * off, d / dist);
                        if surfaces.bvh.occluded(&ray, dist) {
                            continue;
                        }
                    }
                    sum += r * w;
                    wsum += w;
                }
                if wsum > 1e-3 {
                    sum / wsum
                } else {
                    indirect_at(k)
                }
            };
            m.emission + m.reflectance * (direct + indirect)
        })
        .collect();
    let mut texels = vec![Rgb::BLACK; n_texels];
    let mut kind = vec![Texel::Padding; n_texels];
    let mut points = vec![None; n_texels];
    for ((s, v), p) in samples.iter().zip(&values).zip(&probes) {
        texels[s.index as usize] = *v;
        kind[s.index as usize] = if p.covered {
            Texel::Covered
        } else {
            Texel::Surface
        };
        points[s.index as usize] = Some(TexelPoint {
            x: s.x,
            n: p.n,
            face: s.face,
            inside: s.inside,
        });
    }
    dilate(&u, &mut texels, &kind);
    Ok(Lightmap {
        unwrap: u,
        texels,
        kind,
        points,
        records: n_records,
    })
}

/// Fill each chart's padding from its evaluated texels ([`PADDING`] + 1 passes of the mean of
/// the filled 8-neighbours within the chart).
fn dilate(u: &Unwrap, texels: &mut [Rgb], kind: &[Texel]) {
    let w = u.width as usize;
    let mut filled: Vec<bool> = kind.iter().map(|k| *k != Texel::Padding).collect();
    for c in &u.charts {
        let (x0, y0, cw, ch) = (
            c.x0 as usize,
            c.y0 as usize,
            c.width as usize,
            c.height as usize,
        );
        for _ in 0..=PADDING {
            let mut add = Vec::new();
            for j in 0..ch {
                for i in 0..cw {
                    let at = (y0 + j) * w + x0 + i;
                    if filled[at] {
                        continue;
                    }
                    let (mut sum, mut n) = (Rgb::BLACK, 0u32);
                    for dj in -1i64..=1 {
                        for di in -1i64..=1 {
                            let (a, b) = (i as i64 + di, j as i64 + dj);
                            if a < 0 || b < 0 || a >= cw as i64 || b >= ch as i64 {
                                continue;
                            }
                            let q = (y0 + b as usize) * w + x0 + a as usize;
                            if filled[q] {
                                sum += texels[q];
                                n += 1;
                            }
                        }
                    }
                    if n > 0 {
                        add.push((at, sum / n as f64));
                    }
                }
            }
            if add.is_empty() {
                break;
            }
            for (at, v) in add {
                texels[at] = v;
                filled[at] = true;
            }
        }
    }
}

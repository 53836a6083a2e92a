//! Pictures of a solution: primary visibility by ray casting through a pinhole camera, the
//! radiosity interpolated across each surface from its patch vertices (Gouraud shading), several
//! jittered samples per pixel, then exposure and the sRGB transfer curve.
//!
//! A Lambertian surface of radiosity `B` has radiance `B/π` in every direction; the image holds
//! that linear radiance. The back side of a patch is one-sided and renders black, as does the
//! background.

use crate::accel::{Bvh, Hit};
use crate::color::Rgb;
use crate::geom::{Ray, Vec3};
use crate::mesh::Mesh;
use crate::observe::{Event, Observer, Stage};
use crate::sampling::{stream, uniform, Rng64};
use crate::scene::Camera;
use rayon::prelude::*;

pub mod baked;
pub mod camera;
pub mod compare;
pub mod gather;
pub mod light;
pub mod particle;
pub mod path;

/// Image size and sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderParams {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Jittered camera rays per pixel.
    pub samples_per_pixel: u32,
    /// Seed of the jitter.
    pub seed: u64,
}

impl Default for RenderParams {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            samples_per_pixel: 4,
            seed: 1,
        }
    }
}

/// A linear-radiance image, rows from top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` RGB radiances (W·sr⁻¹·m⁻² in the scene's emission units).
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    /// The pixel at column `x`, row `y` (0 = top).
    pub fn at(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// The photometric luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of every pixel (ITU-R
    /// BT.709 coefficients for linear sRGB), rows top to bottom: cd/m² when the scene's
    /// emission and light are photometric (lm/m², lux).
    pub fn luminance(&self) -> Vec<f32> {
        self.pixels
            .iter()
            .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
            .collect()
    }

    /// A grey image of `values` (one per pixel, rows top to bottom) in all three channels:
    /// how a luminance picture is written to OpenEXR or PFM. `None` when the count is not
    /// `width × height`.
    pub fn grey(width: u32, height: u32, values: &[f32]) -> Option<Image> {
        (values.len() as u64 == width as u64 * height as u64).then(|| Image {
            width,
            height,
            pixels: values.iter().map(|&v| [v; 3]).collect(),
        })
    }
}

/// Radiosity at each mesh vertex, interpolated within surfaces and hard between them.
///
/// A vertex takes the area-weighted mean of the patches around its position that belong to the
/// same surface: the patches that share the vertex, plus those of other pieces of the same input
/// polygon, or of other polygons of the same smoothing group ([`crate::scene::Polygon::group`])
/// whose normal is within [`crate::scene::CREASE_ANGLE_DEG`] of its own. So patches of one
/// surface show no seams, and edges between surfaces (or across a crease) stay hard. A
/// T-vertex of an adaptive mesh ([`Mesh::hanging`]) then takes the mean of the ends of the edge
/// it lies on, so the larger patch's interpolation along that edge and the smaller patches'
/// agree: no colour cracks.
pub fn vertex_radiosity(mesh: &Mesh, patch_values: &[Rgb]) -> Vec<Rgb> {
    let nv = mesh.vertices.len();
    let mut sum = vec![Rgb::BLACK; nv];
    let mut weight = vec![0.0f64; nv];
    let mut normal = vec![Vec3::ZERO; nv];
    let mut surface = vec![u32::MAX; nv];
    for (p, b) in mesh.patches.iter().zip(patch_values) {
        let n = if p.is_triangle() { 3 } else { 4 };
        for &v in &p.vertices[..n] {
            let v = v as usize;
            sum[v] += *b * p.area as f64;
            weight[v] += p.area as f64;
            normal[v] += p.normal * p.area;
            surface[v] = p.surface;
        }
    }
    let mut out: Vec<Rgb> = sum
        .iter()
        .zip(&weight)
        .map(|(s, w)| if *w > 0.0 { *s / *w } else { Rgb::BLACK })
        .collect();
    // Vertices of one surface at one position: sort by (surface key, position), then blend each
    // run. Adding 0.0 maps −0.0 to +0.0 so that equal positions have equal bits.
    let key = |v: usize| {
        let s = surface[v];
        let g = mesh.groups.get(s as usize).copied().unwrap_or(0);
        let group = if g == 0 {
            s as u64
        } else {
            (1 << 32) | g as u64
        };
        let p = mesh.vertices[v];
        (
            group,
            [
                (p.x + 0.0).to_bits(),
                (p.y + 0.0).to_bits(),
                (p.z + 0.0).to_bits(),
            ],
        )
    };
    // Keys computed once per vertex, not per comparison.
    let mut keyed: Vec<((u64, [u32; 3]), u32)> = (0..nv)
        .filter(|&v| weight[v] > 0.0)
        .map(|v| (key(v), v as u32))
        .collect();
    keyed.par_sort_unstable_by_key(|k| k.0);
    for n in &mut normal {
        *n = n.normalize_or_zero();
    }
    let cos_crease = crate::scene::CREASE_ANGLE_DEG.to_radians().cos();
    for run in keyed.chunk_by(|a, b| a.0 == b.0) {
        if run.len() < 2 {
            continue;
        }
        for &(_, i) in run {
            let ni = normal[i as usize];
            let (mut s, mut w) = (Rgb::BLACK, 0.0);
            for &(_, j) in run {
                if normal[j as usize].dot(ni) >= cos_crease {
                    s += sum[j as usize];
                    w += weight[j as usize];
                }
            }
            if w > 0.0 {
                out[i as usize] = s / w;
            }
        }
    }
    for &[v, a, b] in &mesh.hanging {
        out[v as usize] = (out[a as usize] + out[b as usize]) * 0.5;
    }
    out
}

/// The camera's orthonormal frame `(forward, right, up)`.
fn frame(c: &Camera) -> (Vec3, Vec3, Vec3) {
    let forward = (c.target - c.eye).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    (forward, right, up)
}

/// Render the radiosity given at mesh vertices (`vertex_values`, e.g. from
/// [`vertex_radiosity`]). `observer` hears of [`Stage::Render`] and of each row finished.
pub fn render(
    mesh: &Mesh,
    bvh: &Bvh,
    vertex_values: &[Rgb],
    camera: &Camera,
    params: &RenderParams,
    observer: &dyn Observer,
) -> Image {
    render_with(
        bvh,
        camera,
        params,
        observer,
        std::f64::consts::FRAC_1_PI,
        |_, hit, _, _, _| gouraud(mesh, vertex_values, hit),
    )
}

/// A ray arriving at point `x` of `patch` against its normal `n`, and its hit: what an
/// integrator needs to shade `x` as if a camera ray had reached it (tests and probes).
pub(crate) fn arriving(x: Vec3, n: Vec3, patch: u32) -> (Ray, Hit) {
    let hit = Hit {
        t: 1.0,
        patch,
        sub: 0,
        u: 0.0,
        v: 0.0,
        front: true,
    };
    (Ray::new(x + n, -n), hit)
}

/// The value at a hit point interpolated from the patch's vertex values.
#[inline]
pub(crate) fn gouraud(mesh: &Mesh, vertex_values: &[Rgb], hit: &Hit) -> Rgb {
    let p = &mesh.patches[hit.patch as usize];
    let [a, b, c, dd] = p.vertices;
    let (b, c) = if hit.sub == 0 { (b, c) } else { (c, dd) };
    let (u, v) = (hit.u as f64, hit.v as f64);
    vertex_values[a as usize] * (1.0 - u - v)
        + vertex_values[b as usize] * u
        + vertex_values[c as usize] * v
}

/// The pixel loop every integrator shares: jittered camera rays through each pixel (stratified
/// when the count is a square; streams
/// keyed by row, so the image does not depend on the thread count), `shade` called for every
/// front-side hit with the ray, the hit, the pixel, (sample index, samples per pixel) and the
/// row's shading stream; the mean of the
/// samples times `scale` is the pixel. Back sides and the background are black.
pub(crate) fn render_with<F>(
    bvh: &Bvh,
    camera: &Camera,
    params: &RenderParams,
    observer: &dyn Observer,
    scale: f64,
    shade: F,
) -> Image
where
    F: Fn(&Ray, &Hit, (u32, u32), (u32, u32), &mut Rng64) -> Rgb + Sync,
{
    observer.event(Event::Stage(Stage::Render));
    let (w, h) = (params.width.max(1), params.height.max(1));
    let spp = params.samples_per_pixel.max(1);
    let strata = (spp as f64).sqrt().round() as u32;
    let rays = CameraRays::new(camera, w, h);
    let done = std::sync::atomic::AtomicU32::new(0);
    let mut pixels = vec![[0.0f32; 3]; (w * h) as usize];
    pixels
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            let mut rng = stream(params.seed, 0x5245_4e44, y as u64, 0);
            let mut shading = stream(params.seed, 0x5348_4144, y as u64, 0);
            for (x, px) in row.iter_mut().enumerate() {
                let mut acc = Rgb::BLACK;
                for k in 0..spp {
                    let (jx, jy) = jitter(k, spp, strata, &mut rng);
                    let ray = rays.ray(x as f32 + jx, y as f32 + jy);
                    if let Some(hit) = bvh.closest_hit(&ray, f32::INFINITY) {
                        if hit.front {
                            acc += shade(&ray, &hit, (x as u32, y as u32), (k, spp), &mut shading);
                        }
                    }
                }
                let l = acc * (scale / spp as f64);
                *px = [l.r as f32, l.g as f32, l.b as f32];
            }
            observer.event(Event::Progress {
                stage: Stage::Render,
                done: done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) as u64 + 1,
                total: h as u64,
            });
        });
    Image {
        width: w,
        height: h,
        pixels,
    }
}

/// Where in its pixel camera sample `k` of `spp` goes, in pixels from the pixel's corner: the
/// centre for one sample; stratified, a jittered `strata × strata` grid when `spp` is that
/// square (so edges converge as n^(-3/4) rather than n^(-1/2)); else uniform.
#[inline]
fn jitter(k: u32, spp: u32, strata: u32, rng: &mut Rng64) -> (f32, f32) {
    if spp == 1 {
        (0.5, 0.5)
    } else if strata * strata == spp {
        (
            ((k % strata) as f32 + uniform(rng)) / strata as f32,
            ((k / strata) as f32 + uniform(rng)) / strata as f32,
        )
    } else {
        (uniform(rng), uniform(rng))
    }
}

/// A camera sample's front-side hit, as a pass over a whole image row sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplePoint {
    /// The point hit, scene units.
    pub position: Vec3,
    /// The hit patch's (front) normal.
    pub normal: Vec3,
    /// The hit patch.
    pub patch: u32,
}

/// A worker's buffers for one image row of [`render_rows_with`], reused row after row: the
/// camera samples' hits (front sides), the hits as points, and the row pass's values.
#[derive(Default)]
struct RowBuffers {
    hits: Vec<Option<(Ray, Hit)>>,
    points: Vec<SamplePoint>,
    values: Vec<f64>,
}

/// [`render_with`] with a pass over each image row before it is shaded (`mesh` gives the
/// hits' normals): the row's camera
/// samples are cast first (the same jitter, from the same streams), `row_pass` is handed the
/// front-side hits of the row in sample order and fills one value for each (so that work
/// which is cheaper in batches, such as the luminaires' shadow rays of a whole row, is done
/// once a row), then `shade` is called for each hit with its value. The shading streams are
/// drawn in the same order as by [`render_with`], so with the same `shade` the image is the
/// same. Deterministic: nothing depends on the thread count.
#[allow(clippy::too_many_arguments)]
pub(crate) fn render_rows_with<P, F>(
    mesh: &Mesh,
    bvh: &Bvh,
    camera: &Camera,
    params: &RenderParams,
    observer: &dyn Observer,
    scale: f64,
    row_pass: P,
    shade: F,
) -> Image
where
    P: Fn(&[SamplePoint], &mut Vec<f64>) + Sync,
    F: Fn(&Ray, &Hit, (u32, u32), (u32, u32), f64, &mut Rng64) -> Rgb + Sync,
{
    observer.event(Event::Stage(Stage::Render));
    let (w, h) = (params.width.max(1), params.height.max(1));
    let spp = params.samples_per_pixel.max(1);
    let strata = (spp as f64).sqrt().round() as u32;
    let rays = CameraRays::new(camera, w, h);
    let done = std::sync::atomic::AtomicU32::new(0);
    let mut pixels = vec![[0.0f32; 3]; (w * h) as usize];
    pixels.par_chunks_mut(w as usize).enumerate().for_each_init(
        RowBuffers::default,
        |RowBuffers {
             hits,
             points,
             values,
         },
         (y, row)| {
            let mut rng = stream(params.seed, 0x5245_4e44, y as u64, 0);
            let mut shading = stream(params.seed, 0x5348_4144, y as u64, 0);
            hits.clear();
            points.clear();
            for x in 0..w {
                for k in 0..spp {
                    let (jx, jy) = jitter(k, spp, strata, &mut rng);
                    let ray = rays.ray(x as f32 + jx, y as f32 + jy);
                    let hit = bvh.closest_hit(&ray, f32::INFINITY).filter(|hit| hit.front);
                    if let Some(hit) = hit {
                        points.push(SamplePoint {
                            position: ray.at(hit.t),
                            normal: mesh.patches[hit.patch as usize].normal,
                            patch: hit.patch,
                        });
                    }
                    hits.push(hit.map(|hit| (ray, hit)));
                }
            }
            values.clear();
            row_pass(points, values);
            values.resize(points.len(), 0.0);
            let mut next = 0;
            for (x, px) in row.iter_mut().enumerate() {
                let mut acc = Rgb::BLACK;
                for k in 0..spp {
                    if let Some((ray, hit)) = &hits[x * spp as usize + k as usize] {
                        let v = values[next];
                        next += 1;
                        acc += shade(ray, hit, (x as u32, y as u32), (k, spp), v, &mut shading);
                    }
                }
                let l = acc * (scale / spp as f64);
                *px = [l.r as f32, l.g as f32, l.b as f32];
            }
            observer.event(Event::Progress {
                stage: Stage::Render,
                done: done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) as u64 + 1,
                total: h as u64,
            });
        },
    );
    Image {
        width: w,
        height: h,
        pixels,
    }
}

/// Rays through points of the image plane of a pinhole camera.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CameraRays {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_x: f32,
    tan_y: f32,
    w: f32,
    h: f32,
}

impl CameraRays {
    pub(crate) fn new(camera: &Camera, w: u32, h: u32) -> Self {
        let (forward, right, up) = frame(camera);
        let tan_y = (camera.fov_y_deg.to_radians() * 0.5).tan();
        Self {
            eye: camera.eye,
            forward,
            right,
            up,
            tan_x: tan_y * w as f32 / h as f32,
            tan_y,
            w: w as f32,
            h: h as f32,
        }
    }

    /// The ray through image point `(px, py)` in pixels from the top-left corner.
    #[inline]
    pub(crate) fn ray(&self, px: f32, py: f32) -> Ray {
        let sx = (2.0 * px / self.w - 1.0) * self.tan_x;
        let sy = (1.0 - 2.0 * py / self.h) * self.tan_y;
        let d = (self.forward + self.right * sx + self.up * sy).normalize();
        Ray::new(self.eye, d)
    }
}

/// The exposure scale that maps the 97th percentile of pixel luminance to 0.9 (so that a few
/// percent of the pixels, typically the lights, may clip), or 1 for a black image.
pub fn auto_exposure(image: &Image) -> f32 {
    let mut lum: Vec<f32> = image
        .pixels
        .iter()
        .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        .filter(|l| *l > 0.0)
        .collect();
    if lum.is_empty() {
        return 1.0;
    }
    let k = ((lum.len() as f64 * 0.97) as usize).min(lum.len() - 1);
    let (_, v, _) = lum.select_nth_unstable_by(k, f32::total_cmp);
    0.9 / *v
}

/// The exposure scale that maps the 97th percentile of luminance over the patches, weighted by
/// `area`, to 0.9: the scene-space counterpart of [`auto_exposure`], for baked vertex colours.
/// 1 when everything is black.
pub fn auto_exposure_patches(values: &[Rgb], area: &[f64]) -> f32 {
    let mut lum: Vec<(f64, f64)> = values
        .iter()
        .zip(area)
        .map(|(v, a)| (v.luminance(), *a))
        .filter(|(l, a)| *l > 0.0 && *a > 0.0)
        .collect();
    if lum.is_empty() {
        return 1.0;
    }
    lum.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = lum.iter().map(|x| x.1).sum();
    let mut acc = 0.0;
    for (l, a) in &lum {
        acc += a;
        if acc >= 0.97 * total {
            return (0.9 / l) as f32;
        }
    }
    (0.9 / lum[lum.len() - 1].0) as f32
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value in `[0, 1]`.
pub fn srgb_encode(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// 8-bit sRGB pixels (RGB, rows top to bottom) of `image` after multiplying by `scale`.
pub fn to_srgb8(image: &Image, scale: f32) -> Vec<u8> {
    image
        .pixels
        .iter()
        .flat_map(|p| p.map(|c| (srgb_encode(c * scale) * 255.0 + 0.5) as u8))
        .collect()
}

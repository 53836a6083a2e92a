//! A thin binding of Intel Embree 3 (the system's `libembree3`, Debian's `libembree-dev`),
//! enough to cast the same closest-hit rays as the engine's BVH: one triangle mesh, one
//! committed scene, `rtcIntersect1` (one ray) and `rtcIntersect1M` (a stream of rays). Built only with the `embree` feature; the structures are
//! laid out as `embree3/rtcore_ray.h` and `rtcore_common.h` define them (Embree 3.13,
//! `RTC_MAX_INSTANCE_LEVEL_COUNT` 1). FFI is unsafe by nature: this module and `alloc.rs` are
//! the only places that allow it.
#![allow(unsafe_code)]

use crate::rays::Caster;
use anyhow::{bail, Result};
use radiosity::geom::Ray;
use radiosity::mesh::Mesh;
use std::ffi::c_void;

#[repr(C, align(16))]
#[derive(Clone, Copy, Default)]
struct RtcRay {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: u32,
    id: u32,
    flags: u32,
}

#[repr(C, align(16))]
#[derive(Clone, Copy, Default)]
struct RtcHit {
    ng: [f32; 3],
    u: f32,
    v: f32,
    prim_id: u32,
    geom_id: u32,
    inst_id: [u32; 1],
}

#[repr(C)]
#[derive(Clone, Copy, Default)]
struct RtcRayHit {
    ray: RtcRay,
    hit: RtcHit,
}

#[repr(C)]
struct RtcIntersectContext {
    flags: u32,
    filter: *const c_void,
    inst_id: [u32; 1],
}

const INVALID_ID: u32 = u32::MAX;
const GEOMETRY_TYPE_TRIANGLE: u32 = 0;
const BUFFER_TYPE_INDEX: u32 = 0;
const BUFFER_TYPE_VERTEX: u32 = 1;
const FORMAT_UINT3: u32 = 0x5003;
const FORMAT_FLOAT3: u32 = 0x9003;
const BUILD_QUALITY_HIGH: u32 = 2;

#[link(name = "embree3")]
extern "C" {
    fn rtcNewDevice(config: *const std::ffi::c_char) -> *mut c_void;
    fn rtcReleaseDevice(device: *mut c_void);
    fn rtcGetDeviceError(device: *mut c_void) -> u32;
    fn rtcNewScene(device: *mut c_void) -> *mut c_void;
    fn rtcReleaseScene(scene: *mut c_void);
    fn rtcSetSceneBuildQuality(scene: *mut c_void, quality: u32);
    fn rtcCommitScene(scene: *mut c_void);
    fn rtcNewGeometry(device: *mut c_void, kind: u32) -> *mut c_void;
    fn rtcSetNewGeometryBuffer(
        geometry: *mut c_void,
        kind: u32,
        slot: u32,
        format: u32,
        byte_stride: usize,
        count: usize,
    ) -> *mut c_void;
    fn rtcCommitGeometry(geometry: *mut c_void);
    fn rtcAttachGeometry(scene: *mut c_void, geometry: *mut c_void) -> u32;
    fn rtcReleaseGeometry(geometry: *mut c_void);
    fn rtcIntersect1(scene: *mut c_void, context: *mut RtcIntersectContext, rayhit: *mut RtcRayHit);
    fn rtcIntersect1M(
        scene: *mut c_void,
        context: *mut RtcIntersectContext,
        rayhit: *mut RtcRayHit,
        m: u32,
        byte_stride: usize,
    );
}

/// An Embree scene of a mesh's triangles, and which patch each came from.
pub struct Embree {
    device: *mut c_void,
    scene: *mut c_void,
    patch_of: Vec<u32>,
    normal: Vec<[f32; 3]>,
}

// Embree's committed scenes are safe to trace from many threads at once (its documented
// contract for rtcIntersect1 on a committed scene); the pointers are never written after
// construction.
unsafe impl Sync for Embree {}
unsafe impl Send for Embree {}

impl Embree {
    /// Build a high-quality BVH over `mesh`'s triangles.
    pub fn new(mesh: &Mesh) -> Result<Self> {
        let mut tris: Vec<[u32; 3]> = Vec::new();
        let mut patch_of = Vec::new();
        for (k, p) in mesh.patches.iter().enumerate() {
            for t in p.triangles() {
                tris.push(t);
                patch_of.push(k as u32);
            }
        }
        // Embree's device configuration (`rtcNewDevice`), for comparing its variants:
        // `tri_accel=bvh4.triangle4`, `isa=avx2`, `tri_builder=sah`, `verbose=1`, …
        let config = match std::env::var_os("RADIOSITY_EMBREE_CONFIG") {
            None => None,
            Some(c) => Some(
                c.to_str()
                    .and_then(|c| std::ffi::CString::new(c).ok())
                    .ok_or_else(|| {
                        anyhow::anyhow!("RADIOSITY_EMBREE_CONFIG: not UTF-8, or holds a NUL byte")
                    })?,
            ),
        };
        // SAFETY: every call follows Embree's API: handles come from the calls that create
        // them and are checked for null, buffers are written within the sizes requested, and
        // the scene is committed before it is traced.
        unsafe {
            let device = rtcNewDevice(config.as_ref().map_or(std::ptr::null(), |c| c.as_ptr()));
            if device.is_null() {
                bail!(
                    "Embree: rtcNewDevice failed{}",
                    config.as_ref().map_or(String::new(), |c| format!(
                        " (RADIOSITY_EMBREE_CONFIG={:?})",
                        c.to_string_lossy()
                    ))
                );
            }
            let scene = rtcNewScene(device);
            rtcSetSceneBuildQuality(scene, BUILD_QUALITY_HIGH);
            let geom = rtcNewGeometry(device, GEOMETRY_TYPE_TRIANGLE);
            let nv = mesh.vertices.len();
            let vb = rtcSetNewGeometryBuffer(geom, BUFFER_TYPE_VERTEX, 0, FORMAT_FLOAT3, 12, nv)
                as *mut f32;
            let ib =
                rtcSetNewGeometryBuffer(geom, BUFFER_TYPE_INDEX, 0, FORMAT_UINT3, 12, tris.len())
                    as *mut u32;
            if vb.is_null() || ib.is_null() {
                bail!(
                    "Embree: buffers not allocated (error {})",
                    rtcGetDeviceError(device)
                );
            }
            for (i, v) in mesh.vertices.iter().enumerate() {
                *vb.add(3 * i) = v.x;
                *vb.add(3 * i + 1) = v.y;
                *vb.add(3 * i + 2) = v.z;
            }
            for (i, t) in tris.iter().enumerate() {
                for c in 0..3 {
                    *ib.add(3 * i + c) = t[c];
                }
            }
            rtcCommitGeometry(geom);
            rtcAttachGeometry(scene, geom);
            rtcReleaseGeometry(geom);
            rtcCommitScene(scene);
            let e = rtcGetDeviceError(device);
            if e != 0 {
                bail!("Embree: error {e} while building the scene");
            }
            Ok(Self {
                device,
                scene,
                patch_of,
                normal: mesh
                    .patches
                    .iter()
                    .map(|p| [p.normal.x, p.normal.y, p.normal.z])
                    .collect(),
            })
        }
    }
}

impl Drop for Embree {
    fn drop(&mut self) {
        // SAFETY: the handles are valid and released once.
        unsafe {
            rtcReleaseScene(self.scene);
            rtcReleaseDevice(self.device);
        }
    }
}

impl Embree {
    /// A ray as Embree takes it: from `tnear` 0 to infinity, no hit yet.
    fn ray_hit(ray: &Ray) -> RtcRayHit {
        RtcRayHit {
            ray: RtcRay {
                org: ray.origin.to_array(),
                tnear: 0.0,
                dir: ray.direction.to_array(),
                time: 0.0,
                tfar: f32::INFINITY,
                mask: u32::MAX,
                id: 0,
                flags: 0,
            },
            hit: RtcHit {
                geom_id: INVALID_ID,
                prim_id: INVALID_ID,
                inst_id: [INVALID_ID],
                ..Default::default()
            },
        }
    }

    /// A context for incoherent rays (flags 0), without a filter.
    fn context() -> RtcIntersectContext {
        RtcIntersectContext {
            flags: 0,
            filter: std::ptr::null(),
            inst_id: [INVALID_ID],
        }
    }

    /// What Embree found for `ray`, as [`Caster::cast`] reports it.
    fn answer(&self, ray: &Ray, rh: &RtcRayHit) -> (u32, f32) {
        if rh.hit.geom_id == INVALID_ID {
            return (u32::MAX, f32::INFINITY);
        }
        let patch = self.patch_of[rh.hit.prim_id as usize];
        let n = self.normal[patch as usize];
        let d = ray.direction;
        // Front side: the ray arrives against the patch's normal, as the engine's BVH decides.
        let t = rh.ray.tfar;
        if n[0] * d.x + n[1] * d.y + n[2] * d.z < 0.0 {
            (patch, t)
        } else {
            (u32::MAX, t)
        }
    }
}

impl Caster for Embree {
    fn name(&self) -> &'static str {
        "Embree 3"
    }

    fn cast(&self, ray: &Ray) -> (u32, f32) {
        let mut rh = Self::ray_hit(ray);
        let mut ctx = Self::context();
        // SAFETY: the scene is committed; `ctx` and `rh` are valid, aligned as Embree requires.
        unsafe { rtcIntersect1(self.scene, &mut ctx, &mut rh) };
        self.answer(ray, &rh)
    }

    fn batch_name(&self) -> &'static str {
        "Embree 3 stream"
    }

    /// `rtcIntersect1M`: Embree's stream of single rays.
    fn cast_batch(&self, rays: &[Ray], out: &mut [(u32, f32)]) {
        let mut rh = [RtcRayHit::default(); crate::rays::BATCH];
        for (r, o) in rays
            .chunks(crate::rays::BATCH)
            .zip(out.chunks_mut(crate::rays::BATCH))
        {
            let rh = &mut rh[..r.len()];
            for (h, ray) in rh.iter_mut().zip(r) {
                *h = Self::ray_hit(ray);
            }
            let mut ctx = Self::context();
            // SAFETY: the scene is committed; `rh` holds `r.len()` (at most BATCH) valid,
            // aligned ray-hits laid out at the stride given.
            unsafe {
                rtcIntersect1M(
                    self.scene,
                    &mut ctx,
                    rh.as_mut_ptr(),
                    rh.len() as u32,
                    std::mem::size_of::<RtcRayHit>(),
                )
            };
            for ((h, ray), o) in rh.iter().zip(r).zip(o.iter_mut()) {
                *o = self.answer(ray, h);
            }
        }
    }
}

//! Instruction-set-specific code: the box test in AVX2 and FMA intrinsics (module `avx`), and
//! for portable builds the run-time choice of the queries' copy compiled for AVX2 (module
//! `dispatch`). Each of the two modules allows `unsafe` code for itself alone.

/// Whether the build assumes AVX2 and FMA, so that the queries test boxes with
/// [`avx::enter`] without asking the CPU.
pub(super) const NATIVE_AVX: bool = cfg!(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
));

/// [`Ray4::enter`](super::intersect::Ray4::enter) in AVX2 and FMA intrinsics, used by builds
/// that assume them (the default, `-C target-cpu=native` on such a CPU) and by the run-time
/// AVX2 copy of a portable build ([`NATIVE_AVX`], module `dispatch`): the compiler's own
/// vectorisation of [`Ray4::enter_lanes`](super::intersect::Ray4::enter_lanes) splits the far
/// distances into two halves and keeps the ray's constants on the stack.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
pub(super) mod avx {
    use crate::accel::intersect::Ray4;
    use crate::accel::node::{WideNode, WIDTH};
    use std::arch::x86_64::*;

    /// Entry distances and the mask of the children met with `0 ≤ t ≤ t_max` (finite), as
    /// [`Ray4::enter_lanes`] computes them but with each slab distance one fused
    /// multiply-add (`plane·inv − o·inv`, the ray's constants padded so that the test stays
    /// conservative).
    ///
    /// The maxima, minima and the comparison are taken on the distances' bits as signed
    /// integers (`vpmaxsd`, `vpminsd`, `vpcmpgtd`: one cycle each against `maxps`'s four, on
    /// the chain from a node's load to the next; docs/notes/accel.md). As integers,
    /// non-negative floats keep their order and every negative one lies below them, so the
    /// entry distance, a maximum with 0, is the float maximum; an exit distance that comes out
    /// negative, as an integer or not, lies below every entry and the child is not met, as with
    /// floats. A NaN origin coordinate makes both of its slab's distances carry its NaN
    /// (propagated through `o·inv`, the padding and the fused multiply-add), which as an
    /// integer lies above every exit (positive sign) or below every entry (negative), so such a
    /// ray still enters nothing (and `nan_rays_meet_nothing` holds NaN rays to no hit). Only an
    /// exit of exactly −0.0 differs from the float test, which would meet that box at t = 0,
    /// where no hit counts.
    #[inline(always)]
    pub(in crate::accel) fn enter(r: &Ray4, n: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
        // SAFETY: `Ray4::enter::<true>`, the only caller, is instantiated only where the CPU
        // has AVX2 and FMA: in builds whose target features include both (`NATIVE_AVX`),
        // and in `dispatch`'s copies, which run after `is_x86_feature_detected!`. The loads
        // and the store touch whole `[f32; 8]` arrays through references to them.
        unsafe {
            let plane = |k: usize| _mm256_loadu_ps(n.planes[k].as_ptr());
            let dist = |k: usize, a: usize, o: f32| {
                _mm256_fmsub_ps(plane(k), _mm256_set1_ps(r.inv[a]), _mm256_set1_ps(o))
            };
            let nx = dist(r.near[0], 0, r.o_near[0]);
            let ny = dist(r.near[1], 1, r.o_near[1]);
            let nz = dist(r.near[2], 2, r.o_near[2]);
            let fx = dist(r.far[0], 0, r.o_far[0]);
            let fy = dist(r.far[1], 1, r.o_far[1]);
            let fz = dist(r.far[2], 2, r.o_far[2]);
            let i = _mm256_castps_si256;
            let near = _mm256_max_epi32(
                _mm256_max_epi32(_mm256_setzero_si256(), i(nz)),
                _mm256_max_epi32(i(nx), i(ny)),
            );
            let far = _mm256_min_epi32(
                _mm256_min_epi32(i(_mm256_set1_ps(t_max)), i(fz)),
                _mm256_min_epi32(i(fx), i(fy)),
            );
            let beyond = _mm256_cmpgt_epi32(near, far);
            let mask = !(_mm256_movemask_ps(_mm256_castsi256_ps(beyond)) as u32) & 0xff;
            let mut out = [0.0f32; WIDTH];
            _mm256_storeu_ps(out.as_mut_ptr(), _mm256_castsi256_ps(near));
            (out, mask)
        }
    }
}

/// Run-time choice of instruction set, for builds that do not assume AVX2 (no
/// `-C target-cpu=native`): the queries are compiled a second time with AVX2, FMA, BMI and
/// POPCNT enabled (8-wide box tests in one instruction, `tzcnt`, `popcnt`), and that copy runs
/// wherever the CPU has them. A build for a CPU with AVX2 uses its one copy directly.
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
#[allow(unsafe_code)]
pub(super) mod dispatch {
    use crate::accel::{Bvh, Hit};
    use crate::geom::Ray;
    use std::sync::OnceLock;

    /// Whether this CPU has every feature the AVX2 copy is compiled with (asked once).
    #[inline(always)]
    pub(in crate::accel) fn avx2() -> bool {
        static HAS: OnceLock<bool> = OnceLock::new();
        *HAS.get_or_init(|| {
            is_x86_feature_detected!("avx2")
                && is_x86_feature_detected!("fma")
                && is_x86_feature_detected!("bmi1")
                && is_x86_feature_detected!("bmi2")
                && is_x86_feature_detected!("lzcnt")
                && is_x86_feature_detected!("popcnt")
        })
    }

    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    fn closest_hit_avx2(bvh: &Bvh, ray: &Ray, t_max: f32) -> Option<Hit> {
        bvh.closest_hit_in::<true>(ray, t_max)
    }

    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    fn closest_hits_avx2(bvh: &Bvh, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
        bvh.closest_hits_in::<true>(rays, t_max, out)
    }

    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    fn any_hit_except_avx2<const FAR_FIRST: bool>(
        bvh: &Bvh,
        ray: &Ray,
        t_max: f32,
        skip: impl Fn(u32) -> bool,
    ) -> Option<f32> {
        bvh.any_hit_except_in::<true, FAR_FIRST>(ray, t_max, skip)
    }

    /// The AVX2 copy of [`Bvh::closest_hit`]; call only where [`avx2`] is true.
    #[inline]
    pub(in crate::accel) fn closest_hit(bvh: &Bvh, ray: &Ray, t_max: f32) -> Option<Hit> {
        debug_assert!(avx2());
        // SAFETY: the caller checked with `avx2()` that the CPU has every feature enabled.
        unsafe { closest_hit_avx2(bvh, ray, t_max) }
    }

    /// The AVX2 copy of [`Bvh::closest_hits`]; call only where [`avx2`] is true.
    #[inline]
    pub(in crate::accel) fn closest_hits(
        bvh: &Bvh,
        rays: &[Ray],
        t_max: f32,
        out: &mut [Option<Hit>],
    ) {
        debug_assert!(avx2());
        // SAFETY: the caller checked with `avx2()` that the CPU has every feature enabled.
        unsafe { closest_hits_avx2(bvh, rays, t_max, out) }
    }

    /// The AVX2 copy of [`Bvh::any_hit_except`]; call only where [`avx2`] is true.
    #[inline]
    pub(in crate::accel) fn any_hit_except<const FAR_FIRST: bool>(
        bvh: &Bvh,
        ray: &Ray,
        t_max: f32,
        skip: impl Fn(u32) -> bool,
    ) -> Option<f32> {
        debug_assert!(avx2());
        // SAFETY: as above.
        unsafe { any_hit_except_avx2::<FAR_FIRST>(bvh, ray, t_max, skip) }
    }
}

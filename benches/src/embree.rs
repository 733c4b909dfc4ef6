//! Embree 3 as a measured baseline: a safe wrapper over the few calls of the `embree` crate's raw
//! `sys` bindings that the benchmarks need (build a triangle scene, trace one ray, test one
//! occlusion ray, and the same for packets of 16 coherent rays). Needs Debian's `libembree-dev` (3.13) and the feature `embree`.
//!
//! This is one of the two modules of the workspace allowed `unsafe` (foreign calls cannot be
//! written without it); every block says why it is sound.
#![allow(unsafe_code)]

use embree::sys;
use rt_core::{Hit, Ray, Triangle};
use std::ffi::CString;

/// Embree's build quality (`rtcSetSceneBuildQuality`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    /// Embree's default: binned SAH, no spatial splits.
    Medium,
    /// SAH with spatial splits: slower builds, faster traversal.
    High,
}

/// An Embree device with one committed triangle scene.
#[derive(Debug)]
pub struct EmbreeScene {
    device: sys::RTCDevice,
    scene: sys::RTCScene,
}

/// The geometry id Embree writes when nothing was hit (`RTC_INVALID_GEOMETRY_ID`).
const INVALID_ID: u32 = u32::MAX;

impl EmbreeScene {
    /// A device with `threads` worker threads (`None`: Embree's default, one per core). Device
    /// creation starts Embree's thread pool, so it is kept out of [`EmbreeScene::build`]'s timing
    /// by building on a device made beforehand.
    ///
    /// # Errors
    /// When Embree cannot create the device (no supported CPU, bad configuration).
    pub fn device(threads: Option<usize>) -> Result<Device, String> {
        let config = match threads {
            Some(n) => format!("threads={n}"),
            None => String::new(),
        };
        let config = CString::new(config).map_err(|e| e.to_string())?;
        // SAFETY: `config` is a valid NUL-terminated string that outlives the call; Embree copies
        // what it needs from it.
        let device = unsafe { sys::rtcNewDevice(config.as_ptr()) };
        if device.is_null() {
            return Err("rtcNewDevice failed (is libembree3 installed?)".into());
        }
        Ok(Device(device))
    }

    /// Builds a scene of the triangles on `device` (one geometry, triangle `i` is Embree's
    /// `primID` `i`), with the default scene flags and the given quality.
    ///
    /// # Errors
    /// Any error Embree reports while building.
    pub fn build(device: &Device, tris: &[Triangle], quality: Quality) -> Result<Self, String> {
        let d = device.0;
        let n = tris.len();
        // SAFETY: `d` is a live device (owned by `device`, which outlives this function). Each
        // created object is checked for null before use. The vertex and index buffers returned by
        // `rtcSetNewGeometryBuffer` are Embree-owned allocations of exactly `3 * n` items of the
        // requested stride (Embree adds its own padding), so the slices built over them are in
        // bounds and aligned for `f32`/`u32`; they are written before `rtcCommitGeometry` and not
        // touched afterwards. Retaining the device for the scene keeps it alive until `Drop`.
        unsafe {
            let geometry = sys::rtcNewGeometry(d, sys::RTCGeometryType::TRIANGLE);
            if geometry.is_null() {
                return Err(device_error(d, "rtcNewGeometry"));
            }
            let vertices = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTCBufferType::VERTEX,
                0,
                sys::RTCFormat::FLOAT3,
                12,
                3 * n,
            ) as *mut f32;
            let indices = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTCBufferType::INDEX,
                0,
                sys::RTCFormat::UINT3,
                12,
                n,
            ) as *mut u32;
            if vertices.is_null() || indices.is_null() {
                sys::rtcReleaseGeometry(geometry);
                return Err(device_error(d, "rtcSetNewGeometryBuffer"));
            }
            let vertices = std::slice::from_raw_parts_mut(vertices, 9 * n);
            let indices = std::slice::from_raw_parts_mut(indices, 3 * n);
            for (i, t) in tris.iter().enumerate() {
                for (k, v) in [t.v0, t.v1, t.v2].iter().enumerate() {
                    vertices[9 * i + 3 * k..9 * i + 3 * k + 3].copy_from_slice(&v.to_array());
                    indices[3 * i + k] = (3 * i + k) as u32;
                }
            }
            sys::rtcCommitGeometry(geometry);
            let scene = sys::rtcNewScene(d);
            if scene.is_null() {
                sys::rtcReleaseGeometry(geometry);
                return Err(device_error(d, "rtcNewScene"));
            }
            sys::rtcSetSceneBuildQuality(
                scene,
                match quality {
                    Quality::Medium => sys::RTCBuildQuality::MEDIUM,
                    Quality::High => sys::RTCBuildQuality::HIGH,
                },
            );
            sys::rtcAttachGeometry(scene, geometry);
            // The scene holds its own reference to the geometry.
            sys::rtcReleaseGeometry(geometry);
            sys::rtcCommitScene(scene);
            if sys::rtcGetDeviceError(d) != sys::RTCError::NONE {
                sys::rtcReleaseScene(scene);
                return Err(device_error(d, "rtcCommitScene"));
            }
            sys::rtcRetainDevice(d);
            Ok(Self { device: d, scene })
        }
    }

    /// The closest hit: Embree's primitive id, `t` and surface coordinates, the answer rt-core's
    /// structures give (Embree's `u` and `v` weigh the second and third vertex, as theirs do).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut rayhit = sys::RTCRayHit {
            ray: to_rtc(ray),
            hit: sys::RTCHit {
                Ng_x: 0.0,
                Ng_y: 0.0,
                Ng_z: 0.0,
                u: 0.0,
                v: 0.0,
                primID: INVALID_ID,
                geomID: INVALID_ID,
                instID: [INVALID_ID],
            },
        };
        let mut context = context();
        // SAFETY: `self.scene` is a committed scene, alive until `Drop`; `context` and `rayhit`
        // are valid, properly aligned (`RTCRayHit` is `repr(align(16))`) locals that Embree only
        // accesses during the call.
        unsafe { sys::rtcIntersect1(self.scene, &mut context, &mut rayhit) };
        (rayhit.hit.geomID != INVALID_ID).then_some(Hit {
            prim: rayhit.hit.primID,
            t: rayhit.ray.tfar,
            u: rayhit.hit.u,
            v: rayhit.hit.v,
        })
    }

    /// Whether anything is hit in the ray's interval (Embree sets `tfar` to `-inf` then).
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        let mut r = to_rtc(ray);
        let mut context = context();
        // SAFETY: as in `intersect`: a committed scene and valid locals for the call's duration.
        unsafe { sys::rtcOccluded1(self.scene, &mut context, &mut r) };
        r.tfar == f32::NEG_INFINITY
    }
}

/// The lanes of one Embree packet call (`rtcIntersect16`, `rtcOccluded16`).
pub const PACKET: usize = 16;

/// A packet's valid mask: -1 for an active lane, 0 for an unused one, aligned as Embree loads it.
#[repr(C, align(64))]
struct Valid16([i32; PACKET]);

impl EmbreeScene {
    /// The closest hits of `rays` into `out` (as many as both have), `PACKET` consecutive rays per
    /// `rtcIntersect16` call with the coherent flag: Embree's packet path for coherent rays.
    pub fn intersect_packets(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        for (rays, out) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
            let n = rays.len().min(out.len());
            let mut valid = Valid16([0; PACKET]);
            // SAFETY: `RTCRayHit16` is plain old data (arrays of f32 and u32), for which all
            // zero bytes are a valid value.
            let mut packet: sys::RTCRayHit16 = unsafe { std::mem::zeroed() };
            for (i, r) in rays[..n].iter().enumerate() {
                valid.0[i] = -1;
                let p = &mut packet.ray;
                (p.org_x[i], p.org_y[i], p.org_z[i]) = (r.origin.x, r.origin.y, r.origin.z);
                (p.dir_x[i], p.dir_y[i], p.dir_z[i]) = (r.dir().x, r.dir().y, r.dir().z);
                (p.tnear[i], p.tfar[i], p.mask[i]) = (r.t_min, r.t_max, u32::MAX);
                packet.hit.geomID[i] = INVALID_ID;
                packet.hit.primID[i] = INVALID_ID;
            }
            let mut context = coherent_context();
            // SAFETY: a committed scene alive until `Drop`; `valid` and `packet` are locals
            // aligned to 64 bytes (`Valid16` and bindgen's `repr(align(64))`), as Embree's
            // 16-wide loads require, and only accessed during the call.
            unsafe { sys::rtcIntersect16(valid.0.as_ptr(), self.scene, &mut context, &mut packet) };
            for (i, o) in out[..n].iter_mut().enumerate() {
                *o = (packet.hit.geomID[i] != INVALID_ID).then_some(Hit {
                    prim: packet.hit.primID[i],
                    t: packet.ray.tfar[i],
                    u: packet.hit.u[i],
                    v: packet.hit.v[i],
                });
            }
        }
    }

    /// Whether anything is hit in each ray's interval, into `out`, `PACKET` rays per
    /// `rtcOccluded16` call with the coherent flag.
    pub fn occluded_packets(&self, rays: &[Ray], out: &mut [bool]) {
        for (rays, out) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
            let n = rays.len().min(out.len());
            let mut valid = Valid16([0; PACKET]);
            // SAFETY: as in `intersect_packets`: plain old data, all zeros valid.
            let mut p: sys::RTCRay16 = unsafe { std::mem::zeroed() };
            for (i, r) in rays[..n].iter().enumerate() {
                valid.0[i] = -1;
                (p.org_x[i], p.org_y[i], p.org_z[i]) = (r.origin.x, r.origin.y, r.origin.z);
                (p.dir_x[i], p.dir_y[i], p.dir_z[i]) = (r.dir().x, r.dir().y, r.dir().z);
                (p.tnear[i], p.tfar[i], p.mask[i]) = (r.t_min, r.t_max, u32::MAX);
            }
            let mut context = coherent_context();
            // SAFETY: as in `intersect_packets`.
            unsafe { sys::rtcOccluded16(valid.0.as_ptr(), self.scene, &mut context, &mut p) };
            for (i, o) in out[..n].iter_mut().enumerate() {
                *o = p.tfar[i] == f32::NEG_INFINITY;
            }
        }
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: both handles were created (scene) or retained (device) by `build` and are
        // released exactly once, here.
        unsafe {
            sys::rtcReleaseScene(self.scene);
            sys::rtcReleaseDevice(self.device);
        }
    }
}

/// An Embree device; scenes built on it keep it alive.
#[derive(Debug)]
pub struct Device(sys::RTCDevice);

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: the handle came from `rtcNewDevice` and this is its owner's only release.
        unsafe { sys::rtcReleaseDevice(self.0) };
    }
}

/// What `rtcInitIntersectContext` (an inline function the bindings lack) sets for Embree 3.13
/// built with one instance level.
fn context() -> sys::RTCIntersectContext {
    sys::RTCIntersectContext {
        flags: sys::RTCIntersectContextFlags::INCOHERENT,
        filter: None,
        instID: [INVALID_ID],
    }
}

/// [`context`] with the coherent flag, which Embree's packet traversal uses for rays that
/// travel together.
fn coherent_context() -> sys::RTCIntersectContext {
    sys::RTCIntersectContext {
        flags: sys::RTCIntersectContextFlags::COHERENT,
        ..context()
    }
}

fn to_rtc(ray: &Ray) -> sys::RTCRay {
    sys::RTCRay {
        org_x: ray.origin.x,
        org_y: ray.origin.y,
        org_z: ray.origin.z,
        tnear: ray.t_min,
        dir_x: ray.dir().x,
        dir_y: ray.dir().y,
        dir_z: ray.dir().z,
        time: 0.0,
        tfar: ray.t_max,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

fn device_error(device: sys::RTCDevice, call: &str) -> String {
    // SAFETY: `device` is a live device handle.
    let code = unsafe { sys::rtcGetDeviceError(device) };
    format!("{call} failed: Embree error {code:?}")
}

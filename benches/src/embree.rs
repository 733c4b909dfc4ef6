//! Embree 3 as a measured baseline: a safe wrapper over the few calls of the `embree` crate's raw
//! `sys` bindings that the benchmarks need (build a triangle scene, trace one ray, test one
//! occlusion ray, and the same for packets of 16 coherent rays). Needs Debian's `libembree-dev` (3.13) and the feature `embree`.
//!
//! This is one of the two modules of the workspace allowed `unsafe` (foreign calls cannot be
//! written without it); every block says why it is sound.
#![allow(unsafe_code)]

use embree::sys;
use rt_core::glam::Vec3;
use rt_core::{Hit, Ray, Triangle};
use std::ffi::CString;

/// How Embree builds a scene: its build quality (`rtcSetSceneBuildQuality`) and scene flags
/// (`rtcSetSceneFlags`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    /// Embree's default: build quality medium (binned SAH, no spatial splits), no scene flags.
    Medium,
    /// Build quality high (SAH with spatial splits): slower builds, faster traversal.
    High,
    /// Build quality medium with `RTC_SCENE_FLAG_ROBUST`: Embree's robust mode, which avoids
    /// the optimizations that may miss a hit on an edge (what Open3D's `RaycastingScene`
    /// ships): the Embree mode whose guarantee is closest to the watertight test's.
    Robust,
}

impl Quality {
    /// Every configuration, the default first.
    pub const ALL: [Quality; 3] = [Quality::Medium, Quality::High, Quality::Robust];

    /// The name the benchmarks print: `medium`, `high` or `robust`.
    pub fn name(self) -> &'static str {
        match self {
            Quality::Medium => "medium",
            Quality::High => "high",
            Quality::Robust => "robust",
        }
    }
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
    /// `primID` `i`), with the build quality and scene flags of `quality`.
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
                    Quality::Medium | Quality::Robust => sys::RTCBuildQuality::MEDIUM,
                    Quality::High => sys::RTCBuildQuality::HIGH,
                },
            );
            if quality == Quality::Robust {
                sys::rtcSetSceneFlags(scene, sys::RTCSceneFlags::ROBUST);
            }
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
            hit: no_hit(),
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

/// The lanes of one 8-wide Embree packet call (`rtcIntersect8`).
pub const PACKET8: usize = 8;

/// The rays of one Embree stream call (`rtcIntersect1M`): a camera's 8×8 tile.
pub const STREAM: usize = 64;

/// Embree's packet calls of one width with the coherent flag, as two methods of
/// [`EmbreeScene`]: the closest hits of `rays` into `out` (as many as both have), and whether
/// anything is hit in each ray's interval, `$n` consecutive rays per call.
macro_rules! packet_calls {
    ($n:expr, $valid:ident, $align:literal, $rayhit:ident, $ray:ident, $intersect:ident,
     $occluded:ident, $closest:ident, $any:ident) => {
        /// A packet's valid mask: -1 for an active lane, 0 for an unused one, aligned as Embree
        /// loads it.
        #[repr(C, align($align))]
        struct $valid([i32; $n]);

        impl $valid {
            /// Writes `rays` (at most a packet's worth) into the packet's lanes and returns the
            /// mask of those lanes.
            fn fill(rays: &[Ray], p: &mut sys::$ray) -> Self {
                let mut valid = $valid([0; $n]);
                for (i, r) in rays.iter().enumerate().take($n) {
                    valid.0[i] = -1;
                    (p.org_x[i], p.org_y[i], p.org_z[i]) = (r.origin.x, r.origin.y, r.origin.z);
                    (p.dir_x[i], p.dir_y[i], p.dir_z[i]) = (r.dir().x, r.dir().y, r.dir().z);
                    (p.tnear[i], p.tfar[i], p.mask[i]) = (r.t_min, r.t_max, u32::MAX);
                }
                valid
            }
        }

        impl EmbreeScene {
            #[doc = concat!("The closest hits of `rays` into `out`, ", stringify!($n),
                        " rays per `", stringify!($intersect), "` call with the coherent flag.")]
            pub fn $closest(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
                for (rays, out) in rays.chunks($n).zip(out.chunks_mut($n)) {
                    let n = rays.len().min(out.len());
                    // SAFETY: the packet is plain old data (arrays of f32 and u32), for which
                    // all zero bytes are a valid value.
                    let mut packet: sys::$rayhit = unsafe { std::mem::zeroed() };
                    let valid = $valid::fill(&rays[..n], &mut packet.ray);
                    packet.hit.geomID[..n].fill(INVALID_ID);
                    packet.hit.primID[..n].fill(INVALID_ID);
                    let mut context = coherent_context();
                    // SAFETY: a committed scene alive until `Drop`; `valid` and `packet` are
                    // locals aligned as Embree's packet loads require (the mask by its type,
                    // the packet by bindgen's `repr(align)`), only accessed during the call.
                    unsafe {
                        sys::$intersect(valid.0.as_ptr(), self.scene, &mut context, &mut packet)
                    };
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

            #[doc = concat!("Whether anything is hit in each ray's interval, into `out`, ",
                        stringify!($n), " rays per `", stringify!($occluded),
                        "` call with the coherent flag.")]
            pub fn $any(&self, rays: &[Ray], out: &mut [bool]) {
                for (rays, out) in rays.chunks($n).zip(out.chunks_mut($n)) {
                    let n = rays.len().min(out.len());
                    // SAFETY: as in the closest-hit call: plain old data, all zeros valid.
                    let mut p: sys::$ray = unsafe { std::mem::zeroed() };
                    let valid = $valid::fill(&rays[..n], &mut p);
                    let mut context = coherent_context();
                    // SAFETY: as in the closest-hit call.
                    unsafe { sys::$occluded(valid.0.as_ptr(), self.scene, &mut context, &mut p) };
                    for (i, o) in out[..n].iter_mut().enumerate() {
                        *o = p.tfar[i] == f32::NEG_INFINITY;
                    }
                }
            }
        }
    };
}

packet_calls!(
    PACKET,
    Valid16,
    64,
    RTCRayHit16,
    RTCRay16,
    rtcIntersect16,
    rtcOccluded16,
    intersect_packets,
    occluded_packets
);
packet_calls!(
    PACKET8,
    Valid8,
    32,
    RTCRayHit8,
    RTCRay8,
    rtcIntersect8,
    rtcOccluded8,
    intersect_packets8,
    occluded_packets8
);

impl EmbreeScene {
    /// The closest hits of `rays` into `out`, `STREAM` consecutive rays per `rtcIntersect1M`
    /// call with the coherent flag: Embree's stream path, which gathers the stream's rays into
    /// packets itself.
    pub fn intersect_stream(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        let blank = sys::RTCRayHit {
            ray: to_rtc(&Ray::new(Vec3::ZERO, Vec3::X)),
            hit: no_hit(),
        };
        let mut stream = [blank; STREAM];
        for (rays, out) in rays.chunks(STREAM).zip(out.chunks_mut(STREAM)) {
            let n = rays.len().min(out.len());
            for (s, r) in stream.iter_mut().zip(&rays[..n]) {
                *s = sys::RTCRayHit {
                    ray: to_rtc(r),
                    ..blank
                };
            }
            let mut context = coherent_context();
            // SAFETY: a committed scene; `stream` holds at least `n` valid `RTCRayHit`s laid
            // out `size_of::<RTCRayHit>()` bytes apart, aligned to 16 as Embree requires, and
            // is only accessed during the call.
            unsafe {
                sys::rtcIntersect1M(
                    self.scene,
                    &mut context,
                    stream.as_mut_ptr(),
                    n as u32,
                    std::mem::size_of::<sys::RTCRayHit>(),
                )
            };
            for (o, s) in out[..n].iter_mut().zip(&stream) {
                *o = (s.hit.geomID != INVALID_ID).then_some(Hit {
                    prim: s.hit.primID,
                    t: s.ray.tfar,
                    u: s.hit.u,
                    v: s.hit.v,
                });
            }
        }
    }

    /// Whether anything is hit in each ray's interval, into `out`, `STREAM` rays per
    /// `rtcOccluded1M` call with the coherent flag.
    pub fn occluded_stream(&self, rays: &[Ray], out: &mut [bool]) {
        let blank = to_rtc(&Ray::new(Vec3::ZERO, Vec3::X));
        let mut stream = [blank; STREAM];
        for (rays, out) in rays.chunks(STREAM).zip(out.chunks_mut(STREAM)) {
            let n = rays.len().min(out.len());
            for (s, r) in stream.iter_mut().zip(&rays[..n]) {
                *s = to_rtc(r);
            }
            let mut context = coherent_context();
            // SAFETY: as in `intersect_stream`, with `RTCRay`s.
            unsafe {
                sys::rtcOccluded1M(
                    self.scene,
                    &mut context,
                    stream.as_mut_ptr(),
                    n as u32,
                    std::mem::size_of::<sys::RTCRay>(),
                )
            };
            for (o, s) in out[..n].iter_mut().zip(&stream) {
                *o = s.tfar == f32::NEG_INFINITY;
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

/// A hit record that says nothing was hit, as Embree expects it before a closest-hit call.
fn no_hit() -> sys::RTCHit {
    sys::RTCHit {
        Ng_x: 0.0,
        Ng_y: 0.0,
        Ng_z: 0.0,
        u: 0.0,
        v: 0.0,
        primID: INVALID_ID,
        geomID: INVALID_ID,
        instID: [INVALID_ID],
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

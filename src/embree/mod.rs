//! Safe wrapper over Intel Embree (3 or 4, found by build.rs) through our C
//! shim. This is the only module allowed to contain `unsafe` code.
//!
//! Ownership follows the types: a [`Device`] makes a [`SceneBuilder`], which
//! owns the triangle buffers it shares with Embree and becomes an immutable,
//! thread-safe [`Scene`] on [`SceneBuilder::commit`]. Errors Embree reports
//! through its error callback come back as [`EmbreeError`] results.
#![allow(unsafe_code)]

mod sys;

use std::cell::Cell;
use std::ffi::{CStr, CString};
use std::ptr::NonNull;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Instant;

use glam::{Affine3A, Vec2, Vec3, Vec4};

/// An error reported by Embree (through the device's error callback or
/// `rtcGetDeviceError`), or by the shim when Embree returned no object.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("Embree error {code} ({kind}) while {context}: {message}")]
pub struct EmbreeError {
    /// Embree's `RTCError` value.
    pub code: i32,
    /// Embree's name for the code.
    pub kind: &'static str,
    /// What lightcuts was doing.
    pub context: &'static str,
    /// Embree's message.
    pub message: String,
}

fn error_kind(code: i32) -> &'static str {
    match code {
        1 => "RTC_ERROR_UNKNOWN",
        2 => "RTC_ERROR_INVALID_ARGUMENT",
        3 => "RTC_ERROR_INVALID_OPERATION",
        4 => "RTC_ERROR_OUT_OF_MEMORY",
        5 => "RTC_ERROR_UNSUPPORTED_CPU",
        6 => "RTC_ERROR_CANCELLED",
        _ => "RTC_ERROR_OTHER",
    }
}

fn to_error(raw: &sys::LcError, context: &'static str) -> Option<EmbreeError> {
    if raw.code == 0 {
        return None;
    }
    // SAFETY: the shim always NUL-terminates `message` (copy_message writes a
    // '\0' at its last byte, and memset/zero-initialisation fills the rest).
    let message = unsafe { CStr::from_ptr(raw.message.as_ptr()) };
    Some(EmbreeError {
        code: raw.code,
        kind: error_kind(raw.code),
        context,
        message: message.to_string_lossy().into_owned(),
    })
}

/// The version of the Embree library lightcuts was built against, e.g. `(3, 13, 5)`.
#[must_use]
pub fn version() -> (u32, u32, u32) {
    // SAFETY: a pure function returning a compile-time constant.
    let v = unsafe { sys::lc_embree_version() } as u32;
    (v / 10000, (v / 100) % 100, v % 100)
}

/// Turns on flush-to-zero and denormals-are-zero for the calling thread, as
/// Embree's documentation recommends for every thread that traces rays (the
/// renderer calls it from each worker thread's start handler).
pub fn set_flush_denormals() {
    // SAFETY: only changes the calling thread's MXCSR floating-point modes.
    unsafe { sys::lc_set_flush_denormals() }
}

/// Whether flush-to-zero and denormals-are-zero are both on for this thread.
#[must_use]
pub fn flush_denormals_enabled() -> bool {
    // SAFETY: only reads the calling thread's MXCSR.
    unsafe { sys::lc_flush_denormals_enabled() != 0 }
}

static TIMING: AtomicBool = AtomicBool::new(false);
static TIMED_NANOS: AtomicU64 = AtomicU64::new(0);

thread_local! {
    static THREAD_TIMED_NANOS: Cell<u64> = const { Cell::new(0) };
}

/// Turns on (or off) timing of every ray query, summed over threads, for
/// `render --stats`. Off by default: two clock reads per call are not free.
pub fn set_timing(enabled: bool) {
    TIMING.store(enabled, Ordering::Relaxed);
}

/// Whether ray queries are being timed.
#[must_use]
pub fn timing() -> bool {
    TIMING.load(Ordering::Relaxed)
}

/// Nanoseconds spent inside Embree queries since timing was turned on,
/// summed over all threads.
#[must_use]
pub fn timed_nanos() -> u64 {
    TIMED_NANOS.load(Ordering::Relaxed)
}

/// Nanoseconds the calling thread has spent inside timed Embree queries.
#[must_use]
pub fn thread_timed_nanos() -> u64 {
    THREAD_TIMED_NANOS.with(Cell::get)
}

#[inline]
fn timed<R>(query: impl FnOnce() -> R) -> R {
    if TIMING.load(Ordering::Relaxed) {
        let start = Instant::now();
        let result = query();
        let nanos = start.elapsed().as_nanos() as u64;
        TIMED_NANOS.fetch_add(nanos, Ordering::Relaxed);
        THREAD_TIMED_NANOS.with(|t| t.set(t.get() + nanos));
        result
    } else {
        query()
    }
}

struct DeviceHandle(NonNull<sys::LcDevice>);

// SAFETY: an Embree device is thread-safe (Embree's docs: all API calls on a
// device may come from any thread), and the shim guards the recorded error
// with a mutex.
unsafe impl Send for DeviceHandle {}
// SAFETY: as for Send; shared references only call thread-safe functions.
unsafe impl Sync for DeviceHandle {}

impl Drop for DeviceHandle {
    fn drop(&mut self) {
        // SAFETY: the handle came from lc_device_new and is released once; every
        // scene holds an Arc to this handle, so none outlives it.
        unsafe { sys::lc_device_release(self.0.as_ptr()) }
    }
}

/// An Embree device. Cheap to clone (reference-counted).
#[derive(Clone)]
pub struct Device {
    handle: Arc<DeviceHandle>,
}

impl Device {
    /// Creates a device with Embree's default configuration.
    pub fn try_new() -> Result<Self, EmbreeError> {
        let config = CString::new("").expect("no interior NUL");
        let mut raw = sys::LcError::default();
        // SAFETY: config is a valid C string; raw is a valid out-parameter.
        let ptr = unsafe { sys::lc_device_new(config.as_ptr(), &mut raw) };
        match NonNull::new(ptr) {
            Some(ptr) => Ok(Self { handle: Arc::new(DeviceHandle(ptr)) }),
            None => Err(to_error(&raw, "creating the device").unwrap_or(EmbreeError {
                code: 1,
                kind: error_kind(1),
                context: "creating the device",
                message: "rtcNewDevice returned NULL".into(),
            })),
        }
    }

    /// Returns the first error Embree reported since the last check, if any.
    fn check(&self, context: &'static str) -> Result<(), EmbreeError> {
        let mut raw = sys::LcError::default();
        // SAFETY: the device pointer is live (owned by self); raw is a valid out-parameter.
        unsafe { sys::lc_device_take_error(self.handle.0.as_ptr(), &mut raw) };
        match to_error(&raw, context) {
            Some(error) => Err(error),
            None => Ok(()),
        }
    }

    /// Makes Embree report an error on this device through its own API (a
    /// geometry of a type that does not exist), as a failure while tracing
    /// would: for tests of the renderer's error checks.
    #[doc(hidden)]
    pub fn provoke_error_for_tests(&self) {
        // SAFETY: the device pointer is live for as long as self; the shim
        // releases whatever Embree returns.
        unsafe { sys::lc_device_provoke_error(self.handle.0.as_ptr()) }
    }

    /// Starts a new scene on this device.
    pub fn try_new_scene(&self) -> Result<SceneBuilder, EmbreeError> {
        // SAFETY: the device pointer is live for as long as self.
        let ptr = unsafe { sys::lc_scene_new(self.handle.0.as_ptr()) };
        self.check("creating a scene")?;
        let ptr = NonNull::new(ptr).ok_or(EmbreeError {
            code: 4,
            kind: error_kind(4),
            context: "creating a scene",
            message: "rtcNewScene returned NULL".into(),
        })?;
        Ok(SceneBuilder { raw: SceneHandle { ptr, device: self.clone() }, meshes: Vec::new(), instanced: Vec::new() })
    }
}

/// Number of `f32`s to allocate for `vertex_count` float3 vertices shared with
/// Embree: Embree reads each vertex with a 16-byte SSE load, so the buffer
/// must extend at least 16 bytes past the start of the last vertex (one float
/// more than 3 per vertex). Embree's `rtcSetSharedGeometryBuffer` docs.
#[must_use]
pub fn padded_vertex_floats(vertex_count: usize) -> usize {
    if vertex_count == 0 {
        // Embree still may touch the pointer: keep one 16-byte load readable.
        4
    } else {
        (vertex_count - 1) * 3 + 4
    }
}

/// A triangle mesh's buffers, shared with Embree (never moved once attached:
/// the Vecs are not touched again, so their heap storage stays put).
struct SharedMesh {
    _vertices: Vec<f32>,
    _indices: Vec<u32>,
    /// The cut-out's description and the buffers it points into.
    _mask: Option<MaskBuffers>,
}

struct MaskBuffers {
    _raw: Box<sys::LcAlphaMask>,
    _uvs: Vec<f32>,
    _alpha: Vec<f32>,
}

// SAFETY: the mask's raw pointers point into buffers it (and its mesh) own;
// nothing writes them after attachment, and Embree's filter callback only
// reads them, from any tracing thread, as the scene allows (see SceneHandle).
unsafe impl Send for MaskBuffers {}
// SAFETY: as for Send: shared access is read-only.
unsafe impl Sync for MaskBuffers {}

/// A cut-out (glTF's alphaMode MASK): hits where the alpha, looked up at the
/// hit's texture coordinate, is below `cutoff` are skipped by every query;
/// without a cutoff, partial coverage (glTF's BLEND): a hit is kept with
/// probability alpha, drawn from a hash of the ray and the primitive (the
/// same ray meets the same surfaces on any thread).
#[derive(Debug, Clone)]
pub struct AlphaMask {
    /// Texture coordinates, one per vertex.
    pub uvs: Vec<Vec2>,
    /// Alpha texels, `width * height`, row 0 at the top.
    pub alpha: Vec<f32>,
    pub width: u32,
    pub height: u32,
    /// From the mesh's uv to the lookup's (v = 0 at the image's bottom row),
    /// as the colour texture's (see `scene::Albedo::Texture`).
    pub transform: glam::Affine2,
    pub cutoff: Option<f32>,
}

struct SceneHandle {
    ptr: NonNull<sys::LcScene>,
    device: Device,
}

// SAFETY: a committed Embree scene may be traced from any number of threads
// at once (Embree's docs: rtcIntersect1/rtcOccluded1 are thread-safe on a
// committed scene); the builder is only mutated through &mut.
unsafe impl Send for SceneHandle {}
// SAFETY: as for Send; &Scene only exposes the thread-safe query functions.
unsafe impl Sync for SceneHandle {}

impl Drop for SceneHandle {
    fn drop(&mut self) {
        // SAFETY: created by lc_scene_new, released once; the device outlives it
        // because self.device keeps it alive.
        unsafe { sys::lc_scene_release(self.ptr.as_ptr()) }
    }
}

/// A scene being assembled: attach meshes and instances, then
/// [`commit`](Self::commit).
pub struct SceneBuilder {
    raw: SceneHandle,
    meshes: Vec<SharedMesh>,
    /// The scenes instanced here: Embree reads them while this one is
    /// traced, so this one keeps them alive.
    instanced: Vec<Arc<Scene>>,
}

/// Most time steps a moving instance may have (Embree's limit, 129).
pub const MAX_TIME_STEPS: usize = 129;

/// Geometry id of an attached mesh (Embree's geomID).
pub type GeometryId = u32;

/// An error in the data handed to [`SceneBuilder::attach_triangles`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MeshError {
    /// An index refers past the vertex list (caller's data is malformed).
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has {vertex_count} vertices")]
    IndexOutOfRange { triangle: usize, index: u32, vertex_count: usize },
    /// A curve segment reads control points past the end.
    #[error("curve segment {segment} reads {order} control points past the {vertex_count} given")]
    SegmentOutOfRange { segment: usize, order: usize, vertex_count: usize },
    /// A cut-out whose uvs do not match the vertices, or an empty mask.
    #[error("the alpha mask has {uvs} texture coordinates for {vertex_count} vertices, or no texels")]
    BadMask { uvs: usize, vertex_count: usize },
    /// A vertex coordinate is NaN or infinite (or a strand's radius
    /// negative).
    #[error("vertex {vertex} is not finite (or its radius is negative)")]
    NonFiniteVertex { vertex: usize },
    /// An instance's transform is not finite or not invertible (the
    /// caller's data), it has no time step or more than Embree allows, or
    /// its scene belongs to another device.
    #[error(
        "the instance's transforms are not finite and invertible, not 1 to 129 time steps, or its scene is another device's"
    )]
    BadInstance,
    /// Embree rejected the buffers.
    #[error(transparent)]
    Embree(#[from] EmbreeError),
}

impl SceneBuilder {
    /// Attaches a triangle mesh, copying its data into buffers padded as
    /// Embree requires. Indices are checked against the vertex count.
    pub fn attach_triangles(&mut self, vertices: &[Vec3], triangles: &[[u32; 3]]) -> Result<GeometryId, MeshError> {
        self.attach_masked_triangles(vertices, triangles, None)
    }

    /// [`Self::attach_triangles`], with a cut-out when `mask` is given.
    pub fn attach_masked_triangles(
        &mut self,
        vertices: &[Vec3],
        triangles: &[[u32; 3]],
        mask: Option<AlphaMask>,
    ) -> Result<GeometryId, MeshError> {
        if let Some(m) = &mask {
            let texels = m.width as usize * m.height as usize;
            if m.uvs.len() != vertices.len() || m.alpha.len() != texels || texels == 0 {
                return Err(MeshError::BadMask { uvs: m.uvs.len(), vertex_count: vertices.len() });
            }
        }
        if let Some(vertex) = vertices.iter().position(|v| !v.is_finite()) {
            return Err(MeshError::NonFiniteVertex { vertex });
        }
        for (triangle, tri) in triangles.iter().enumerate() {
            for &index in tri {
                if index as usize >= vertices.len() {
                    return Err(MeshError::IndexOutOfRange { triangle, index, vertex_count: vertices.len() });
                }
            }
        }
        let mut vertex_floats = vec![0.0f32; padded_vertex_floats(vertices.len())];
        for (i, v) in vertices.iter().enumerate() {
            vertex_floats[3 * i..3 * i + 3].copy_from_slice(&v.to_array());
        }
        // Index buffers are read element-wise, but keep them 16-byte readable too.
        let mut index_u32 = Vec::with_capacity(triangles.len() * 3 + 1);
        index_u32.extend(triangles.iter().flatten().copied());
        index_u32.push(0);
        // SAFETY: both buffers are live heap allocations owned by self.meshes
        // until the scene is dropped (they are pushed below and never mutated or
        // reallocated), their lengths cover the counts passed, the vertex buffer
        // is padded for 16-byte loads, and all indices were checked in range.
        let id = unsafe {
            sys::lc_scene_attach_triangles(
                self.raw.ptr.as_ptr(),
                vertex_floats.as_ptr(),
                vertices.len(),
                index_u32.as_ptr(),
                triangles.len(),
            )
        };
        self.attached(id, "attaching a triangle mesh")?;
        let mask = mask.map(|m| {
            let uvs: Vec<f32> = m.uvs.iter().flat_map(|uv| uv.to_array()).collect();
            let (a, alpha) = (m.transform, m.alpha);
            let raw = Box::new(sys::LcAlphaMask {
                indices: index_u32.as_ptr(),
                uvs: uvs.as_ptr(),
                alpha: alpha.as_ptr(),
                width: m.width,
                height: m.height,
                transform: [
                    a.matrix2.x_axis.x,
                    a.matrix2.x_axis.y,
                    a.matrix2.y_axis.x,
                    a.matrix2.y_axis.y,
                    a.translation.x,
                    a.translation.y,
                ],
                // The shim's mark of partial coverage.
                cutoff: m.cutoff.unwrap_or(-1.0),
            });
            // SAFETY: the geometry was attached above and the scene is not
            // yet committed; `raw` and the buffers it points into (the index
            // buffer, `uvs` and `alpha`, whose heap storage does not move
            // when the Vecs are moved) are owned by self.meshes until the
            // scene is dropped and never mutated; the uvs cover every vertex
            // the checked indices name, and alpha holds width x height texels.
            unsafe { sys::lc_scene_set_alpha_mask(self.raw.ptr.as_ptr(), id, &*raw) };
            MaskBuffers { _raw: raw, _uvs: uvs, _alpha: alpha }
        });
        self.meshes.push(SharedMesh { _vertices: vertex_floats, _indices: index_u32, _mask: mask });
        self.raw.device.check("setting an alpha mask")?;
        Ok(id)
    }

    /// Attaches curves (Embree's own curve geometry): `points` are the
    /// control points (xyz) with their radii (w), `segments` the first
    /// control point of each segment (a segment reads `basis.order()`
    /// consecutive points). A hit's `u` is the parameter along its
    /// segment; its `ng` is the tube's normal on a round curve but the
    /// curve's tangent on a flat one (Embree's convention).
    pub fn attach_curves(
        &mut self,
        basis: CurveBasis,
        shape: CurveShape,
        points: &[Vec4],
        segments: &[u32],
    ) -> Result<GeometryId, MeshError> {
        check_strand_points(points)?;
        let order = basis.order();
        if let Some(segment) = segments.iter().position(|&s| s as usize + order > points.len()) {
            return Err(MeshError::SegmentOutOfRange { segment, order, vertex_count: points.len() });
        }
        let vertices: Vec<f32> = points.iter().flat_map(|p| p.to_array()).collect();
        let mut indices = segments.to_vec();
        indices.push(0);
        let raw_basis = match basis {
            CurveBasis::Linear => sys::LcCurveBasis_LC_CURVE_LINEAR,
            CurveBasis::Bezier => sys::LcCurveBasis_LC_CURVE_BEZIER,
            CurveBasis::BSpline => sys::LcCurveBasis_LC_CURVE_BSPLINE,
            CurveBasis::CatmullRom => sys::LcCurveBasis_LC_CURVE_CATMULL_ROM,
        };
        let raw_shape = match shape {
            CurveShape::Round => sys::LcCurveShape_LC_CURVE_ROUND,
            CurveShape::Flat => sys::LcCurveShape_LC_CURVE_FLAT,
        };
        // SAFETY: the buffers are heap allocations owned by self.meshes until
        // the scene is dropped (pushed below, never mutated or reallocated);
        // `vertices` holds 4 floats a point, and every segment's control
        // points were checked to lie within the points.
        let id = unsafe {
            sys::lc_scene_attach_curves(
                self.raw.ptr.as_ptr(),
                raw_basis,
                raw_shape,
                vertices.as_ptr(),
                points.len(),
                indices.as_ptr(),
                segments.len(),
            )
        };
        self.attached(id, "attaching curves")?;
        self.meshes.push(SharedMesh { _vertices: vertices, _indices: indices, _mask: None });
        Ok(id)
    }

    /// Attaches spheres (Embree's sphere points): centres (xyz) and radii
    /// (w). A hit's `ng` is the sphere's outward normal.
    pub fn attach_spheres(&mut self, spheres: &[Vec4]) -> Result<GeometryId, MeshError> {
        check_strand_points(spheres)?;
        let vertices: Vec<f32> = spheres.iter().flat_map(|p| p.to_array()).collect();
        // SAFETY: `vertices` (4 floats a sphere) is owned by self.meshes
        // until the scene is dropped, pushed below and never mutated.
        let id = unsafe { sys::lc_scene_attach_spheres(self.raw.ptr.as_ptr(), vertices.as_ptr(), spheres.len()) };
        self.attached(id, "attaching spheres")?;
        self.meshes.push(SharedMesh { _vertices: vertices, _indices: Vec::new(), _mask: None });
        Ok(id)
    }

    /// Attaches an instance of `child` (a committed scene of one mesh, made
    /// on the same device) placed by `transform`, from the child's space to
    /// this scene's: hits on it report the instance's geometry id and the
    /// child mesh's primitive and barycentrics.
    pub fn attach_instance(&mut self, child: &Arc<Scene>, transform: Affine3A) -> Result<GeometryId, MeshError> {
        self.attach_moving_instance(child, &[transform])
    }

    /// [`Self::attach_instance`] through Embree's motion blur: `steps`
    /// (1 to [`MAX_TIME_STEPS`]) are the placements at evenly spaced times
    /// of the shutter, the first at its open (time 0) and the last at its
    /// close (time 1); Embree interpolates the matrices linearly between
    /// them, and a ray meets the instance where it is at the ray's time.
    pub fn attach_moving_instance(&mut self, child: &Arc<Scene>, steps: &[Affine3A]) -> Result<GeometryId, MeshError> {
        let same_device = Arc::ptr_eq(&child.raw.device.handle, &self.raw.device.handle);
        let invertible = |t: &Affine3A| t.is_finite() && t.matrix3.determinant() != 0.0;
        if !same_device || !(1..=MAX_TIME_STEPS).contains(&steps.len()) || !steps.iter().all(invertible) {
            return Err(MeshError::BadInstance);
        }
        let columns: Vec<f32> = steps
            .iter()
            .flat_map(|s| {
                let (m, t) = (s.matrix3, s.translation);
                [
                    m.x_axis.x, m.x_axis.y, m.x_axis.z, m.y_axis.x, m.y_axis.y, m.y_axis.z, m.z_axis.x, m.z_axis.y,
                    m.z_axis.z, t.x, t.y, t.z,
                ]
            })
            .collect();
        // SAFETY: both scenes are live and of the same device (checked);
        // the child is committed (a `Scene` only exists committed) and kept
        // alive by self.instanced for as long as this scene; `columns`
        // holds 12 floats per step for the step count passed (1 to 129,
        // checked), which Embree copies during the call.
        let id = unsafe {
            sys::lc_scene_attach_instance(
                self.raw.ptr.as_ptr(),
                child.raw.ptr.as_ptr(),
                columns.as_ptr(),
                steps.len() as u32,
            )
        };
        self.attached(id, "attaching an instance")?;
        self.instanced.push(Arc::clone(child));
        Ok(id)
    }

    /// The device's error after an attach returned `id`, else an error
    /// when the shim could not make the geometry (LC_INVALID_ID).
    fn attached(&self, id: GeometryId, context: &'static str) -> Result<(), MeshError> {
        self.raw.device.check(context)?;
        if id == sys::LC_INVALID_ID {
            return Err(MeshError::Embree(EmbreeError {
                code: 1,
                kind: error_kind(1),
                context,
                message: "rtcNewGeometry failed".into(),
            }));
        }
        Ok(())
    }

    /// Builds Embree's acceleration structure; the result is read-only and
    /// may be traced from many threads.
    pub fn commit(self) -> Result<Scene, EmbreeError> {
        // SAFETY: the scene pointer is live; commit is called once, from one thread.
        unsafe { sys::lc_scene_commit(self.raw.ptr.as_ptr()) };
        self.raw.device.check("committing the scene")?;
        Ok(Scene { raw: self.raw, _meshes: self.meshes, _instanced: self.instanced })
    }
}

/// The alignments (valid mask, ray packet, what Embree requires) of the
/// structures the shim hands to `rtcOccluded<width>`, in bytes.
#[must_use]
pub fn packet_alignment(width: PacketWidth) -> (u32, u32, u32) {
    // SAFETY: a pure function of its argument.
    let a = unsafe { sys::lc_packet_alignment(width as i32) };
    (a.valid_mask, a.packet, a.required)
}

static REFUSED_RAYS: AtomicU64 = AtomicU64::new(0);

/// How many rays were not handed to Embree because [`Ray::is_valid`] refused
/// them (a non-finite or out-of-range component), since the process began:
/// a shadow ray refused reads as blocked, a closest-hit query as a miss.
/// The renderer reports a non-zero count.
#[must_use]
pub fn refused_rays() -> u64 {
    REFUSED_RAYS.load(Ordering::Relaxed)
}

/// A ray: origin, direction, the parametric interval `[t_near, t_far]`
/// measured in lengths of `direction`, and the time it is traced at, in
/// the shutter interval: 0 at its open, 1 at its close (moving geometry is
/// where it is at that time; 0 in a scene without motion).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub direction: Vec3,
    pub t_near: f32,
    pub t_far: f32,
    pub time: f32,
}

/// Embree's `FLT_LARGE`: a ray component beyond it is invalid, and an
/// assertion-enabled Embree (Debian's) aborts on it.
pub const MAX_RAY_COMPONENT: f32 = 1.844e18;

impl Ray {
    /// Whether Embree accepts this ray: finite components within
    /// [`MAX_RAY_COMPONENT`] and a non-negative, ordered interval. The scene
    /// loader's coordinate limit guarantees it for every ray the renderer casts.
    #[must_use]
    pub fn is_valid(&self) -> bool {
        let within = |v: Vec3| v.is_finite() && v.abs().max_element() <= MAX_RAY_COMPONENT;
        within(self.origin)
            && within(self.direction)
            && self.t_near >= 0.0
            && !self.t_far.is_nan()
            && self.t_near <= self.t_far
            && (0.0..=1.0).contains(&self.time)
    }

    /// The ray in the shim's layout, or None (counted in [`refused_rays`])
    /// when Embree must not see it: Debian's Embree is built with
    /// assertions and aborts the process on such a ray, and another build
    /// would trace garbage. Checked in every build, at about a nanosecond a
    /// ray against Embree's tens.
    fn to_sys(self) -> Option<sys::LcRay> {
        if !self.is_valid() {
            REFUSED_RAYS.fetch_add(1, Ordering::Relaxed);
            return None;
        }
        Some(sys::LcRay {
            org: self.origin.to_array(),
            tnear: self.t_near,
            dir: self.direction.to_array(),
            tfar: self.t_far,
            time: self.time,
        })
    }
}

/// The closest hit of a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Barycentric coordinates: the hit is `(1-u-v) p0 + u p1 + v p2`.
    pub u: f32,
    pub v: f32,
    /// Unnormalised geometric normal, `(p1 - p0) x (p2 - p0)` (Embree's convention).
    pub ng: Vec3,
    pub geometry: GeometryId,
    pub primitive: u32,
}

/// The basis of a curve's control points (USD's `basis`, and `type =
/// linear`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CurveBasis {
    Linear,
    Bezier,
    BSpline,
    CatmullRom,
}

impl CurveBasis {
    /// How many consecutive control points one segment reads.
    #[must_use]
    pub fn order(self) -> usize {
        match self {
            Self::Linear => 2,
            Self::Bezier | Self::BSpline | Self::CatmullRom => 4,
        }
    }

    /// The two control points (offsets from a segment's first) that a
    /// quantity given per control point is interpolated between along the
    /// segment: its ends for linear and Bezier segments, the middle two
    /// for B-spline and Catmull-Rom ones (which pass near or through them).
    #[must_use]
    pub fn ends(self) -> (usize, usize) {
        match self {
            Self::Linear => (0, 1),
            Self::Bezier => (0, 3),
            Self::BSpline | Self::CatmullRom => (1, 2),
        }
    }
}

/// How a curve's cross-section is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CurveShape {
    /// A tube whose radius the control points give.
    Round,
    /// A ribbon turned to face each ray. (Embree's normal-oriented
    /// ribbons are not offered: Debian's Embree 3.13 reports no hit on
    /// them, docs/design.md §4.3.)
    Flat,
}

/// Finite centres and finite, non-negative radii.
fn check_strand_points(points: &[Vec4]) -> Result<(), MeshError> {
    match points.iter().position(|p| !p.is_finite() || p.w < 0.0) {
        Some(vertex) => Err(MeshError::NonFiniteVertex { vertex }),
        None => Ok(()),
    }
}

/// A committed, read-only scene. `Sync`: trace from any number of threads.
pub struct Scene {
    raw: SceneHandle,
    _meshes: Vec<SharedMesh>,
    _instanced: Vec<Arc<Scene>>,
}

impl Scene {
    /// The closest hit along `ray`, or `None`.
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let ray = ray.to_sys()?;
        let mut hit = sys::LcHit::default();
        // SAFETY: the scene is committed and live; ray and hit are valid for the call.
        let found = timed(|| unsafe { sys::lc_intersect1(self.raw.ptr.as_ptr(), &ray, &mut hit) });
        (found != 0).then(|| from_sys_hit(&hit))
    }

    /// Closest hits of many rays in one call into Embree.
    pub fn intersect_batch(&self, rays: &[Ray], hits: &mut Vec<Option<Hit>>) {
        // A refused ray becomes one that misses everything: an empty interval.
        let raw_rays: Vec<sys::LcRay> = rays.iter().map(|r| r.to_sys().unwrap_or(ShadowRay::BLOCKED.0)).collect();
        let mut raw_hits = vec![sys::LcHit::default(); rays.len()];
        // SAFETY: both arrays hold rays.len() elements; the scene is committed.
        unsafe { sys::lc_intersect_batch(self.raw.ptr.as_ptr(), raw_rays.as_ptr(), raw_hits.as_mut_ptr(), rays.len()) };
        hits.clear();
        hits.extend(raw_hits.iter().map(|h| (h.geom_id != sys::LC_INVALID_ID).then(|| from_sys_hit(h))));
    }

    /// Whether anything blocks `ray` inside `[t_near, t_far]`.
    #[must_use]
    pub fn occluded(&self, ray: &Ray) -> bool {
        let Some(ray) = ray.to_sys() else { return true };
        // SAFETY: the scene is committed and live; ray is valid for the call.
        timed(|| unsafe { sys::lc_occluded1(self.raw.ptr.as_ptr(), &ray) != 0 })
    }

    /// The first error Embree reported on this scene's device since the
    /// last check, as an error saying what lightcuts was doing. Embree's ray
    /// queries report nothing themselves (a failing query leaves the ray as
    /// if unoccluded), so the renderer checks after every tile and pass.
    pub fn take_error(&self, context: &'static str) -> Result<(), EmbreeError> {
        self.raw.device.check(context)
    }

    /// The device this scene was made on.
    #[must_use]
    pub fn device(&self) -> &Device {
        &self.raw.device
    }

    /// Occlusion of many rays in one call into Embree (what the renderer
    /// uses). `occluded` is resized to `rays.len()`.
    pub fn occluded_batch(&self, rays: &[ShadowRay], occluded: &mut Vec<bool>) {
        occluded.clear();
        occluded.resize(rays.len(), false);
        if rays.is_empty() {
            return;
        }
        // SAFETY: ShadowRay is repr(transparent) over sys::LcRay, so the slice
        // is a valid array of rays.len() LcRay. `occluded` holds rays.len()
        // bools; bool is one byte and the shim writes only 0 or 1 into each,
        // both valid bool values, so writing through a u8 pointer is sound.
        timed(|| unsafe {
            sys::lc_occluded_batch(
                self.raw.ptr.as_ptr(),
                rays.as_ptr().cast::<sys::LcRay>(),
                occluded.as_mut_ptr().cast::<u8>(),
                rays.len(),
            )
        });
    }
}

/// How many rays Embree traces together in a packet query.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PacketWidth {
    Four = 4,
    Eight = 8,
    Sixteen = 16,
}

impl Scene {
    /// Occlusion of many rays, traced `width` at a time by Embree's packet
    /// queries (rtcOccluded4/8/16). `occluded` is resized to `rays.len()`.
    pub fn occluded_packets(&self, rays: &[ShadowRay], occluded: &mut Vec<bool>, width: PacketWidth) {
        occluded.clear();
        occluded.resize(rays.len(), false);
        if rays.is_empty() {
            return;
        }
        // SAFETY: as for `occluded_batch`: ShadowRay is repr(transparent)
        // over sys::LcRay, `occluded` holds rays.len() one-byte bools and the
        // shim writes only 0 or 1 into them; the shim copies each packet
        // into its own aligned RTCRayN, so the input needs no alignment, and
        // the width is one the shim accepts (it returns -1 otherwise).
        let status = timed(|| unsafe {
            sys::lc_occluded_packets(
                self.raw.ptr.as_ptr(),
                rays.as_ptr().cast::<sys::LcRay>(),
                occluded.as_mut_ptr().cast::<u8>(),
                rays.len(),
                width as i32,
            )
        });
        debug_assert_eq!(status, 0, "every PacketWidth is supported by the shim");
    }
}

fn from_sys_hit(hit: &sys::LcHit) -> Hit {
    Hit { t: hit.t, u: hit.u, v: hit.v, ng: Vec3::from_array(hit.ng), geometry: hit.geom_id, primitive: hit.prim_id }
}

/// A ray in the layout the batch occlusion call takes, so a batch is built
/// once and handed to Embree without copying.
#[derive(Clone, Copy)]
#[repr(transparent)]
pub struct ShadowRay(sys::LcRay);

impl ShadowRay {
    /// A ray Embree skips (its interval is empty: t_far = -inf < t_near)
    /// and whose t_far reads back as Embree's mark of an occluded ray: what
    /// a refused ray becomes, so that it blocks its light instead of
    /// letting it leak.
    const BLOCKED: Self =
        Self(sys::LcRay { org: [0.0; 3], tnear: 0.0, dir: [0.0, 0.0, 1.0], tfar: f32::NEG_INFINITY, time: 0.0 });

    /// The shadow ray, or [`ShadowRay::BLOCKED`] when Embree must not see
    /// it (see [`refused_rays`]).
    #[must_use]
    pub fn new(ray: Ray) -> Self {
        ray.to_sys().map_or(Self::BLOCKED, Self)
    }

    /// The ray back in our own type.
    #[must_use]
    pub fn to_ray(&self) -> Ray {
        Ray {
            origin: Vec3::from_array(self.0.org),
            direction: Vec3::from_array(self.0.dir),
            t_near: self.0.tnear,
            t_far: self.0.tfar,
            time: self.0.time,
        }
    }
}

impl std::fmt::Debug for ShadowRay {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShadowRay")
            .field("origin", &self.0.org)
            .field("direction", &self.0.dir)
            .field("t_near", &self.0.tnear)
            .field("t_far", &self.0.tfar)
            .field("time", &self.0.time)
            .finish()
    }
}

#[cfg(test)]
mod tests;

/* lightcuts' own C interface to Intel Embree 3 or 4.
 *
 * Every Embree type stays inside shim.c: this header declares only our own
 * plain-C types, so the Rust bindings that bindgen makes from it are the same
 * for both Embree majors and cannot disagree with Embree's struct layouts
 * (Embree 4.3's RTCRayHit is 96 bytes, 4.2's was 80).
 */
#ifndef LIGHTCUTS_EMBREE_SHIM_H
#define LIGHTCUTS_EMBREE_SHIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Opaque handles: a device (with its recorded error) and a scene. */
typedef struct LcDevice LcDevice;
typedef struct LcScene LcScene;

/* A ray: origin, direction (need not be normalised), the parametric
 * interval [tnear, tfar] in units of the direction's length, and its time
 * in the shutter interval, 0 at its open and 1 at its close (Embree's ray
 * time, which moving geometry is placed at). */
typedef struct LcRay {
    float org[3];
    float tnear;
    float dir[3];
    float tfar;
    float time;
} LcRay;

/* The closest hit of a ray. geom_id is LC_INVALID_ID on a miss; on an
 * instance (lc_scene_attach_instance) it is the instance's geometry id, and
 * prim_id, u and v are the instanced mesh's. */
typedef struct LcHit {
    float t;
    float u;
    float v;
    float ng[3]; /* unnormalised geometric normal, Embree's convention */
    uint32_t geom_id;
    uint32_t prim_id;
} LcHit;

#define LC_INVALID_ID 0xFFFFFFFFu

/* The first error Embree reported on a device since the last take. */
typedef struct LcError {
    int32_t code;       /* Embree's RTCError value; 0 means none */
    char message[256];  /* NUL-terminated */
} LcError;

/* The major.minor.patch of the Embree library this shim was compiled against,
 * as major * 10000 + minor * 100 + patch (Embree's RTC_VERSION). */
int32_t lc_embree_version(void);

/* Creates a device; NULL on failure, with the reason in *error. */
LcDevice* lc_device_new(const char* config, LcError* error);
void lc_device_release(LcDevice* device);
/* Moves the first recorded error into *error (code 0 when none) and clears it. */
void lc_device_take_error(LcDevice* device, LcError* error);

LcScene* lc_scene_new(LcDevice* device);
void lc_scene_release(LcScene* scene);
/* Attaches a triangle mesh whose buffers stay owned by the caller and must
 * outlive the scene. vertices: vertex_count float3 with stride 12 bytes and
 * padding readable by a 16-byte load past the last vertex; indices:
 * triangle_count uint32 triples. Returns the geometry id, or LC_INVALID_ID. */
uint32_t lc_scene_attach_triangles(LcScene* scene,
                                   const float* vertices, size_t vertex_count,
                                   const uint32_t* indices, size_t triangle_count);
/* Attaches an instance of `child`, a committed scene of the same device
 * holding one geometry, placed by affine maps from its space to this
 * scene's: `step_count` (1 to 129) transforms of 12 floats each,
 * column-major 3 x 4 (the images of the x, y and z axes, then the
 * translation). One step is a still placement; several are Embree's motion
 * blur: step k is the placement at time k / (step_count - 1), and Embree
 * interpolates the matrices linearly between steps. `child` must outlive
 * the scene. Returns the geometry id, or LC_INVALID_ID. */
uint32_t lc_scene_attach_instance(LcScene* scene, const LcScene* child, const float* transforms,
                                  uint32_t step_count);
/* The basis of a curve's control points, and how its cross-section is
 * drawn: Embree's curve geometry types (RTC_GEOMETRY_TYPE_*_CURVE). */
typedef enum LcCurveBasis {
    LC_CURVE_LINEAR = 0,      /* 2 control points a segment */
    LC_CURVE_BEZIER = 1,      /* 4, cubic Bernstein */
    LC_CURVE_BSPLINE = 2,     /* 4, uniform cubic B-spline */
    LC_CURVE_CATMULL_ROM = 3  /* 4, Catmull-Rom */
} LcCurveBasis;

typedef enum LcCurveShape {
    LC_CURVE_ROUND = 0, /* a tube of the control points' radii */
    LC_CURVE_FLAT = 1   /* a ribbon facing the ray */
} LcCurveShape;

/* Attaches curves whose buffers stay owned by the caller and must outlive
 * the scene. vertices: vertex_count (x, y, z, radius) quadruples;
 * segments: segment_count indices of each segment's first control point.
 * A hit's u is the parameter along its segment; its ng is the tube's
 * normal on a round curve but the curve's tangent on a flat one (Embree's
 * convention). Returns the geometry id, or LC_INVALID_ID. */
uint32_t lc_scene_attach_curves(LcScene* scene, LcCurveBasis basis, LcCurveShape shape,
                                const float* vertices, size_t vertex_count, const uint32_t* segments,
                                size_t segment_count);

/* Attaches spheres (Embree's sphere points): `count` (x, y, z, radius)
 * quadruples owned by the caller, outliving the scene. Returns the
 * geometry id, or LC_INVALID_ID. */
uint32_t lc_scene_attach_spheres(LcScene* scene, const float* spheres, size_t count);

/* A cut-out (glTF's alphaMode MASK): a hit on the mesh whose alpha, looked up
 * bilinearly (repeating) at the hit's texture coordinate, is below `cutoff`
 * is ignored by every query (closest hit, occlusion, packets), through
 * Embree's intersection and occlusion filter functions. A negative `cutoff`
 * makes the alpha a partial coverage instead (glTF's BLEND): a hit is kept
 * with probability alpha, decided by a hash of the ray and the hit, so that
 * the same ray always meets the same surfaces. All pointers are owned by
 * the caller and must outlive the scene. */
typedef struct LcAlphaMask {
    const uint32_t* indices; /* the mesh's triangles, 3 per triangle */
    const float* uvs;        /* 2 per vertex */
    const float* alpha;      /* width * height, row 0 at the top */
    uint32_t width;
    uint32_t height;
    /* (u, v) -> (m[0] u + m[2] v + m[4], m[1] u + m[3] v + m[5]): the lookup
     * coordinate, whose v = 0 is the image's bottom row. */
    float transform[6];
    float cutoff;
} LcAlphaMask;

/* Makes geometry `geom_id` (attached, not yet committed scene) a cut-out. */
void lc_scene_set_alpha_mask(LcScene* scene, uint32_t geom_id, const LcAlphaMask* mask);

void lc_scene_commit(LcScene* scene);

/* Closest hit along one ray; returns 1 on a hit, 0 on a miss. */
int32_t lc_intersect1(LcScene* scene, const LcRay* ray, LcHit* hit);
/* Closest hits of n rays in one call. */
void lc_intersect_batch(LcScene* scene, const LcRay* rays, LcHit* hits, size_t n);
/* Returns 1 when anything blocks the ray inside [tnear, tfar]. */
int32_t lc_occluded1(LcScene* scene, const LcRay* ray);
/* occluded[i] = 1 when rays[i] is blocked, in one call for n rays. */
void lc_occluded_batch(LcScene* scene, const LcRay* rays, uint8_t* occluded, size_t n);

/* occluded[i] = 1 when rays[i] is blocked, for n rays traced as packets of
 * `width` rays (4, 8 or 16: rtcOccluded4/8/16; the last packet is padded
 * with inactive lanes; a packet of one or two rays is traced ray by ray).
 * Returns 0, or -1 for an unsupported width. */
int32_t lc_occluded_packets(LcScene* scene, const LcRay* rays, uint8_t* occluded, size_t n, int32_t width);

/* The alignments, in bytes, of the structures lc_occluded_packets hands
 * to rtcOccluded<width> (its valid mask and its ray packet), and the
 * alignment Embree requires of both: 16, 32 and 64 bytes for widths 4, 8
 * and 16 (rtcOccluded4/8/16's documentation). Zeros for another width. */
typedef struct LcPacketAlignment {
    uint32_t valid_mask;
    uint32_t packet;
    uint32_t required;
} LcPacketAlignment;
LcPacketAlignment lc_packet_alignment(int32_t width);

/* Makes Embree itself report an error on the device (a geometry of a type
 * that does not exist), as a failure while tracing would: for the tests of
 * the renderer's error checks. */
void lc_device_provoke_error(LcDevice* device);

/* Sets flush-to-zero and denormals-are-zero on the calling thread, as Embree's
 * documentation recommends for every thread that traces rays. */
void lc_set_flush_denormals(void);
/* 1 when both modes are on for the calling thread. */
int32_t lc_flush_denormals_enabled(void);

#ifdef __cplusplus
}
#endif

#endif

/* lightcuts' Embree shim: the only C in the project. It hides the API
 * differences between Embree 3 (intersect contexts, default geometry mask
 * 0xFFFFFFFF) and Embree 4 (argument structs, default geometry mask 1) behind
 * the types of shim.h. LC_EMBREE_MAJOR is set by build.rs. */
#include "shim.h"

#include <assert.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <xmmintrin.h>
#include <pmmintrin.h>

#if LC_EMBREE_MAJOR == 4
#include <embree4/rtcore.h>
#elif LC_EMBREE_MAJOR == 3
#include <embree3/rtcore.h>
#else
#error "LC_EMBREE_MAJOR must be 3 or 4"
#endif

/* Every ray and every geometry uses all mask bits: Embree 4 changed the
 * default geometry mask from 0xFFFFFFFF to 1, so both are set explicitly. */
#define LC_MASK_ALL 0xFFFFFFFFu

struct LcDevice {
    RTCDevice device;
    pthread_mutex_t lock; /* Embree may call the error callback from any thread */
    LcError first_error;
};

struct LcScene {
    LcDevice* owner;
    RTCScene scene;
};

int32_t lc_embree_version(void) { return RTC_VERSION; }

static void copy_message(LcError* error, enum RTCError code, const char* message) {
    error->code = (int32_t)code;
    if (message == NULL) message = "";
    strncpy(error->message, message, sizeof error->message - 1);
    error->message[sizeof error->message - 1] = '\0';
}

static void on_error(void* user, enum RTCError code, const char* message) {
    LcDevice* device = (LcDevice*)user;
    pthread_mutex_lock(&device->lock);
    if (device->first_error.code == 0) copy_message(&device->first_error, code, message);
    pthread_mutex_unlock(&device->lock);
}

LcDevice* lc_device_new(const char* config, LcError* error) {
    memset(error, 0, sizeof *error);
    RTCDevice rtc = rtcNewDevice(config);
    if (rtc == NULL) {
        copy_message(error, rtcGetDeviceError(NULL), "rtcNewDevice failed (unsupported CPU or bad config)");
        return NULL;
    }
    LcDevice* device = (LcDevice*)calloc(1, sizeof *device);
    if (device == NULL) {
        rtcReleaseDevice(rtc);
        copy_message(error, RTC_ERROR_OUT_OF_MEMORY, "out of memory allocating the device wrapper");
        return NULL;
    }
    device->device = rtc;
    pthread_mutex_init(&device->lock, NULL);
    rtcSetDeviceErrorFunction(rtc, on_error, device);
    return device;
}

void lc_device_release(LcDevice* device) {
    if (device == NULL) return;
    rtcReleaseDevice(device->device);
    pthread_mutex_destroy(&device->lock);
    free(device);
}

void lc_device_take_error(LcDevice* device, LcError* error) {
    pthread_mutex_lock(&device->lock);
    *error = device->first_error;
    memset(&device->first_error, 0, sizeof device->first_error);
    pthread_mutex_unlock(&device->lock);
    /* Embree also keeps the code of the calling thread's last error, which
     * its callback has reported already: read it always, so that it is
     * cleared and never blamed on a later call. */
    enum RTCError code = rtcGetDeviceError(device->device);
    if (error->code == 0 && code != RTC_ERROR_NONE) copy_message(error, code, "Embree device error");
}

LcScene* lc_scene_new(LcDevice* device) {
    RTCScene rtc = rtcNewScene(device->device);
    if (rtc == NULL) return NULL;
    LcScene* scene = (LcScene*)calloc(1, sizeof *scene);
    if (scene == NULL) {
        rtcReleaseScene(rtc);
        return NULL;
    }
    scene->owner = device;
    scene->scene = rtc;
    /* Robust traversal: watertight enough for shadow rays that graze edges. */
    rtcSetSceneFlags(rtc, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(rtc, RTC_BUILD_QUALITY_HIGH);
    return scene;
}

void lc_scene_release(LcScene* scene) {
    if (scene == NULL) return;
    rtcReleaseScene(scene->scene);
    free(scene);
}

uint32_t lc_scene_attach_triangles(LcScene* scene, const float* vertices, size_t vertex_count,
                                   const uint32_t* indices, size_t triangle_count) {
    RTCGeometry geometry = rtcNewGeometry(scene->owner->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (geometry == NULL) return LC_INVALID_ID;
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices, 0,
                               3 * sizeof(float), vertex_count);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices, 0,
                               3 * sizeof(uint32_t), triangle_count);
    rtcSetGeometryMask(geometry, LC_MASK_ALL);
    rtcCommitGeometry(geometry);
    unsigned int id = rtcAttachGeometry(scene->scene, geometry);
    rtcReleaseGeometry(geometry); /* the scene holds its own reference */
    return (uint32_t)id;
}

uint32_t lc_scene_attach_instance(LcScene* scene, const LcScene* child, const float* transforms,
                                  uint32_t step_count) {
    RTCGeometry geometry = rtcNewGeometry(scene->owner->device, RTC_GEOMETRY_TYPE_INSTANCE);
    if (geometry == NULL) return LC_INVALID_ID;
    rtcSetGeometryInstancedScene(geometry, child->scene);
    /* Embree's default time range is [0, 1]: step k sits at k / (steps - 1). */
    rtcSetGeometryTimeStepCount(geometry, step_count);
    for (uint32_t k = 0; k < step_count; ++k)
        rtcSetGeometryTransform(geometry, k, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, transforms + 12 * (size_t)k);
    rtcSetGeometryMask(geometry, LC_MASK_ALL);
    rtcCommitGeometry(geometry);
    unsigned int id = rtcAttachGeometry(scene->scene, geometry);
    rtcReleaseGeometry(geometry); /* the scene holds its own reference */
    return (uint32_t)id;
}

static enum RTCGeometryType curve_type(LcCurveBasis basis, LcCurveShape shape) {
    static const enum RTCGeometryType types[4][2] = {
        {RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE, RTC_GEOMETRY_TYPE_FLAT_LINEAR_CURVE},
        {RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE, RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE},
        {RTC_GEOMETRY_TYPE_ROUND_BSPLINE_CURVE, RTC_GEOMETRY_TYPE_FLAT_BSPLINE_CURVE},
        {RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE, RTC_GEOMETRY_TYPE_FLAT_CATMULL_ROM_CURVE},
    };
    /* RTC_GEOMETRY_TYPE_USER marks a value outside the enums. */
    if ((unsigned)basis > 3u || (unsigned)shape > 1u) return RTC_GEOMETRY_TYPE_USER;
    return types[basis][shape];
}

uint32_t lc_scene_attach_curves(LcScene* scene, LcCurveBasis basis, LcCurveShape shape,
                                const float* vertices, size_t vertex_count, const uint32_t* segments,
                                size_t segment_count) {
    enum RTCGeometryType type = curve_type(basis, shape);
    if (type == RTC_GEOMETRY_TYPE_USER) return LC_INVALID_ID;
    RTCGeometry geometry = rtcNewGeometry(scene->owner->device, type);
    if (geometry == NULL) return LC_INVALID_ID;
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, vertices, 0,
                               4 * sizeof(float), vertex_count);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, segments, 0,
                               sizeof(uint32_t), segment_count);
    rtcSetGeometryMask(geometry, LC_MASK_ALL);
    rtcCommitGeometry(geometry);
    unsigned int id = rtcAttachGeometry(scene->scene, geometry);
    rtcReleaseGeometry(geometry); /* the scene holds its own reference */
    return (uint32_t)id;
}

uint32_t lc_scene_attach_spheres(LcScene* scene, const float* spheres, size_t count) {
    RTCGeometry geometry = rtcNewGeometry(scene->owner->device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    if (geometry == NULL) return LC_INVALID_ID;
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, spheres, 0,
                               4 * sizeof(float), count);
    rtcSetGeometryMask(geometry, LC_MASK_ALL);
    rtcCommitGeometry(geometry);
    unsigned int id = rtcAttachGeometry(scene->scene, geometry);
    rtcReleaseGeometry(geometry); /* the scene holds its own reference */
    return (uint32_t)id;
}

static float mask_texel(const LcAlphaMask* m, long x, long y) {
    long w = (long)m->width, h = (long)m->height;
    x %= w;
    y %= h;
    if (x < 0) x += w;
    if (y < 0) y += h;
    return m->alpha[(size_t)y * m->width + (size_t)x];
}

/* The mask's alpha at a hit: the same bilinear, repeating lookup as the
 * renderer's textures (texture.rs), so a cut-out edge is where the colour
 * texture's alpha crosses the cutoff. */
static float mask_alpha(const LcAlphaMask* m, unsigned prim, float u, float v) {
    const uint32_t* t = &m->indices[3 * (size_t)prim];
    float w = 1.0f - u - v;
    float su = w * m->uvs[2 * t[0]] + u * m->uvs[2 * t[1]] + v * m->uvs[2 * t[2]];
    float sv = w * m->uvs[2 * t[0] + 1] + u * m->uvs[2 * t[1] + 1] + v * m->uvs[2 * t[2] + 1];
    const float* a = m->transform;
    float lu = a[0] * su + a[2] * sv + a[4];
    float lv = a[1] * su + a[3] * sv + a[5];
    if (!isfinite(lu) || !isfinite(lv)) return 1.0f;
    float x = (lu - floorf(lu)) * (float)m->width - 0.5f;
    float y = (1.0f - (lv - floorf(lv))) * (float)m->height - 0.5f;
    float x0 = floorf(x), y0 = floorf(y);
    float fx = x - x0, fy = y - y0;
    long ix = (long)x0, iy = (long)y0;
    float top = mask_texel(m, ix, iy) * (1.0f - fx) + mask_texel(m, ix + 1, iy) * fx;
    float bottom = mask_texel(m, ix, iy + 1) * (1.0f - fx) + mask_texel(m, ix + 1, iy + 1) * fx;
    return top * (1.0f - fy) + bottom * fy;
}

/* Fields of lane i of an N-wide RTCHitN: Embree's SoA layout (Ng_x, Ng_y,
 * Ng_z, u, v, primID, ... each N wide, the same in Embree 3 and 4), which
 * its RTCHitN_u and friends read but declare for C++ only. */
static float hitn_u(const struct RTCHitN* hit, unsigned n, unsigned i) { return ((const float*)hit)[3 * n + i]; }
static float hitn_v(const struct RTCHitN* hit, unsigned n, unsigned i) { return ((const float*)hit)[4 * n + i]; }
static unsigned hitn_prim(const struct RTCHitN* hit, unsigned n, unsigned i) { return ((const unsigned*)hit)[5 * n + i]; }
static unsigned hitn_geom(const struct RTCHitN* hit, unsigned n, unsigned i) { return ((const unsigned*)hit)[6 * n + i]; }

/* Word k of lane i of an N-wide RTCRayN: Embree's SoA layout (org_x, org_y,
 * org_z, tnear, dir_x, dir_y, dir_z, time, ... each N wide, the same in
 * Embree 3 and 4). */
static uint32_t rayn_word(const struct RTCRayN* ray, unsigned n, unsigned i, unsigned k) {
    return ((const uint32_t*)ray)[k * n + i];
}

/* SplitMix64's finaliser: every input bit reaches every output bit. */
static uint64_t mix64(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* A uniform number in [0, 1) that is a function of lane i's ray (origin,
 * direction, time) and the primitive it hit: partial coverage's draw. A
 * camera sample's ray, a bounce's and a shadow ray's each carry their own
 * sample's jitter, so their draws are independent of each other, and the
 * same ray draws the same number on any thread. */
static float coverage_draw(const struct RTCFilterFunctionNArguments* args, unsigned i, unsigned prim) {
    uint64_t h = 0x6c62272e07bb0142ULL ^ prim ^ ((uint64_t)hitn_geom(args->hit, args->N, i) << 32);
    static const unsigned words[7] = {0, 1, 2, 4, 5, 6, 7};
    for (unsigned k = 0; k < 7; ++k) h = mix64(h ^ ((uint64_t)rayn_word(args->ray, args->N, i, words[k]) << 17) ^ k);
    return (float)(h >> 40) * (1.0f / 16777216.0f);
}

/* Embree's filter callback (both majors, any packet width N): rejects the
 * hits where the mask is below its cutoff (or, for partial coverage, where
 * the draw is not below the alpha), so traversal goes on past them. */
static void alpha_filter(const struct RTCFilterFunctionNArguments* args) {
    const LcAlphaMask* m = (const LcAlphaMask*)args->geometryUserPtr;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        unsigned prim = hitn_prim(args->hit, args->N, i);
        float u = hitn_u(args->hit, args->N, i);
        float v = hitn_v(args->hit, args->N, i);
        float alpha = mask_alpha(m, prim, u, v);
        int absent = m->cutoff < 0.0f ? !(coverage_draw(args, i, prim) < alpha) : alpha < m->cutoff;
        if (absent) args->valid[i] = 0;
    }
}

void lc_scene_set_alpha_mask(LcScene* scene, uint32_t geom_id, const LcAlphaMask* mask) {
    RTCGeometry geometry = rtcGetGeometry(scene->scene, geom_id);
    if (geometry == NULL) return;
    rtcSetGeometryUserData(geometry, (void*)mask);
    rtcSetGeometryIntersectFilterFunction(geometry, alpha_filter);
    rtcSetGeometryOccludedFilterFunction(geometry, alpha_filter);
    rtcCommitGeometry(geometry);
}

void lc_scene_commit(LcScene* scene) { rtcCommitScene(scene->scene); }

static void to_rtc_ray(const LcRay* in, struct RTCRay* out) {
    out->org_x = in->org[0];
    out->org_y = in->org[1];
    out->org_z = in->org[2];
    out->tnear = in->tnear;
    out->dir_x = in->dir[0];
    out->dir_y = in->dir[1];
    out->dir_z = in->dir[2];
    out->time = in->time;
    out->tfar = in->tfar;
    out->mask = LC_MASK_ALL;
    out->id = 0;
    out->flags = 0;
}

static int32_t intersect_one(RTCScene scene, const LcRay* ray, LcHit* hit) {
    struct RTCRayHit rayhit;
    to_rtc_ray(ray, &rayhit.ray);
    rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
#if LC_EMBREE_MAJOR == 4
    rtcIntersect1(scene, &rayhit, NULL);
#else
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcIntersect1(scene, &context, &rayhit);
#endif
    if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        memset(hit, 0, sizeof *hit);
        hit->geom_id = LC_INVALID_ID;
        hit->prim_id = LC_INVALID_ID;
        return 0;
    }
    hit->t = rayhit.ray.tfar;
    hit->u = rayhit.hit.u;
    hit->v = rayhit.hit.v;
    hit->ng[0] = rayhit.hit.Ng_x;
    hit->ng[1] = rayhit.hit.Ng_y;
    hit->ng[2] = rayhit.hit.Ng_z;
    /* A hit inside an instance names the instance (its child scenes hold
     * one geometry each); Ng stays in the instanced mesh's space. */
    hit->geom_id = rayhit.hit.instID[0] != RTC_INVALID_GEOMETRY_ID ? rayhit.hit.instID[0] : rayhit.hit.geomID;
    hit->prim_id = rayhit.hit.primID;
    return 1;
}

int32_t lc_intersect1(LcScene* scene, const LcRay* ray, LcHit* hit) {
    return intersect_one(scene->scene, ray, hit);
}

void lc_intersect_batch(LcScene* scene, const LcRay* rays, LcHit* hits, size_t n) {
    for (size_t i = 0; i < n; ++i) intersect_one(scene->scene, &rays[i], &hits[i]);
}

/* Embree 4 removed the ray-stream API (rtcOccluded1M); one call per ray inside
 * this loop keeps the FFI crossing to one per batch on both majors. */
static int32_t occluded_one(RTCScene scene, const LcRay* in) {
    struct RTCRay ray;
    to_rtc_ray(in, &ray);
#if LC_EMBREE_MAJOR == 4
    rtcOccluded1(scene, &ray, NULL);
#else
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcOccluded1(scene, &context, &ray);
#endif
    /* Embree sets tfar to -inf when the ray is occluded. */
    return ray.tfar < 0.0f && isinf(ray.tfar);
}

int32_t lc_occluded1(LcScene* scene, const LcRay* ray) { return occluded_one(scene->scene, ray); }

void lc_occluded_batch(LcScene* scene, const LcRay* rays, uint8_t* occluded, size_t n) {
    for (size_t i = 0; i < n; ++i) occluded[i] = (uint8_t)occluded_one(scene->scene, &rays[i]);
}

/* A packet's valid mask: one int per lane (-1 active, 0 inactive), aligned
 * as its packet must be (4 W bytes: rtcOccluded4/8/16 require 16, 32 and 64;
 * Embree's RTCRay4/8/16 declare the same alignment themselves). */
#define LC_VALID_MASK(W)                                                               \
    typedef struct LcValid##W {                                                        \
        _Alignas(4 * W) int lane[W];                                                   \
    } LcValid##W;                                                                      \
    _Static_assert(_Alignof(LcValid##W) == 4 * W, "valid mask alignment");            \
    _Static_assert(_Alignof(struct RTCRay##W) >= 4 * W, "ray packet alignment");

LC_VALID_MASK(4)
LC_VALID_MASK(8)
LC_VALID_MASK(16)

/* One packet of up to W rays (W = 4, 8, 16): copied into Embree's SoA
 * layout, lanes past `count` invalid; occlusion read back from tfar. */
#define LC_PACKET(W)                                                                   \
    static void occluded_packet##W(RTCScene scene, const LcRay* in, uint8_t* out, size_t count) { \
        struct RTCRay##W packet;                                                       \
        LcValid##W valid;                                                              \
        assert(((uintptr_t)&packet | (uintptr_t)&valid) % (4 * W) == 0);               \
        for (int i = 0; i < W; ++i) {                                                  \
            const LcRay* r = &in[(size_t)i < count ? (size_t)i : 0];                   \
            valid.lane[i] = (size_t)i < count ? -1 : 0;                                \
            packet.org_x[i] = r->org[0];                                               \
            packet.org_y[i] = r->org[1];                                               \
            packet.org_z[i] = r->org[2];                                               \
            packet.tnear[i] = r->tnear;                                                \
            packet.dir_x[i] = r->dir[0];                                               \
            packet.dir_y[i] = r->dir[1];                                               \
            packet.dir_z[i] = r->dir[2];                                               \
            packet.time[i] = r->time;                                                  \
            packet.tfar[i] = r->tfar;                                                  \
            packet.mask[i] = LC_MASK_ALL;                                              \
            packet.id[i] = (unsigned)i;                                                \
            packet.flags[i] = 0;                                                       \
        }                                                                              \
        LC_OCCLUDED_PACKET(W, valid.lane, scene, &packet);                             \
        for (size_t i = 0; i < count; ++i)                                             \
            out[i] = packet.tfar[i] < 0.0f && isinf(packet.tfar[i]);                   \
    }

#if LC_EMBREE_MAJOR == 4
#define LC_OCCLUDED_PACKET(W, valid, scene, packet) rtcOccluded##W(valid, scene, packet, NULL)
#else
#define LC_OCCLUDED_PACKET(W, valid, scene, packet)                                    \
    do {                                                                               \
        struct RTCIntersectContext context;                                            \
        rtcInitIntersectContext(&context);                                             \
        rtcOccluded##W(valid, scene, &context, packet);                                \
    } while (0)
#endif

LC_PACKET(4)
LC_PACKET(8)
LC_PACKET(16)

/* A packet of at most this many rays is traced ray by ray. */
#define LC_SINGLE_RAYS 2

int32_t lc_occluded_packets(LcScene* scene, const LcRay* rays, uint8_t* occluded, size_t n, int32_t width) {
    void (*trace)(RTCScene, const LcRay*, uint8_t*, size_t);
    switch (width) {
    case 4: trace = occluded_packet4; break;
    case 8: trace = occluded_packet8; break;
    case 16: trace = occluded_packet16; break;
    default: return -1;
    }
    for (size_t start = 0; start < n; start += (size_t)width) {
        size_t count = n - start < (size_t)width ? n - start : (size_t)width;
        if (count <= LC_SINGLE_RAYS) {
            /* A packet costs its traversal whatever its lanes: with one or
             * two active rays, Embree's single-ray queries are cheaper
             * (docs/notebook/measurements.md, "Draws over the whole cut"). */
            for (size_t i = 0; i < count; ++i)
                occluded[start + i] = (uint8_t)occluded_one(scene->scene, &rays[start + i]);
        } else {
            trace(scene->scene, &rays[start], &occluded[start], count);
        }
    }
    return 0;
}

LcPacketAlignment lc_packet_alignment(int32_t width) {
    LcPacketAlignment a = {0, 0, 0};
    switch (width) {
    case 4: a = (LcPacketAlignment){_Alignof(LcValid4), _Alignof(struct RTCRay4), 16}; break;
    case 8: a = (LcPacketAlignment){_Alignof(LcValid8), _Alignof(struct RTCRay8), 32}; break;
    case 16: a = (LcPacketAlignment){_Alignof(LcValid16), _Alignof(struct RTCRay16), 64}; break;
    default: break;
    }
    return a;
}

void lc_device_provoke_error(LcDevice* device) {
    /* Embree reports "invalid geometry type" through the device's error
     * callback and returns NULL. */
    RTCGeometry geometry = rtcNewGeometry(device->device, (enum RTCGeometryType)0x7fff);
    if (geometry != NULL) rtcReleaseGeometry(geometry);
}

void lc_set_flush_denormals(void) {
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}

int32_t lc_flush_denormals_enabled(void) {
    return _MM_GET_FLUSH_ZERO_MODE() == _MM_FLUSH_ZERO_ON &&
           _MM_GET_DENORMALS_ZERO_MODE() == _MM_DENORMALS_ZERO_ON;
}

/* Embree 3 on the rays `cargo run --release --example rays -- SCENE SIZE FILE` wrote:
 * the same triangles, spheres and cones, the same primary, shadow and mirror rays, on
 * THREADS threads taking chunks of 64 rays from a shared counter, as rayon does on our
 * side. Each kind of ray through each of Embree's kernels: primary rays one at a time
 * (rtcIntersect1) and in packets of 8 (rtcIntersect8, half a 4x4 block of pixels) and 16
 * (rtcIntersect16, the block); shadow rays by rtcOccluded1, 8 and 16 (a group of 16 is a
 * block's rays to one light; empty slots are masked off); mirror rays, which are
 * incoherent, by rtcIntersect1. Prints Mrays/s (best of five runs) and how often Embree's
 * answers match ours.
 *
 * Our shadow rays go on through surfaces that transmit light, multiplying what each
 * crossing lets through, where rtcOccluded stops at the first surface it meets. So the
 * shadow rays are traced twice: by plain rtcOccluded (shadow1, 8, 16), and through a second
 * scene in which the transmitting primitives are geometries of their own with an occlusion
 * filter that multiplies the ray's light by what the crossing lets through and lets the ray
 * go on (through1, 8, 16: our answers, the way a renderer on Embree gets them; the opaque
 * primitives have no filter, so a ray stops at one as before).
 *
 *   cc -O3 -march=native -o rays rays.c -lembree3 -lpthread -lm
 *   ./rays FILE [THREADS]
 *
 * Triangles and spheres are Embree's own primitives (RTC_GEOMETRY_TYPE_TRIANGLE and
 * SPHERE_POINT); cones, which Embree lacks, are user geometry intersected by a C port of
 * our `intersect_cone` (open sides, no caps), lane by lane for packets. */
#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define CHUNK 64

typedef struct { float *data; unsigned n; } Array;

static Array read_array(FILE *f, unsigned floats_per_item, const char *what) {
    Array a;
    if (fread(&a.n, 4, 1, f) != 1) { fprintf(stderr, "truncated file at %s\n", what); exit(2); }
    size_t count = (size_t)a.n * floats_per_item;
    a.data = malloc(count * sizeof(float) + 1);
    if (!a.data || fread(a.data, sizeof(float), count, f) != count) {
        fprintf(stderr, "truncated file in %s\n", what);
        exit(2);
    }
    return a;
}

/* ---- cones: user geometry ---- */

typedef struct { float p0[3], r0, p1[3], r1; } Cone;

/* A cone geometry's user data: its cones, and for the second scene's shadow rays what a
 * crossing of each lets through (3 floats a cone; NULL: every cone stops a ray). */
typedef struct { const Cone *cones; unsigned n; const float *through; } Cones;

static const Cone *cone_of(void *user, unsigned primID) { return ((const Cones *)user)->cones + primID; }

static void cone_bounds(const struct RTCBoundsFunctionArguments *args) {
    const Cone *c = cone_of(args->geometryUserPtr, args->primID);
    float r = c->r0 > c->r1 ? c->r0 : c->r1;
    struct RTCBounds *b = args->bounds_o;
    b->lower_x = fminf(c->p0[0], c->p1[0]) - r; b->upper_x = fmaxf(c->p0[0], c->p1[0]) + r;
    b->lower_y = fminf(c->p0[1], c->p1[1]) - r; b->upper_y = fmaxf(c->p0[1], c->p1[1]) + r;
    b->lower_z = fminf(c->p0[2], c->p1[2]) - r; b->upper_z = fmaxf(c->p0[2], c->p1[2]) + r;
}

static float dot3(const float *a, const float *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Our intersect_cone: the two crossings of the side between the caps, or INFINITY. The
 * axis measured by s, 0 at the base and 1 at the apex, as ours is (one division). */
static void cone_hits(const Cone *c, const float *o, const float *d, float t[2]) {
    float axis[3] = {c->p1[0] - c->p0[0], c->p1[1] - c->p0[1], c->p1[2] - c->p0[2]};
    float inv = 1.0f / dot3(axis, axis);
    float delta = c->r1 - c->r0;
    float mid[3] = {0.5f * (c->p0[0] + c->p1[0]) - o[0], 0.5f * (c->p0[1] + c->p1[1]) - o[1],
                    0.5f * (c->p0[2] + c->p1[2]) - o[2]};
    float tc = dot3(mid, d);
    float co[3], dp[3], cp[3];
    for (int i = 0; i < 3; i++) co[i] = o[i] + tc * d[i] - c->p0[i];
    float dv = dot3(d, axis) * inv, cv = dot3(co, axis) * inv;
    for (int i = 0; i < 3; i++) { dp[i] = d[i] - dv * axis[i]; cp[i] = co[i] - cv * axis[i]; }
    float rr = c->r0 + delta * cv;
    float kd = delta * dv;
    float qa = dot3(dp, dp) - kd * kd;
    float qb = dot3(cp, dp) - rr * kd;
    float qc = dot3(cp, cp) - rr * rr;
    float r[2] = {INFINITY, INFINITY};
    if (fabsf(qa) < 1e-12f) {
        if (qb != 0.0f) r[0] = -qc / (2.0f * qb);
    } else {
        float disc = qb * qb - qa * qc;
        if (disc < 0.0f) { t[0] = t[1] = INFINITY; return; }
        float sq = sqrtf(disc);
        float r0 = (-qb - sq) / qa, r1 = (-qb + sq) / qa;
        r[0] = fminf(r0, r1); r[1] = fmaxf(r0, r1);
    }
    for (int i = 0; i < 2; i++) {
        float s = cv + r[i] * dv;
        int ok = r[i] != INFINITY && s >= 0.0f && s <= 1.0f && c->r0 + delta * s >= 0.0f;
        t[i] = ok ? r[i] + tc : INFINITY;
    }
}

/* A packet of N rays is N-strided structure of arrays (rtcore_ray.h's RTCRayN_* helpers,
 * which are C++ only): ray fields origin x, y, z, tnear, direction x, y, z, time, tfar at
 * float k * N + i; the hit follows the ray's 12 * N words: Ng x, y, z, u, v, primID,
 * geomID, instID. */
static void cone_intersect(const struct RTCIntersectFunctionNArguments *args) {
    const Cone *c = cone_of(args->geometryUserPtr, args->primID);
    unsigned N = args->N;
    float *ray = (float *)args->rayhit;
    float *hit = ray + 12 * N;
    for (unsigned i = 0; i < N; i++) {
        if (!args->valid[i]) continue;
        float o[3] = {ray[0 * N + i], ray[1 * N + i], ray[2 * N + i]};
        float d[3] = {ray[4 * N + i], ray[5 * N + i], ray[6 * N + i]};
        float t[2];
        cone_hits(c, o, d, t);
        for (int j = 0; j < 2; j++) {
            if (t[j] > ray[3 * N + i] && t[j] < ray[8 * N + i]) {
                ray[8 * N + i] = t[j];
                hit[0 * N + i] = hit[1 * N + i] = 0.0f;
                hit[2 * N + i] = 1.0f;
                hit[3 * N + i] = hit[4 * N + i] = 0.0f;
                ((unsigned *)hit)[5 * N + i] = args->primID;
                ((unsigned *)hit)[6 * N + i] = args->geomID;
                ((unsigned *)hit)[7 * N + i] = args->context->instID[0];
                break;
            }
        }
    }
}

/* ---- shadow rays through transmitting surfaces ---- */

/* The context of a call through the second scene: the light each ray of the call has let
 * through so far, found by the ray's id (its lane). */
typedef struct {
    struct RTCIntersectContext ctx;
    float light[16][3];
} Through;

/* Whether a crossing that lets `through` (3 floats; NULL: nothing) through transmits. */
static int transmits(const float *through) {
    return through && (through[0] != 0.0f || through[1] != 0.0f || through[2] != 0.0f);
}

/* Multiplies the ray's light by `through` (3 floats), and says whether the ray goes on. */
static int let_through(const struct RTCIntersectContext *ctx, unsigned id, const float *through) {
    if (!transmits(through)) return 0;
    float *light = ((Through *)ctx)->light[id];
    for (int c = 0; c < 3; c++) light[c] *= through[c];
    return 1;
}

/* The occlusion filter of the transmitting triangles and spheres (each hit on them lets
 * the ray go on). RTCRayN's id is word 10 * N + i, RTCHitN's primID word 5 * N + i. */
static void through_filter(const struct RTCFilterFunctionNArguments *args) {
    const float *through = args->geometryUserPtr;
    const unsigned *ray = (const unsigned *)args->ray, *hit = (const unsigned *)args->hit;
    unsigned N = args->N;
    for (unsigned i = 0; i < N; i++)
        if (args->valid[i] && let_through(args->context, ray[10 * N + i], through + 3 * hit[5 * N + i]))
            args->valid[i] = 0;
}

static void cone_occluded(const struct RTCOccludedFunctionNArguments *args) {
    const Cone *c = cone_of(args->geometryUserPtr, args->primID);
    const float *cones_through = ((const Cones *)args->geometryUserPtr)->through;
    const float *through = cones_through ? cones_through + 3 * (size_t)args->primID : NULL;
    unsigned N = args->N;
    float *ray = (float *)args->ray;
    for (unsigned i = 0; i < N; i++) {
        if (!args->valid[i]) continue;
        float o[3] = {ray[0 * N + i], ray[1 * N + i], ray[2 * N + i]};
        float d[3] = {ray[4 * N + i], ray[5 * N + i], ray[6 * N + i]};
        float t[2];
        cone_hits(c, o, d, t);
        for (int j = 0; j < 2; j++) {
            if (!(t[j] > ray[3 * N + i] && t[j] < ray[8 * N + i])) continue;
            if (let_through(args->context, ((unsigned *)ray)[10 * N + i], through)) continue;
            ray[8 * N + i] = -INFINITY;
            break;
        }
    }
}

/* ---- scenes ---- */

/* Attaches a geometry of the triangles (9 floats each) or spheres (4) of `prims` whose
 * transmission (3 floats each, NULL: all of them) is opaque (`transmitting` 0) or not (1),
 * the latter with `through_filter` on their own copy of the transmission, if any. */
static void attach(RTCDevice device, RTCScene scene, int high, Array prims, int sphere,
                   const float *through, int transmitting) {
    unsigned floats = sphere ? 4 : 9, n = 0;
    for (unsigned i = 0; i < prims.n; i++) {
        n += transmits(through ? through + 3 * (size_t)i : NULL) == transmitting;
    }
    if (n == 0) return;
    RTCGeometry g = rtcNewGeometry(device, sphere ? RTC_GEOMETRY_TYPE_SPHERE_POINT : RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                       sphere ? RTC_FORMAT_FLOAT4 : RTC_FORMAT_FLOAT3,
                                       (sphere ? 4 : 3) * sizeof(float), (sphere ? 1 : 3) * (size_t)n);
    float *kept = transmitting ? malloc(3 * sizeof(float) * n) : NULL; /* held as long as the geometry */
    unsigned j = 0;
    for (unsigned i = 0; i < prims.n; i++) {
        const float *k = through ? through + 3 * (size_t)i : NULL;
        if (transmits(k) != transmitting) continue;
        memcpy(v + (size_t)floats * j, prims.data + (size_t)floats * i, floats * sizeof(float));
        if (kept) memcpy(kept + 3 * (size_t)j, k, 3 * sizeof(float));
        j++;
    }
    if (!sphere) {
        unsigned *idx = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                3 * sizeof(unsigned), n);
        for (unsigned i = 0; i < 3 * n; i++) idx[i] = i;
        if (high) rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
    }
    if (kept) {
        rtcSetGeometryUserData(g, kept);
        rtcSetGeometryOccludedFilterFunction(g, through_filter);
    }
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
}

/* The scene of the primitives; with `tris_through` and `spheres_through` (what a crossing of
 * each lets through), the transmitting ones in geometries of their own with the filter. */
static RTCScene new_scene(RTCDevice device, int high, Array tris, Array spheres, Cones *cones,
                          const float *tris_through, const float *spheres_through) {
    RTCScene scene = rtcNewScene(device);
    if (high) rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    attach(device, scene, high, tris, 0, tris_through, 0);
    attach(device, scene, high, spheres, 1, spheres_through, 0);
    if (tris_through) attach(device, scene, high, tris, 0, tris_through, 1);
    if (spheres_through) attach(device, scene, high, spheres, 1, spheres_through, 1);
    if (cones->n) {
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(g, cones->n);
        rtcSetGeometryUserData(g, cones);
        rtcSetGeometryBoundsFunction(g, cone_bounds, NULL);
        rtcSetGeometryIntersectFunction(g, cone_intersect);
        rtcSetGeometryOccludedFunction(g, cone_occluded);
        rtcCommitGeometry(g);
        rtcAttachGeometry(scene, g);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(scene);
    return scene;
}

/* ---- tracing ---- */

/* THROUGH: shadow rays through the second scene. */
enum Kind { PRIMARY, SHADOW, THROUGH, MIRROR };

typedef struct {
    RTCScene scene;
    const float *rays; /* 8 floats a ray: origin, direction, tnear or tfar, our answer */
    unsigned n;
    enum Kind kind;
    int width; /* rays a call: 1, 8 or 16 */
    float *answer; /* per ray: hit distance (INFINITY: miss), or 1 blocked / 0 not */
    float *light;  /* THROUGH: 3 floats a ray, the light it let through */
    atomic_uint next;
} Job;

static int shadow_kind(enum Kind kind) { return kind == SHADOW || kind == THROUGH; }

/* An empty slot of a shadow group: tfar below zero. */
static int present(const float *r, enum Kind kind) { return !shadow_kind(kind) || r[6] >= 0.0f; }

/* A THROUGH ray's answer from its light so far and whether a surface stopped it. */
static void answer_through(Job *job, struct RTCIntersectContext *ctx, unsigned lane, unsigned i, int stopped) {
    float *light = job->light + 3 * (size_t)i;
    for (int c = 0; c < 3; c++) light[c] = stopped ? 0.0f : ((Through *)ctx)->light[lane][c];
    job->answer[i] = stopped ? 1.0f : 0.0f;
}

static void reset_light(struct RTCIntersectContext *ctx, unsigned lanes) {
    for (unsigned i = 0; i < lanes; i++)
        for (int c = 0; c < 3; c++) ((Through *)ctx)->light[i][c] = 1.0f;
}

static void trace_one(Job *job, struct RTCIntersectContext *ctx, unsigned i) {
    const float *r = job->rays + 8 * (size_t)i;
    if (!present(r, job->kind)) return;
    if (shadow_kind(job->kind)) {
        struct RTCRay ray = {.org_x = r[0], .org_y = r[1], .org_z = r[2], .tnear = 0.0f,
                             .dir_x = r[3], .dir_y = r[4], .dir_z = r[5], .time = 0.0f,
                             .tfar = r[6], .mask = 0xffffffffu, .id = 0, .flags = 0};
        if (job->kind == THROUGH) reset_light(ctx, 1);
        rtcOccluded1(job->scene, ctx, &ray);
        if (job->kind == THROUGH) answer_through(job, ctx, 0, i, ray.tfar == -INFINITY);
        else job->answer[i] = ray.tfar == -INFINITY ? 1.0f : 0.0f;
    } else {
        struct RTCRayHit rh;
        memset(&rh, 0, sizeof rh);
        rh.ray.org_x = r[0]; rh.ray.org_y = r[1]; rh.ray.org_z = r[2];
        rh.ray.dir_x = r[3]; rh.ray.dir_y = r[4]; rh.ray.dir_z = r[5];
        rh.ray.tnear = r[6]; rh.ray.tfar = INFINITY; rh.ray.mask = 0xffffffffu;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(job->scene, ctx, &rh);
        job->answer[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? INFINITY : rh.ray.tfar;
    }
}

/* Rays first..first + W - 1 as one packet of W (8 or 16) through rtcIntersectW or
 * rtcOccludedW: the packet's layout is RTCRayHitN's with N = W. */
static void trace_packet(Job *job, struct RTCIntersectContext *ctx, unsigned first) {
    const unsigned W = (unsigned)job->width;
    _Alignas(64) float buf[24 * 16];
    _Alignas(64) int valid[16] = {0};
    memset(buf, 0, sizeof buf);
    unsigned *words = (unsigned *)buf;
    for (unsigned i = 0; i < W; i++) {
        const float *r = job->rays + 8 * (size_t)(first + i);
        valid[i] = first + i < job->n && present(r, job->kind) ? -1 : 0;
        if (!valid[i]) continue;
        buf[0 * W + i] = r[0]; buf[1 * W + i] = r[1]; buf[2 * W + i] = r[2];
        buf[3 * W + i] = shadow_kind(job->kind) ? 0.0f : r[6];
        buf[4 * W + i] = r[3]; buf[5 * W + i] = r[4]; buf[6 * W + i] = r[5];
        buf[8 * W + i] = shadow_kind(job->kind) ? r[6] : INFINITY;
        words[9 * W + i] = 0xffffffffu;
        words[10 * W + i] = i; /* the ray's id: its lane, for the filter */
        words[(12 + 6) * W + i] = RTC_INVALID_GEOMETRY_ID;
    }
    if (job->kind == THROUGH) reset_light(ctx, W);
    if (shadow_kind(job->kind)) {
        if (W == 8) rtcOccluded8(valid, job->scene, ctx, (struct RTCRay8 *)buf);
        else rtcOccluded16(valid, job->scene, ctx, (struct RTCRay16 *)buf);
    } else {
        if (W == 8) rtcIntersect8(valid, job->scene, ctx, (struct RTCRayHit8 *)buf);
        else rtcIntersect16(valid, job->scene, ctx, (struct RTCRayHit16 *)buf);
    }
    for (unsigned i = 0; i < W; i++) {
        if (!valid[i]) continue;
        float *a = &job->answer[first + i];
        if (job->kind == THROUGH) answer_through(job, ctx, i, first + i, buf[8 * W + i] == -INFINITY);
        else if (job->kind == SHADOW) *a = buf[8 * W + i] == -INFINITY ? 1.0f : 0.0f;
        else *a = words[(12 + 6) * W + i] == RTC_INVALID_GEOMETRY_ID ? INFINITY : buf[8 * W + i];
    }
}

static void *work(void *arg) {
    Job *job = arg;
    Through through;
    struct RTCIntersectContext *ctx = &through.ctx;
    rtcInitIntersectContext(ctx);
    /* Packets hold neighbouring rays: tell Embree so (mirror rays go one at a time). */
    if (job->width > 1) ctx->flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (;;) {
        unsigned start = atomic_fetch_add(&job->next, CHUNK);
        if (start >= job->n) return NULL;
        unsigned end = start + CHUNK < job->n ? start + CHUNK : job->n;
        if (job->width == 1)
            for (unsigned i = start; i < end; i++) trace_one(job, ctx, i);
        else
            for (unsigned i = start; i < end; i += (unsigned)job->width) trace_packet(job, ctx, i);
    }
}

/* Wall-clock time, or with CLOCK=cpu the processor time of the whole process (as
 * examples/rays.rs), which other programs sharing the machine inflate far less. */
static int cpu_clock;
static double now(void) {
    struct timespec ts;
    clock_gettime(cpu_clock ? CLOCK_PROCESS_CPUTIME_ID : CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* Traces all rays on `threads` threads, five times; returns the best time. */
static double trace(RTCScene scene, Array rays, enum Kind kind, int width, float *answer,
                    float *light, int threads) {
    double best = INFINITY;
    for (int run = 0; run < 5; run++) {
        Job job = {scene, rays.data, rays.n, kind, width, answer, light, 0};
        pthread_t tid[64];
        double t0 = now();
        for (int i = 0; i < threads; i++) pthread_create(&tid[i], NULL, work, &job);
        for (int i = 0; i < threads; i++) pthread_join(tid[i], NULL);
        double t = now() - t0;
        if (t < best) best = t;
    }
    return best;
}

static int near(float ours, float theirs) { return fabsf(ours - theirs) <= 1e-4f * fabsf(ours); }

/* How many of `rays`' answers `answer` matches: both miss, or both hit within a relative
 * 1e-4 of each other (hits), or the same verdict (shadows; through the second scene, the
 * same light let through too, each channel within a relative 1e-4, where `ours_light`
 * holds ours); and how many rays there are. */
static unsigned agree(Array rays, enum Kind kind, const float *answer, const float *light,
                      const float *ours_light, unsigned *count) {
    unsigned same = 0;
    *count = 0;
    for (unsigned i = 0; i < rays.n; i++) {
        const float *r = rays.data + 8 * (size_t)i;
        if (!present(r, kind)) continue;
        float ours = r[7], theirs = answer[i];
        ++*count;
        if (kind == THROUGH) {
            const float *a = ours_light + 3 * (size_t)i, *b = light + 3 * (size_t)i;
            same += (a[0] == 0.0f && a[1] == 0.0f && a[2] == 0.0f) == (theirs == 1.0f) &&
                    near(a[0], b[0]) && near(a[1], b[1]) && near(a[2], b[2]);
        } else if (kind == SHADOW)
            same += ours == theirs;
        else
            same += (isinf(ours) && isinf(theirs)) ||
                    (!isinf(ours) && !isinf(theirs) && near(ours, theirs));
    }
    return same;
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: %s FILE [THREADS [ISA]]\n", argv[0]); return 2; }
    int threads = argc > 2 ? atoi(argv[2]) : 2;
    cpu_clock = getenv("CLOCK") && strcmp(getenv("CLOCK"), "cpu") == 0;
    if (threads < 1 || threads > 64) { fprintf(stderr, "1 to 64 threads\n"); return 2; }
    FILE *f = fopen(argv[1], "rb");
    char magic[8];
    if (!f || fread(magic, 1, 8, f) != 8 || memcmp(magic, "GPRTRAYS", 8) != 0) {
        fprintf(stderr, "%s: not a rays file\n", argv[1]);
        return 2;
    }
    Array tris = read_array(f, 9, "triangles");
    Array spheres = read_array(f, 4, "spheres");
    Array cones = read_array(f, 8, "cones");
    /* 8 floats a ray: origin, direction, tnear (primary, mirror) or tfar (shadow), our answer. */
    Array primary = read_array(f, 8, "primary rays");
    Array shadow = read_array(f, 8, "shadow rays");
    Array mirror = read_array(f, 8, "mirror rays");
    /* What a crossing of each triangle, sphere and cone lets through, and the light each
       shadow ray let through on our side: 3 floats each. */
    Array tris_through = read_array(f, 3, "triangles' transmission");
    Array spheres_through = read_array(f, 3, "spheres' transmission");
    Array cones_through = read_array(f, 3, "cones' transmission");
    Array shadow_light = read_array(f, 3, "shadow rays' light");
    fclose(f);
    if (primary.n % 16 || shadow.n % 16) { fprintf(stderr, "rays not in blocks of 16\n"); return 2; }
    if (tris_through.n != tris.n || spheres_through.n != spheres.n || cones_through.n != cones.n ||
        shadow_light.n != shadow.n) {
        fprintf(stderr, "transmission arrays do not match the primitives and rays\n");
        return 2;
    }

    /* ISA (avx2, sse4.2, ...) holds Embree to that instruction set, as GPURT_SIMD holds ours. */
    char config[64];
    if (argc > 3)
        snprintf(config, sizeof config, "threads=%d,isa=%s", threads, argv[3]);
    else
        snprintf(config, sizeof config, "threads=%d", threads);
    RTCDevice device = rtcNewDevice(config);
    /* EMBREE_QUALITY=high: Embree's high-quality build (spatial splits) for the scene and
       its triangles; the default is its medium one. */
    const char *quality = getenv("EMBREE_QUALITY");
    int high = quality && strcmp(quality, "high") == 0;
    Cones cone_set = {(const Cone *)cones.data, cones.n, NULL};
    double t0 = now();
    RTCScene scene = new_scene(device, high, tris, spheres, &cone_set, NULL, NULL);
    double build = now() - t0;
    /* The second scene, for the shadow rays through transmitting surfaces (not with the
       high-quality build, whose spatial splits may report a triangle more than once). */
    Cones cone_through = {(const Cone *)cones.data, cones.n, cones_through.data};
    RTCScene through = high ? NULL
                            : new_scene(device, 0, tris, spheres, &cone_through, tris_through.data,
                                        spheres_through.data);

    size_t most = primary.n > shadow.n ? primary.n : shadow.n;
    float *answer = malloc((most > mirror.n ? most : mirror.n) * sizeof(float) + 16);
    float *light = malloc(3 * sizeof(float) * (size_t)shadow.n + 16);
    struct { const char *name; Array rays; enum Kind kind; int width; } runs[] = {
        {"primary1", primary, PRIMARY, 1}, {"primary8", primary, PRIMARY, 8},
        {"primary16", primary, PRIMARY, 16}, {"shadow1", shadow, SHADOW, 1},
        {"shadow8", shadow, SHADOW, 8}, {"shadow16", shadow, SHADOW, 16},
        {"through1", shadow, THROUGH, 1}, {"through8", shadow, THROUGH, 8},
        {"through16", shadow, THROUGH, 16}, {"mirror1", mirror, MIRROR, 1},
    };
    printf("embree");
    char agreement[512] = "agree";
    for (size_t k = 0; k < sizeof runs / sizeof runs[0]; k++) {
        if (runs[k].kind == THROUGH && !through) continue;
        RTCScene on = runs[k].kind == THROUGH ? through : scene;
        double t = trace(on, runs[k].rays, runs[k].kind, runs[k].width, answer, light, threads);
        unsigned count, same = agree(runs[k].rays, runs[k].kind, answer, light, shadow_light.data, &count);
        printf(" %s %u %.2f", runs[k].name, count, count / t / 1e6);
        size_t used = strlen(agreement);
        snprintf(agreement + used, sizeof agreement - used, " %s %.4f", runs[k].name,
                 count ? 100.0 * same / count : 100.0);
    }
    printf("   (name, rays, Mrays/s; %d threads, build %.3f s)\n", threads, build);
    printf("%s   (name, %% of rays: hit distance within 1e-4, or the same shadow verdict; through: "
           "and the same light, each channel within 1e-4)\n", agreement);
    if (through) rtcReleaseScene(through);
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
    return 0;
}

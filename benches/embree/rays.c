/* Embree 3 on the rays `cargo run --release --example rays -- SCENE SIZE FILE` wrote:
 * the same triangles, spheres and cones, the same primary and shadow rays, on THREADS
 * threads taking chunks of 64 rays from a shared counter, as rayon does on our side.
 * Prints Mrays/s (best of five runs) and how often Embree's answers match ours.
 *
 *   cc -O3 -march=native -o rays rays.c -lembree3 -lpthread -lm
 *   ./rays FILE [THREADS]
 *
 * Triangles and spheres are Embree's own primitives (RTC_GEOMETRY_TYPE_TRIANGLE and
 * SPHERE_POINT); cones, which Embree lacks, are user geometry intersected by a C port of
 * our `intersect_cone` (open sides, no caps). Primary rays use rtcIntersect1, shadow rays
 * rtcOccluded1 (an any-hit test: it stops at the first surface). */
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

static void cone_bounds(const struct RTCBoundsFunctionArguments *args) {
    const Cone *c = (const Cone *)args->geometryUserPtr + args->primID;
    float r = c->r0 > c->r1 ? c->r0 : c->r1;
    struct RTCBounds *b = args->bounds_o;
    b->lower_x = fminf(c->p0[0], c->p1[0]) - r; b->upper_x = fmaxf(c->p0[0], c->p1[0]) + r;
    b->lower_y = fminf(c->p0[1], c->p1[1]) - r; b->upper_y = fmaxf(c->p0[1], c->p1[1]) + r;
    b->lower_z = fminf(c->p0[2], c->p1[2]) - r; b->upper_z = fmaxf(c->p0[2], c->p1[2]) + r;
}

static float dot3(const float *a, const float *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Our intersect_cone: the two crossings of the side between the caps, or INFINITY. */
static void cone_hits(const Cone *c, const float *o, const float *d, float t[2]) {
    float axis[3] = {c->p1[0] - c->p0[0], c->p1[1] - c->p0[1], c->p1[2] - c->p0[2]};
    float height = sqrtf(dot3(axis, axis));
    float a[3] = {axis[0] / height, axis[1] / height, axis[2] / height};
    float k = (c->r1 - c->r0) / height;
    float mid[3] = {0.5f * (c->p0[0] + c->p1[0]) - o[0], 0.5f * (c->p0[1] + c->p1[1]) - o[1],
                    0.5f * (c->p0[2] + c->p1[2]) - o[2]};
    float tc = dot3(mid, d);
    float co[3], dp[3], cp[3];
    for (int i = 0; i < 3; i++) co[i] = o[i] + tc * d[i] - c->p0[i];
    float dv = dot3(d, a), cv = dot3(co, a);
    for (int i = 0; i < 3; i++) { dp[i] = d[i] - dv * a[i]; cp[i] = co[i] - cv * a[i]; }
    float rr = c->r0 + k * cv;
    float qa = dot3(dp, dp) - k * k * dv * dv;
    float qb = dot3(cp, dp) - k * rr * dv;
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
        int ok = r[i] != INFINITY && s >= 0.0f && s <= height && c->r0 + k * s >= 0.0f;
        t[i] = ok ? r[i] + tc : INFINITY;
    }
}

static void cone_intersect(const struct RTCIntersectFunctionNArguments *args) {
    if (!args->valid[0]) return;
    const Cone *c = (const Cone *)args->geometryUserPtr + args->primID;
    struct RTCRayHit *rh = (struct RTCRayHit *)args->rayhit;
    float o[3] = {rh->ray.org_x, rh->ray.org_y, rh->ray.org_z};
    float d[3] = {rh->ray.dir_x, rh->ray.dir_y, rh->ray.dir_z};
    float t[2];
    cone_hits(c, o, d, t);
    for (int i = 0; i < 2; i++) {
        if (t[i] > rh->ray.tnear && t[i] < rh->ray.tfar) {
            rh->ray.tfar = t[i];
            rh->hit.geomID = args->geomID;
            rh->hit.primID = args->primID;
            rh->hit.instID[0] = args->context->instID[0];
            rh->hit.Ng_x = rh->hit.Ng_y = 0.0f; rh->hit.Ng_z = 1.0f;
            rh->hit.u = rh->hit.v = 0.0f;
            break;
        }
    }
}

static void cone_occluded(const struct RTCOccludedFunctionNArguments *args) {
    if (!args->valid[0]) return;
    const Cone *c = (const Cone *)args->geometryUserPtr + args->primID;
    struct RTCRay *r = (struct RTCRay *)args->ray;
    float o[3] = {r->org_x, r->org_y, r->org_z}, d[3] = {r->dir_x, r->dir_y, r->dir_z};
    float t[2];
    cone_hits(c, o, d, t);
    for (int i = 0; i < 2; i++)
        if (t[i] > r->tnear && t[i] < r->tfar) { r->tfar = -INFINITY; return; }
}

/* ---- tracing ---- */

typedef struct {
    RTCScene scene;
    const float *rays; /* 8 floats a ray: origin, direction, tnear or tfar, our answer */
    unsigned n;
    int shadow;
    float *answer; /* per ray: hit distance (INFINITY: miss), or 1 blocked / 0 not */
    atomic_uint next;
} Job;

static void *work(void *arg) {
    Job *job = arg;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (;;) {
        unsigned start = atomic_fetch_add(&job->next, CHUNK);
        if (start >= job->n) return NULL;
        unsigned end = start + CHUNK < job->n ? start + CHUNK : job->n;
        for (unsigned i = start; i < end; i++) {
            const float *r = job->rays + 8 * (size_t)i;
            if (job->shadow) {
                struct RTCRay ray = {.org_x = r[0], .org_y = r[1], .org_z = r[2], .tnear = 0.0f,
                                     .dir_x = r[3], .dir_y = r[4], .dir_z = r[5], .time = 0.0f,
                                     .tfar = r[6], .mask = 0xffffffffu, .id = 0, .flags = 0};
                rtcOccluded1(job->scene, &ctx, &ray);
                job->answer[i] = ray.tfar == -INFINITY ? 1.0f : 0.0f;
            } else {
                struct RTCRayHit rh;
                memset(&rh, 0, sizeof rh);
                rh.ray.org_x = r[0]; rh.ray.org_y = r[1]; rh.ray.org_z = r[2];
                rh.ray.dir_x = r[3]; rh.ray.dir_y = r[4]; rh.ray.dir_z = r[5];
                rh.ray.tnear = r[6]; rh.ray.tfar = INFINITY; rh.ray.mask = 0xffffffffu;
                rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                rtcIntersect1(job->scene, &ctx, &rh);
                job->answer[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? INFINITY : rh.ray.tfar;
            }
        }
    }
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* Traces all rays on `threads` threads, five times; returns the best time. */
static double trace(RTCScene scene, Array rays, int shadow, float *answer, int threads) {
    double best = INFINITY;
    for (int run = 0; run < 5; run++) {
        Job job = {scene, rays.data, rays.n, shadow, answer, 0};
        pthread_t tid[64];
        double t0 = now();
        for (int i = 0; i < threads; i++) pthread_create(&tid[i], NULL, work, &job);
        for (int i = 0; i < threads; i++) pthread_join(tid[i], NULL);
        double t = now() - t0;
        if (t < best) best = t;
    }
    return best;
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: %s FILE [THREADS]\n", argv[0]); return 2; }
    int threads = argc > 2 ? atoi(argv[2]) : 2;
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
    /* 8 floats a ray: origin, direction, tnear (primary) or tfar (shadow), our answer. */
    Array primary = read_array(f, 8, "primary rays");
    Array shadow = read_array(f, 8, "shadow rays");
    fclose(f);

    char config[32];
    snprintf(config, sizeof config, "threads=%d", threads);
    RTCDevice device = rtcNewDevice(config);
    RTCScene scene = rtcNewScene(device);
    double t0 = now();
    if (tris.n) {
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                           3 * sizeof(float), 3 * (size_t)tris.n);
        unsigned *idx = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                3 * sizeof(unsigned), tris.n);
        memcpy(v, tris.data, 9 * sizeof(float) * (size_t)tris.n);
        for (unsigned i = 0; i < 3 * tris.n; i++) idx[i] = i;
        rtcCommitGeometry(g);
        rtcAttachGeometry(scene, g);
        rtcReleaseGeometry(g);
    }
    if (spheres.n) {
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
        float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                           4 * sizeof(float), spheres.n);
        memcpy(v, spheres.data, 4 * sizeof(float) * (size_t)spheres.n);
        rtcCommitGeometry(g);
        rtcAttachGeometry(scene, g);
        rtcReleaseGeometry(g);
    }
    if (cones.n) {
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(g, cones.n);
        rtcSetGeometryUserData(g, cones.data);
        rtcSetGeometryBoundsFunction(g, cone_bounds, NULL);
        rtcSetGeometryIntersectFunction(g, cone_intersect);
        rtcSetGeometryOccludedFunction(g, cone_occluded);
        rtcCommitGeometry(g);
        rtcAttachGeometry(scene, g);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(scene);
    double build = now() - t0;

    float *answer = malloc(((size_t)primary.n + shadow.n + 1) * sizeof(float));
    double tp = trace(scene, primary, 0, answer, threads);
    /* Agreement: both miss, or both hit within a relative 1e-4 of each other. */
    unsigned same_p = 0;
    for (unsigned i = 0; i < primary.n; i++) {
        float ours = primary.data[8 * (size_t)i + 7], theirs = answer[i];
        if ((isinf(ours) && isinf(theirs)) ||
            (!isinf(ours) && !isinf(theirs) && fabsf(ours - theirs) <= 1e-4f * fabsf(ours)))
            same_p++;
    }
    double ts = trace(scene, shadow, 1, answer + primary.n, threads);
    unsigned same_s = 0;
    for (unsigned i = 0; i < shadow.n; i++)
        same_s += shadow.data[8 * (size_t)i + 7] == answer[primary.n + i];

    printf("embree  primary %9u rays %8.2f Mrays/s   shadow %9u rays %8.2f Mrays/s   (%d threads, "
           "build %.3f s)\n",
           primary.n, primary.n / tp / 1e6, shadow.n, shadow.n / ts / 1e6, threads, build);
    printf("agree   primary %.4f%% of rays (hit distance within 1e-4), shadow %.4f%% (blocked or not)\n",
           primary.n ? 100.0 * same_p / primary.n : 100.0, shadow.n ? 100.0 * same_s / shadow.n : 100.0);
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
    return 0;
}

// The stills of `nlifs bench raytrace` traced by Intel Embree 3, for comparison: the same
// spheres, camera, samples, lights and shading as nlifs (read from the `.trace` files that
// `nlifs bench raytrace --describe` writes), in four variants of Embree's API:
//
//   sphere    Embree's own sphere primitive (RTC_GEOMETRY_TYPE_SPHERE_POINT), one ray at a time
//   sphere16  the same geometry, 16-wide ray packets (rtcIntersect16 / rtcOccluded16)
//   user16    user geometry: spheres intersected by our callbacks (nlifs's root formula,
//             written so the compiler vectorises the 16 lanes), 16-wide packets
//   stream    the user geometry with the stream API (rtcIntersect1M / rtcOccluded1M)
//
// Prints CPU seconds (user + system of the whole process: Embree's build threads included)
// for build + trace, and writes a PPM per variant to compare with nlifs's PNG.
//
// Not built by cargo or CI; see build.sh. Usage: trace FILE.trace [VARIANT...] [--out DIR]

#include <embree3/rtcore.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>
#include <sys/resource.h>

namespace {

struct V3 {
    float x, y, z;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(V3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
V3 operator*(V3 a, V3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 normalize(V3 a) { return a * (1.0f / std::sqrt(dot(a, a))); }

struct Light {
    V3 to_light, intensity;
};

// What nlifs's tracer uses (see `write_trace_description` in src/raytrace/tracer.rs).
struct Scene {
    unsigned width = 0, height = 0, spp = 1, seed = 0;
    V3 eye{}, right{}, up{}, forward{};
    float half_height = 0, aspect = 1, back_off = 0;
    bool parallel = false, shadows = true, ground = true;
    float ground_y = 0, radius = 1, eps = 0, ambient = 0;
    V3 centre{}, background{};
    std::vector<Light> lights;
    std::vector<V3> colours;
    std::vector<float> sphere;  // x y z r per sphere
    std::vector<unsigned> function;
};

float from_bits(uint32_t b) {
    float f;
    std::memcpy(&f, &b, 4);
    return f;
}

bool read_scene(const char* path, Scene& s) {
    std::ifstream in(path);
    if (!in) return false;
    std::string line;
    auto floats = [](std::istringstream& ls, int n) {
        std::vector<float> v(n);
        for (auto& f : v) {
            uint32_t b = 0;
            ls >> b;
            f = from_bits(b);
        }
        return v;
    };
    auto v3 = [&](std::istringstream& ls) {
        auto v = floats(ls, 3);
        return V3{v[0], v[1], v[2]};
    };
    while (std::getline(in, line)) {
        std::istringstream ls(line);
        std::string key;
        ls >> key;
        if (key == "image") ls >> s.width >> s.height >> s.spp >> s.seed;
        else if (key == "eye") s.eye = v3(ls);
        else if (key == "right") s.right = v3(ls);
        else if (key == "up") s.up = v3(ls);
        else if (key == "forward") s.forward = v3(ls);
        else if (key == "view") {
            auto v = floats(ls, 3);
            unsigned p = 0;
            ls >> p;
            s.half_height = v[0], s.aspect = v[1], s.back_off = v[2], s.parallel = p != 0;
        } else if (key == "flags") {
            unsigned a = 0, b = 0;
            ls >> a >> b;
            s.shadows = a != 0, s.ground = b != 0;
        } else if (key == "frame") {
            auto v = floats(ls, 6);
            s.ground_y = v[0], s.centre = {v[1], v[2], v[3]}, s.radius = v[4], s.eps = v[5];
        } else if (key == "ambient") s.ambient = floats(ls, 1)[0];
        else if (key == "background") s.background = v3(ls);
        else if (key == "light") {
            V3 l = v3(ls);
            s.lights.push_back({l, v3(ls)});
        } else if (key == "colour") s.colours.push_back(v3(ls));
        else if (key == "sphere") {
            auto v = floats(ls, 4);
            s.sphere.insert(s.sphere.end(), v.begin(), v.end());
            unsigned f = 0;
            ls >> f;
            s.function.push_back(f);
        }
    }
    return s.width > 0 && !s.sphere.empty();
}

// nlifs's PCG (src/rng.rs).
constexpr uint32_t PCG_MUL = 747796405u, PCG_INC = 2891336453u, PCG_OUT_MUL = 277803737u;
uint32_t pcg_hash(uint32_t input) {
    uint32_t state = input * PCG_MUL + PCG_INC;
    uint32_t word = ((state >> ((state >> 28) + 4)) ^ state) * PCG_OUT_MUL;
    return (word >> 22) ^ word;
}
struct Pcg32 {
    uint32_t state;
    static Pcg32 for_stream(uint32_t seed, uint32_t frame, uint32_t chain) {
        return {pcg_hash(seed ^ pcg_hash(frame ^ pcg_hash(chain)))};
    }
    uint32_t next_u32() {
        uint32_t old = state;
        state = old * PCG_MUL + PCG_INC;
        uint32_t word = ((old >> ((old >> 28) + 4)) ^ old) * PCG_OUT_MUL;
        return (word >> 22) ^ word;
    }
    float next_f32() { return float(next_u32() >> 8) * (1.0f / 16777216.0f); }
};

// nlifs's 8-bit sRGB encode (src/color.rs): the linear value where each byte starts.
struct Srgb8 {
    float starts[255];
    static unsigned encode_slow(float v) {
        v = std::fmin(std::fmax(v, 0.0f), 1.0f);
        float s = v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
        return unsigned(s * 255.0f + 0.5f);
    }
    Srgb8() {
        for (unsigned k = 0; k < 255; k++) {
            uint32_t lo = 0, hi = 0x3f800000u;
            while (hi - lo > 1) {
                uint32_t mid = lo + (hi - lo) / 2;
                if (encode_slow(from_bits(mid)) > k) hi = mid; else lo = mid;
            }
            starts[k] = from_bits(hi);
        }
    }
    uint8_t encode(float v) const {
        unsigned n = 0;
        for (float s : starts) n += s <= v;
        return uint8_t(n);
    }
};

// ---- user geometry: nlifs's sphere (closest-approach roots, visible surface of a solid) ----

struct Spheres {
    const float* xyzr;
};

void sphere_bounds(const RTCBoundsFunctionArguments* args) {
    const float* s = static_cast<const Spheres*>(args->geometryUserPtr)->xyzr + 4 * args->primID;
    RTCBounds* b = args->bounds_o;
    b->lower_x = s[0] - s[3], b->lower_y = s[1] - s[3], b->lower_z = s[2] - s[3];
    b->upper_x = s[0] + s[3], b->upper_y = s[1] + s[3], b->upper_z = s[2] + s[3];
}

// Lane i of N: the visible surface's t in (tnear, tfar), or NaN/none.
// Lanes 0..count of the N-wide rays (count = N for the packet widths, so the loop is
// vectorised): the visible surface's t in (tnear, tfar), and whether there is one.
template <int N>
inline void sphere_lanes(const int* valid, const float* s, RTCRayN* ray, unsigned n, unsigned first, float* t_out,
                         int* hit) {
    const unsigned count = N ? N : 1;
    for (unsigned j = 0; j < count; j++) {
        unsigned i = first + j;
        float ox = RTCRayN_org_x(ray, n, i) - s[0], oy = RTCRayN_org_y(ray, n, i) - s[1],
              oz = RTCRayN_org_z(ray, n, i) - s[2];
        float dx = RTCRayN_dir_x(ray, n, i), dy = RTCRayN_dir_y(ray, n, i), dz = RTCRayN_dir_z(ray, n, i);
        float b = ox * dx + oy * dy + oz * dz;
        float lx = ox - b * dx, ly = oy - b * dy, lz = oz - b * dz;
        float disc = s[3] * s[3] - (lx * lx + ly * ly + lz * lz);
        float q = std::sqrt(std::fmax(disc, 0.0f));
        float t0 = -b - q, t1 = -b + q;
        float tn = RTCRayN_tnear(ray, n, i), tf = RTCRayN_tfar(ray, n, i);
        float t = t0 > tn ? t0 : t1;
        hit[j] = valid[i] != 0 && disc >= 0.0f && t > tn && t < tf;
        t_out[j] = t;
    }
}

// N = 0: any width, one lane at a time.
template <int N>
void intersect_n(const RTCIntersectFunctionNArguments* args) {
    const float* s = static_cast<const Spheres*>(args->geometryUserPtr)->xyzr + 4 * args->primID;
    const unsigned n = N ? N : args->N;
    RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, n);
    RTCHitN* hitn = RTCRayHitN_HitN(args->rayhit, n);
    for (unsigned first = 0; first < n; first += N ? N : 1) {
        float t[N ? N : 1];
        int hit[N ? N : 1];
        sphere_lanes<N>(args->valid, s, ray, n, first, t, hit);
        for (unsigned j = 0; j < (N ? N : 1); j++) {
            if (!hit[j]) continue;
            unsigned i = first + j;
            RTCRayN_tfar(ray, n, i) = t[j];
            RTCHitN_primID(hitn, n, i) = args->primID;
            RTCHitN_geomID(hitn, n, i) = args->geomID;
            RTCHitN_instID(hitn, n, i, 0) = args->context->instID[0];
            RTCHitN_u(hitn, n, i) = 0, RTCHitN_v(hitn, n, i) = 0;
        }
    }
}

void sphere_intersect(const RTCIntersectFunctionNArguments* args) {
    switch (args->N) {
        case 16: intersect_n<16>(args); break;
        case 8: intersect_n<8>(args); break;
        case 4: intersect_n<4>(args); break;
        default: intersect_n<0>(args);
    }
}

template <int N>
void occluded_n(const RTCOccludedFunctionNArguments* args) {
    const float* s = static_cast<const Spheres*>(args->geometryUserPtr)->xyzr + 4 * args->primID;
    const unsigned n = N ? N : args->N;
    for (unsigned first = 0; first < n; first += N ? N : 1) {
        float t[N ? N : 1];
        int hit[N ? N : 1];
        sphere_lanes<N>(args->valid, s, args->ray, n, first, t, hit);
        for (unsigned j = 0; j < (N ? N : 1); j++)
            if (hit[j]) RTCRayN_tfar(args->ray, n, first + j) = -INFINITY;
    }
}

void sphere_occluded(const RTCOccludedFunctionNArguments* args) {
    switch (args->N) {
        case 16: occluded_n<16>(args); break;
        case 8: occluded_n<8>(args); break;
        case 4: occluded_n<4>(args); break;
        default: occluded_n<0>(args);
    }
}

// ---- the tracer: nlifs's samples and shading, rays handed to Embree in batches ----

enum class Variant { Sphere, Sphere16, User16, Stream };

struct Counts {
    std::atomic<uint64_t> primary{0}, shadow{0}, hits{0};
};

constexpr unsigned RUN = 32;  // pixels of a run (as nlifs)

struct Tracer {
    const Scene& s;
    RTCScene scene;
    Variant variant;
    Srgb8 srgb;

    // A run's rays, stored as Embree takes them: one struct per ray (sphere, stream) or
    // 16-wide packets (sphere16, user16), so no copying between the two.
    struct Rays {
        bool packets;
        std::vector<RTCRayHit> one;
        std::vector<RTCRayHit16> p16;
        std::vector<RTCRay> shadow_one;
        std::vector<RTCRay16> shadow_p16;
        void resize(unsigned n) {
            one.resize(n), shadow_one.resize(n);
            p16.resize((n + 15) / 16), shadow_p16.resize((n + 15) / 16);
        }
        void set(unsigned k, V3 o, V3 d, float tfar) {
            if (!packets) {
                RTCRayHit& r = one[k];
                r.ray.org_x = o.x, r.ray.org_y = o.y, r.ray.org_z = o.z;
                r.ray.dir_x = d.x, r.ray.dir_y = d.y, r.ray.dir_z = d.z;
                r.ray.tnear = 0, r.ray.tfar = tfar, r.ray.time = 0, r.ray.mask = ~0u, r.ray.id = k, r.ray.flags = 0;
                r.hit.geomID = RTC_INVALID_GEOMETRY_ID, r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                return;
            }
            RTCRayHit16& r = p16[k / 16];
            unsigned i = k % 16;
            r.ray.org_x[i] = o.x, r.ray.org_y[i] = o.y, r.ray.org_z[i] = o.z;
            r.ray.dir_x[i] = d.x, r.ray.dir_y[i] = d.y, r.ray.dir_z[i] = d.z;
            r.ray.tnear[i] = 0, r.ray.tfar[i] = tfar, r.ray.time[i] = 0, r.ray.mask[i] = ~0u, r.ray.id[i] = k;
            r.ray.flags[i] = 0;
            r.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID, r.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
        }
        // (hit?, primID, t)
        bool hit(unsigned k, unsigned& prim, float& t) const {
            if (!packets) {
                prim = one[k].hit.primID, t = one[k].ray.tfar;
                return one[k].hit.geomID != RTC_INVALID_GEOMETRY_ID;
            }
            const RTCRayHit16& r = p16[k / 16];
            unsigned i = k % 16;
            prim = r.hit.primID[i], t = r.ray.tfar[i];
            return r.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
        }
        void set_shadow(unsigned m, V3 o, V3 d) {
            if (!packets) {
                RTCRay& r = shadow_one[m];
                r.org_x = o.x, r.org_y = o.y, r.org_z = o.z;
                r.dir_x = d.x, r.dir_y = d.y, r.dir_z = d.z;
                r.tnear = 0, r.tfar = INFINITY, r.time = 0, r.mask = ~0u, r.id = m, r.flags = 0;
                return;
            }
            RTCRay16& r = shadow_p16[m / 16];
            unsigned i = m % 16;
            r.org_x[i] = o.x, r.org_y[i] = o.y, r.org_z[i] = o.z;
            r.dir_x[i] = d.x, r.dir_y[i] = d.y, r.dir_z[i] = d.z;
            r.tnear[i] = 0, r.tfar[i] = INFINITY, r.time[i] = 0, r.mask[i] = ~0u, r.id[i] = m, r.flags[i] = 0;
        }
        bool blocked(unsigned m) const {
            return (packets ? shadow_p16[m / 16].tfar[m % 16] : shadow_one[m].tfar) < 0;
        }
    };

    static void valid16(int* valid, unsigned first, unsigned n) {
        for (unsigned i = 0; i < 16; i++) valid[i] = first + i < n ? -1 : 0;
    }

    void intersect(Rays& r, unsigned n, RTCIntersectContext& ctx) const {
        if (variant == Variant::Sphere) {
            for (unsigned k = 0; k < n; k++) rtcIntersect1(scene, &ctx, &r.one[k]);
        } else if (variant == Variant::Stream) {
            rtcIntersect1M(scene, &ctx, r.one.data(), n, sizeof(RTCRayHit));
        } else {
            for (unsigned first = 0; first < n; first += 16) {
                alignas(64) int valid[16];
                valid16(valid, first, n);
                rtcIntersect16(valid, scene, &ctx, &r.p16[first / 16]);
            }
        }
    }

    void occluded(Rays& r, unsigned n, RTCIntersectContext& ctx) const {
        if (variant == Variant::Sphere) {
            for (unsigned k = 0; k < n; k++) rtcOccluded1(scene, &ctx, &r.shadow_one[k]);
        } else if (variant == Variant::Stream) {
            rtcOccluded1M(scene, &ctx, r.shadow_one.data(), n, sizeof(RTCRay));
        } else {
            for (unsigned first = 0; first < n; first += 16) {
                alignas(64) int valid[16];
                valid16(valid, first, n);
                rtcOccluded16(valid, scene, &ctx, &r.shadow_p16[first / 16]);
            }
        }
    }

    void row(unsigned y, uint8_t* out, Counts& counts) const {
        const unsigned spp = s.spp;
        std::vector<unsigned> strata(spp);
        for (unsigned i = 0; i < spp; i++) strata[i] = i;
        Rays rays{variant == Variant::Sphere16 || variant == Variant::User16, {}, {}, {}, {}};
        rays.resize(RUN * spp);
        std::vector<V3> dir(RUN * spp), origin(RUN * spp);
        std::vector<unsigned> shadow_of(RUN * spp);
        std::vector<V3> point(RUN * spp), normal(RUN * spp), albedo(RUN * spp), colour(RUN * spp);
        std::vector<float> tg(RUN * spp), specular(RUN * spp);
        std::vector<uint8_t> lit(RUN * spp), ground(RUN * spp);
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        if (variant != Variant::Sphere) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        uint64_t primary = 0, shadows = 0, hits = 0;
        for (unsigned x0 = 0; x0 < s.width; x0 += RUN) {
            unsigned pixels = std::min(RUN, s.width - x0), n = pixels * spp;
            for (unsigned p = 0; p < pixels; p++) {
                unsigned x = x0 + p;
                Pcg32 rng = Pcg32::for_stream(s.seed, 0, y * s.width + x);
                for (unsigned i = spp - 1; i >= 1; i--) {
                    unsigned j = unsigned((uint64_t(rng.next_u32()) * (i + 1)) >> 32);
                    std::swap(strata[i], strata[j]);
                }
                for (unsigned i = 0; i < spp; i++) {
                    float sx = (float(i) + rng.next_f32()) / float(spp);
                    float sy = (float(strata[i]) + rng.next_f32()) / float(spp);
                    float fx = float(x) + sx, fy = float(y) + sy;
                    float ix = (2.0f * fx / float(s.width) - 1.0f) * s.half_height * s.aspect;
                    float iy = (1.0f - 2.0f * fy / float(s.height)) * s.half_height;
                    V3 o, d;
                    if (s.parallel) {
                        o = s.eye + s.right * ix + s.up * iy - s.forward * s.back_off;
                        d = s.forward;
                    } else {
                        o = s.eye;
                        d = normalize(s.forward + s.right * ix + s.up * iy);
                    }
                    unsigned k = p * spp + i;
                    float t = s.ground && d.y < -1e-6f ? (s.ground_y - o.y) / d.y : INFINITY;
                    tg[k] = t > 0 ? t : INFINITY;
                    rays.set(k, o, d, tg[k]);
                    origin[k] = o, dir[k] = d;
                }
            }
            intersect(rays, n, ctx);
            primary += n;
            for (unsigned k = 0; k < n; k++) {
                V3 o = origin[k], d = dir[k];
                lit[k] = 0, ground[k] = 0, specular[k] = 0, albedo[k] = {0, 0, 0};
                unsigned prim = 0;
                float t_hit = 0;
                if (rays.hit(k, prim, t_hit)) {
                    hits++;
                    const float* sp = &s.sphere[4 * prim];
                    point[k] = o + d * t_hit;
                    V3 nn = normalize(point[k] - V3{sp[0], sp[1], sp[2]});
                    normal[k] = dot(nn, d) > 0 ? nn * -1.0f : nn;
                    unsigned f = s.function[prim];
                    albedo[k] = f < s.colours.size() ? s.colours[f] : V3{0.7f, 0.7f, 0.7f};
                    specular[k] = 0.25f, lit[k] = 1;
                } else if (std::isfinite(tg[k])) {
                    point[k] = o + d * tg[k];
                    normal[k] = {0, 1, 0}, albedo[k] = {0.55f, 0.55f, 0.55f};
                    lit[k] = 1, ground[k] = 1;
                }
                colour[k] = albedo[k] * s.ambient;
            }
            for (const Light& light : s.lights) {
                unsigned m = 0;
                for (unsigned k = 0; k < n; k++) {
                    if (!lit[k] || dot(normal[k], light.to_light) <= 0) continue;
                    rays.set_shadow(m, point[k] + normal[k] * s.eps, light.to_light);
                    shadow_of[m++] = k;
                }
                if (s.shadows) {
                    occluded(rays, m, ctx);
                    shadows += m;
                }
                for (unsigned j = 0; j < m; j++) {
                    if (s.shadows && rays.blocked(j)) continue;
                    unsigned k = shadow_of[j];
                    float cos = dot(normal[k], light.to_light);
                    V3 lk = albedo[k] * cos;
                    if (specular[k] > 0) {
                        V3 h = normalize(light.to_light - dir[k]);
                        float nh = std::fmax(dot(normal[k], h), 0.0f);
                        float p2 = nh * nh, p4 = p2 * p2, p8 = p4 * p4, p16 = p8 * p8;
                        float a = specular[k] * (p16 * p16);
                        lk = lk + V3{a, a, a};
                    }
                    colour[k] = colour[k] + light.intensity * lk;
                }
            }
            for (unsigned p = 0; p < pixels; p++) {
                V3 sum{0, 0, 0};
                for (unsigned i = 0; i < spp; i++) {
                    unsigned k = p * spp + i;
                    V3 c = s.background;
                    if (ground[k]) {
                        float d = std::sqrt(dot(point[k] - s.centre, point[k] - s.centre)) / (2.5f * s.radius);
                        float fade = std::exp(-d * d);
                        c = s.background * (1.0f - fade) + colour[k] * fade;
                    } else if (lit[k]) {
                        c = colour[k];
                    }
                    sum = sum + c;
                }
                V3 c{sum.x / float(spp), sum.y / float(spp), sum.z / float(spp)};
                uint8_t* px = out + 3 * (x0 + p);
                px[0] = srgb.encode(c.x), px[1] = srgb.encode(c.y), px[2] = srgb.encode(c.z);
            }
        }
        counts.primary += primary, counts.shadow += shadows, counts.hits += hits;
    }
};

double cpu_secs() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double wall_secs() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s FILE.trace [sphere|sphere16|user16|stream ...] [--out DIR]\n", argv[0]);
        return 2;
    }
    Scene s;
    if (!read_scene(argv[1], s)) {
        std::fprintf(stderr, "%s: cannot read the scene description\n", argv[1]);
        return 2;
    }
    std::vector<std::string> variants;
    std::string out_dir;
    for (int a = 2; a < argc; a++) {
        std::string arg = argv[a];
        if (arg == "--out" && a + 1 < argc) out_dir = argv[++a];
        else variants.push_back(arg);
    }
    if (variants.empty()) variants = {"sphere", "sphere16", "user16", "stream"};
    unsigned threads = std::thread::hardware_concurrency();
    std::string config = "threads=" + std::to_string(threads);
    RTCDevice device = rtcNewDevice(config.c_str());
    Spheres spheres{s.sphere.data()};
    unsigned count = unsigned(s.function.size());
    for (const std::string& name : variants) {
        Variant variant;
        if (name == "sphere") variant = Variant::Sphere;
        else if (name == "sphere16") variant = Variant::Sphere16;
        else if (name == "user16") variant = Variant::User16;
        else if (name == "stream") variant = Variant::Stream;
        else {
            std::fprintf(stderr, "unknown variant %s\n", name.c_str());
            return 2;
        }
        double cpu0 = cpu_secs(), wall0 = wall_secs();
        RTCScene scene = rtcNewScene(device);
        rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
        if (variant == Variant::Sphere || variant == Variant::Sphere16) {
            RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
            float* v = static_cast<float*>(
                rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 16, count));
            std::memcpy(v, s.sphere.data(), 16 * size_t(count));
            rtcCommitGeometry(g);
            rtcAttachGeometry(scene, g);
            rtcReleaseGeometry(g);
        } else {
            RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
            rtcSetGeometryUserPrimitiveCount(g, count);
            rtcSetGeometryUserData(g, &spheres);
            rtcSetGeometryBoundsFunction(g, sphere_bounds, nullptr);
            rtcSetGeometryIntersectFunction(g, sphere_intersect);
            rtcSetGeometryOccludedFunction(g, sphere_occluded);
            rtcCommitGeometry(g);
            rtcAttachGeometry(scene, g);
            rtcReleaseGeometry(g);
        }
        rtcCommitScene(scene);
        double build_wall = wall_secs() - wall0;
        Tracer tracer{s, scene, variant, Srgb8()};
        std::vector<uint8_t> image(size_t(s.width) * s.height * 3);
        Counts counts;
        std::atomic<unsigned> next_row{0};
        std::vector<std::thread> pool;
        for (unsigned t = 0; t < threads; t++)
            pool.emplace_back([&] {
                for (unsigned y; (y = next_row++) < s.height;) tracer.row(y, &image[size_t(y) * s.width * 3], counts);
            });
        for (auto& t : pool) t.join();
        double cpu = cpu_secs() - cpu0, wall = wall_secs() - wall0;
        rtcReleaseScene(scene);
        std::printf(
            "embree %s %s: %u spheres, build %.3f s, %.2f s wall, %.2f s CPU (build + trace), %.2f M primary, %.2f M "
            "shadow rays, %.2f M leaf hits\n",
            RTC_VERSION_STRING, name.c_str(), count, build_wall, wall, cpu, counts.primary / 1e6, counts.shadow / 1e6,
            counts.hits / 1e6);
        if (!out_dir.empty()) {
            std::string base = argv[1];
            base = base.substr(base.find_last_of('/') + 1);
            base = base.substr(0, base.find_last_of('.'));
            std::string path = out_dir + "/" + base + "_embree_" + name + ".ppm";
            FILE* f = std::fopen(path.c_str(), "wb");
            if (f) {
                std::fprintf(f, "P6\n%u %u\n255\n", s.width, s.height);
                std::fwrite(image.data(), 1, image.size(), f);
                std::fclose(f);
            }
        }
    }
    rtcReleaseDevice(device);
    return 0;
}

// Hits of rays on pbrt-v3's cone, paraboloid and hyperboloid, for src/shapes/revolved.rs's test.
// Build: see tests/data/pbrt-v3/README or the test's doc comment; output: revolved-hits.txt.
#include "shapes/cone.h"
#include "shapes/paraboloid.h"
#include "shapes/hyperboloid.h"
#include "core/interaction.h"
#include <cstdio>
#include <cstdint>
using namespace pbrt;
static uint64_t state = 88172645463325252ull;
static float rnd() { state ^= state << 13; state ^= state >> 7; state ^= state << 17; return (state >> 40) / float(1 << 24); }
int main() {
    Transform o2w[3] = {Translate(Vector3f(0.2f, -0.1f, 0.3f)) * RotateX(30.f),
                        RotateY(-20.f) * Scale(1.f, 1.f, 1.5f),
                        Translate(Vector3f(0, 0, -0.4f)) * Scale(-1.f, 1.f, 1.f)};
    Transform w2o[3] = {Inverse(o2w[0]), Inverse(o2w[1]), Inverse(o2w[2])};
    Cone cone(&o2w[0], &w2o[0], false, 1.3f, 0.8f, 300.f);  // height, radius
    Paraboloid para(&o2w[1], &w2o[1], true, 0.9f, 0.2f, 1.1f, 270.f);
    Hyperboloid hyp(&o2w[2], &w2o[2], false, Point3f(0.4f, 0.1f, -0.5f), Point3f(0.3f, 0.6f, 0.7f), 330.f);
    const Shape *shapes[3] = {&cone, &para, &hyp};
    for (int s = 0; s < 3; ++s) {
        for (int i = 0; i < 200; ++i) {
            Point3f o(rnd() * 8 - 4, rnd() * 8 - 4, rnd() * 8 - 4);
            Point3f target(rnd() * 2 - 1, rnd() * 2 - 1, rnd() * 2 - 1);
            if (i % 4 == 3) o = Point3f(rnd() * 0.4f - 0.2f, rnd() * 0.4f - 0.2f, rnd() * 0.6f);
            Ray r(o, target - o);
            Float t; SurfaceInteraction si;
            printf("%d %.7g %.7g %.7g %.7g %.7g %.7g", s, o.x, o.y, o.z, r.d.x, r.d.y, r.d.z);
            if (!shapes[s]->Intersect(r, &t, &si, false)) { printf(" miss\n"); continue; }
            printf(" hit %.7g  %.7g %.7g %.7g  %.7g %.7g %.7g  %.7g %.7g  %.7g %.7g %.7g  %.7g %.7g %.7g  %.7g %.7g %.7g  %.7g %.7g %.7g\n", t,
                   si.p.x, si.p.y, si.p.z, si.n.x, si.n.y, si.n.z, si.uv.x, si.uv.y,
                   si.dpdu.x, si.dpdu.y, si.dpdu.z, si.dpdv.x, si.dpdv.y, si.dpdv.z,
                   si.dndu.x, si.dndu.y, si.dndu.z, si.dndv.x, si.dndv.y, si.dndv.z);
        }
        printf("area %d %.7g\n", s, shapes[s]->Area());
    }
}

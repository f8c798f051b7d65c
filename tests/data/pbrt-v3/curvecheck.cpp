// Hits of rays on pbrt-v3's curves (flat, cylinder, ribbon; bezier and bspline), for
// src/shapes/curve.rs's test. Output: curve-hits.txt.
#include "shapes/curve.h"
#include "paramset.h"
#include "core/interaction.h"
#include <cstdio>
#include <cstdint>
#include <memory>
using namespace pbrt;
static uint64_t state = 88172645463325252ull;
static float rnd() { state ^= state << 13; state ^= state >> 7; state ^= state << 17; return (state >> 40) / float(1 << 24); }
int main() {
    Transform o2w[3] = {Translate(Vector3f(0.1f, 0.2f, -0.3f)) * RotateZ(25.f),
                        RotateY(-20.f) * Scale(1.f, 1.5f, 1.f),
                        Scale(-1.f, 1.f, 1.f)};
    Transform w2o[3] = {Inverse(o2w[0]), Inverse(o2w[1]), Inverse(o2w[2])};
    std::vector<std::shared_ptr<Shape>> shapes[3];
    {
        ParamSet ps;
        std::unique_ptr<Point3f[]> p(new Point3f[7]{{-1, -0.5f, 0}, {-0.5f, 0.8f, 0.3f}, {0, -0.6f, -0.2f}, {0.3f, 0.1f, 0.4f}, {0.6f, 0.7f, 0.1f}, {0.9f, -0.3f, 0.2f}, {1.1f, 0.4f, -0.3f}});
        ps.AddPoint3f("P", std::move(p), 7);
        std::unique_ptr<Float[]> w0(new Float[1]{0.25f}), w1(new Float[1]{0.08f});
        ps.AddFloat("width0", std::move(w0), 1); ps.AddFloat("width1", std::move(w1), 1);
        std::unique_ptr<std::string[]> t(new std::string[1]{"flat"}); ps.AddString("type", std::move(t), 1);
        shapes[0] = CreateCurveShape(&o2w[0], &w2o[0], false, ps);
    }
    {
        ParamSet ps;
        std::unique_ptr<Point3f[]> p(new Point3f[5]{{-0.9f, 0, -0.6f}, {-0.4f, 0.5f, 0.2f}, {0.1f, -0.4f, 0.5f}, {0.5f, 0.3f, -0.1f}, {1.0f, -0.2f, 0.3f}});
        ps.AddPoint3f("P", std::move(p), 5);
        std::unique_ptr<Float[]> w(new Float[1]{0.3f}); ps.AddFloat("width", std::move(w), 1);
        std::unique_ptr<std::string[]> t(new std::string[1]{"cylinder"}); ps.AddString("type", std::move(t), 1);
        std::unique_ptr<std::string[]> b(new std::string[1]{"bspline"}); ps.AddString("basis", std::move(b), 1);
        std::unique_ptr<int[]> sd(new int[1]{2}); ps.AddInt("splitdepth", std::move(sd), 1);
        shapes[1] = CreateCurveShape(&o2w[1], &w2o[1], true, ps);
    }
    {
        ParamSet ps;
        std::unique_ptr<Point3f[]> p(new Point3f[5]{{-1, 0, 0}, {-0.3f, 0.6f, 0.2f}, {0.4f, -0.5f, 0.1f}, {0.7f, 0.2f, 0.5f}, {1.0f, 0.5f, -0.2f}});
        ps.AddPoint3f("P", std::move(p), 5);
        std::unique_ptr<Float[]> w(new Float[1]{0.35f}); ps.AddFloat("width", std::move(w), 1);
        std::unique_ptr<std::string[]> t(new std::string[1]{"ribbon"}); ps.AddString("type", std::move(t), 1);
        std::unique_ptr<int[]> deg(new int[1]{2}); ps.AddInt("degree", std::move(deg), 1);
        std::unique_ptr<Normal3f[]> n(new Normal3f[3]{{0, 0, 1}, {0.3f, 0.2f, 1}, {-0.5f, 0.6f, 0.4f}});
        ps.AddNormal3f("N", std::move(n), 3);
        shapes[2] = CreateCurveShape(&o2w[2], &w2o[2], false, ps);
    }
    for (int s = 0; s < 3; ++s) {
        printf("pieces %d %d\n", s, (int)shapes[s].size());
        for (int i = 0; i < 400; ++i) {
            Point3f o(rnd() * 6 - 3, rnd() * 6 - 3, rnd() * 6 - 3);
            Point3f target(rnd() * 2.4f - 1.2f, rnd() * 2 - 1, rnd() * 1.6f - 0.8f);
            Ray r(o, target - o);
            bool any = false; Float tBest = 0; SurfaceInteraction best;
            for (auto &c : shapes[s]) {
                Float t; SurfaceInteraction si;
                if (c->Intersect(r, &t, &si, false)) { any = true; tBest = t; best = si; r.tMax = t; }
            }
            printf("%d %.7g %.7g %.7g %.7g %.7g %.7g", s, o.x, o.y, o.z, r.d.x, r.d.y, r.d.z);
            if (!any) { printf(" miss\n"); continue; }
            SurfaceInteraction &si = best;
            printf(" hit %.7g  %.7g %.7g %.7g  %.7g %.7g %.7g  %.7g %.7g  %.7g %.7g %.7g  %.7g %.7g %.7g\n", tBest,
                   si.p.x, si.p.y, si.p.z, si.n.x, si.n.y, si.n.z, si.uv.x, si.uv.y,
                   si.dpdu.x, si.dpdu.y, si.dpdu.z, si.dpdv.x, si.dpdv.y, si.dpdv.z);
        }
    }
}

// pbrt-v3's own tessellation of two NURBS patches (non-rational "P" and rational "Pw", both with
// non-uniform knot vectors and a sub-range of the parameters), for src/shapes/nurbs.rs's test.
// Build: see the test's doc comment; output: nurbs-mesh.txt. Lines: "patch K NV NT", then NV
// vertex lines "px py pz  nx ny nz  u v", then one line of the 3 NT vertex indices.
#include "pbrt.h"
#include "paramset.h"
#include "transform.h"
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>
// Triangle::mesh is private and CreateNURBS gives back only Triangle shapes; open it up here.
#define private public
#include "shapes/triangle.h"
#undef private
#include "shapes/nurbs.h"
using namespace pbrt;

static void ints(ParamSet &ps, const char *name, int v) {
    std::unique_ptr<int[]> a(new int[1]);
    a[0] = v;
    ps.AddInt(name, std::move(a), 1);
}
static void floats(ParamSet &ps, const char *name, const std::vector<Float> &v) {
    std::unique_ptr<Float[]> a(new Float[v.size()]);
    for (size_t i = 0; i < v.size(); ++i) a[i] = v[i];
    ps.AddFloat(name, std::move(a), v.size());
}

static void dump(int k, const ParamSet &ps) {
    Transform id;
    auto shapes = CreateNURBS(&id, &id, false, ps);
    const TriangleMesh &m = *static_cast<const Triangle *>(shapes[0].get())->mesh;
    printf("patch %d %d %d\n", k, m.nVertices, m.nTriangles);
    for (int i = 0; i < m.nVertices; ++i)
        printf("%.8g %.8g %.8g  %.8g %.8g %.8g  %.8g %.8g\n", m.p[i].x, m.p[i].y, m.p[i].z,
               m.n[i].x, m.n[i].y, m.n[i].z, m.uv[i].x, m.uv[i].y);
    for (int i = 0; i < 3 * m.nTriangles; ++i)
        printf(i + 1 < 3 * m.nTriangles ? "%d " : "%d\n", m.vertexIndices[i]);
}

int main() {
    {
        // Non-rational: cubic in u, quadratic in v, interior knots at 0.3 and 0.6, u1 = 0.9.
        ParamSet ps;
        ints(ps, "nu", 5);
        ints(ps, "uorder", 4);
        floats(ps, "uknots", {0, 0, 0, 0, 0.3f, 1, 1, 1, 1});
        floats(ps, "u1", {0.9f});
        ints(ps, "nv", 4);
        ints(ps, "vorder", 3);
        floats(ps, "vknots", {0, 0, 0, 0.6f, 1, 1, 1});
        const float z[20] = {0,    0.3f, -0.2f, 0.5f, 0.1f,  0.4f, 1.2f, 0.8f, -0.3f, 0.2f,
                             -0.1f, 0.9f, 1.5f,  0.6f, 0.0f,  0.2f, 0.1f, -0.4f, 0.3f, 0.5f};
        std::unique_ptr<Point3f[]> P(new Point3f[20]);
        for (int v = 0; v < 4; ++v)
            for (int u = 0; u < 5; ++u)
                P[v * 5 + u] = Point3f(0.5f * u + 0.1f * v, 0.6f * v - 0.05f * u * u, z[v * 5 + u]);
        ps.AddPoint3f("P", std::move(P), 20);
        dump(0, ps);
    }
    {
        // Rational: a semicircle of two quadratic arcs in u (double knot at 0.4), swept along a
        // quadratic in v on knots [1 1 1 1.5 3 3 3] with extra v weights, v in [1.2, 2.8].
        ParamSet ps;
        ints(ps, "nu", 5);
        ints(ps, "uorder", 3);
        floats(ps, "uknots", {0, 0, 0, 0.4f, 0.4f, 1, 1, 1});
        ints(ps, "nv", 4);
        ints(ps, "vorder", 3);
        floats(ps, "vknots", {1, 1, 1, 1.5f, 3, 3, 3});
        floats(ps, "v0", {1.2f});
        floats(ps, "v1", {2.8f});
        const float h = std::sqrt(0.5f);
        const float cx[5] = {1, 1, 0, -1, -1}, cy[5] = {0, 1, 1, 1, 0}, wu[5] = {1, h, 1, h, 1};
        const float r[4] = {1, 1.2f, 0.9f, 0.7f}, zz[4] = {0, 0.5f, 1.2f, 2},
                    wv[4] = {1, 0.8f, 1.3f, 1};
        std::vector<Float> pw;
        for (int v = 0; v < 4; ++v)
            for (int u = 0; u < 5; ++u) {
                float w = wu[u] * wv[v];
                pw.insert(pw.end(), {r[v] * cx[u] * w, r[v] * cy[u] * w, zz[v] * w, w});
            }
        floats(ps, "Pw", pw);
        dump(1, ps);
    }
}

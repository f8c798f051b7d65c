// Prints pbrt-v3's DisneyMaterial BSDF (materials/disney.cpp) for acr's src/bsdf/disney/tests.rs test
// `bsdf_matches_pbrt_v3`: for each parameter set, the BSDF built by
// DisneyMaterial::ComputeScatteringFunctions on a SurfaceInteraction with tilted geometric
// and shading frames, then bsdf->f, bsdf->Pdf (and each lobe's f and Pdf in the local frame)
// for pairs of directions, and bsdf->Sample_f for given samples. Written for acr (CC0).
//
// Build against a pbrt-v3 build tree, and run:
//   B=/work/pbrt-v3-build; F=$(grep CXX_FLAGS $B/build/CMakeFiles/pbrt.dir/flags.make | cut -d= -f2-)
//   I=$(grep CXX_INCLUDES $B/build/CMakeFiles/pbrt.dir/flags.make | cut -d= -f2-)
//   LIBS="$B/build/libpbrt.a $(find $B/build -name '*.a' ! -name libpbrt.a | tr '\n' ' ')"
//   eval g++ $F $I disneycheck.cpp -o disneycheck $LIBS $LIBS -lpthread -ldl -lz
//   ./disneycheck > disney-bsdf.txt
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>
#include "core/pbrt.h"
#include "core/geometry.h"
#include "core/spectrum.h"
#include "core/microfacet.h"
#include "core/shape.h"
#include "core/interaction.h"
#include "core/memory.h"
#include "core/texture.h"
#include "textures/constant.h"
#include "materials/disney.h"
// The BSDF's lobes are private: opened here to print each lobe's values.
#define private public
#include "core/reflection.h"
#undef private
using namespace pbrt;

static std::shared_ptr<Texture<Float>> F(Float v) {
    return std::make_shared<ConstantTexture<Float>>(v);
}
static std::shared_ptr<Texture<Spectrum>> S(Float r, Float g, Float b) {
    Float rgb[3] = {r, g, b};
    return std::make_shared<ConstantTexture<Spectrum>>(Spectrum::FromRGB(rgb));
}

struct Params {
    const char *name;
    Float color[3];
    Float metallic, eta, roughness, speculartint, anisotropic, sheen, sheentint, clearcoat,
        clearcoatgloss, spectrans;
    bool thin;
    Float flatness, difftrans;
};

static void pv(const char *tag, const Spectrum &s) {
    Float rgb[3];
    s.ToRGB(rgb);
    printf(" %s %.9g %.9g %.9g", tag, rgb[0], rgb[1], rgb[2]);
}

int main() {
    // The parameter sets; acr's test writes the same values as a Material line.
    Params sets[] = {
        // name, color, metallic, eta, roughness, speculartint, anisotropic, sheen, sheentint,
        // clearcoat, clearcoatgloss, spectrans, thin, flatness, difftrans
        {"base", {0.8f, 0.3f, 0.2f}, 0, 1.5f, 0.5f, 0, 0, 0, 0.5f, 0, 1, 0, false, 0, 1},
        {"metallic", {0.9f, 0.6f, 0.3f}, 1, 1.5f, 0.3f, 0, 0, 0, 0.5f, 0, 1, 0, false, 0, 1},
        {"half-metal-tint-sheen", {0.2f, 0.5f, 0.8f}, 0.5f, 1.5f, 0.4f, 0.7f, 0, 0.8f, 0.3f, 0, 1, 0, false, 0, 1},
        {"anisotropic", {0.7f, 0.7f, 0.7f}, 0.7f, 1.5f, 0.4f, 0, 0.8f, 0, 0.5f, 0, 1, 0, false, 0, 1},
        {"clearcoat", {0.1f, 0.3f, 0.6f}, 0, 1.5f, 0.6f, 0, 0, 0, 0.5f, 1, 0.6f, 0, false, 0, 1},
        {"sheen", {0.6f, 0.2f, 0.4f}, 0, 1.5f, 0.8f, 0, 0, 1, 0.5f, 0, 1, 0, false, 0, 1},
        {"thin", {0.5f, 0.8f, 0.3f}, 0, 1.4f, 0.35f, 0, 0, 0, 0.5f, 0, 1, 0.6f, true, 0.4f, 0.8f},
        {"spectrans", {0.9f, 0.9f, 0.7f}, 0.1f, 1.33f, 0.25f, 0, 0.3f, 0, 0.5f, 0, 1, 0.7f, false, 0, 1},
        {"all-eight", {0.7f, 0.4f, 0.3f}, 0.2f, 1.6f, 0.5f, 0.4f, 0.5f, 0.6f, 0.2f, 0.5f, 0.3f, 0.5f, true, 0.7f, 1.2f},
        {"thin-metal", {0.4f, 0.4f, 0.9f}, 1, 1.5f, 0.2f, 0, 0, 0, 0.5f, 0, 1, 0, true, 0, 1},
    };
    // A hit with a tangent frame turned about the normal and a tilted geometric normal.
    Vector3f dpdu = Normalize(Vector3f(1, 0.3f, 0.2f)), dpdv = Normalize(Vector3f(-0.2f, 1, 0.1f));
    SurfaceInteraction si(Point3f(0.1f, 0.2f, 0.3f), Vector3f(0, 0, 0), Point2f(0.3f, 0.6f),
                          Vector3f(0, 0, 1), dpdu, dpdv, Normal3f(0, 0, 0), Normal3f(0, 0, 0), 0,
                          nullptr);
    // Shading tangents that differ from the geometric ones (as a mesh's vertex normals do).
    Vector3f dpdus = Normalize(Vector3f(1, 0.25f, 0.3f)), dpdvs = Normalize(Vector3f(-0.25f, 1, 0.05f));
    si.SetShadingGeometry(dpdus, dpdvs, Normal3f(0, 0, 0), Normal3f(0, 0, 0), false);
    printf("frame n %.9g %.9g %.9g ns %.9g %.9g %.9g dpdus %.9g %.9g %.9g dpdvs %.9g %.9g %.9g\n",
           si.n.x, si.n.y, si.n.z, si.shading.n.x, si.shading.n.y, si.shading.n.z,
           si.shading.dpdu.x, si.shading.dpdu.y, si.shading.dpdu.z, si.shading.dpdv.x,
           si.shading.dpdv.y, si.shading.dpdv.z);
    // Directions in the world (not all above the surface).
    Vector3f dirs[] = {
        Normalize(Vector3f(0.1f, 0.2f, 1)),   Normalize(Vector3f(0.6f, -0.3f, 0.7f)),
        Normalize(Vector3f(-0.5f, 0.4f, 0.6f)), Normalize(Vector3f(0.9f, 0.1f, 0.15f)),
        Normalize(Vector3f(-0.3f, -0.6f, -0.7f)), Normalize(Vector3f(0.2f, 0.5f, -0.8f)),
        Normalize(Vector3f(-0.62f, 0.28f, 0.7f)),
    };
    const int nd = sizeof(dirs) / sizeof(dirs[0]);
    for (int i = 0; i < nd; ++i) printf("dir %d %.9g %.9g %.9g\n", i, dirs[i].x, dirs[i].y, dirs[i].z);
    Point2f us[] = {Point2f(0.03f, 0.7f),  Point2f(0.21f, 0.15f), Point2f(0.37f, 0.92f),
                    Point2f(0.52f, 0.33f), Point2f(0.64f, 0.58f), Point2f(0.78f, 0.05f),
                    Point2f(0.86f, 0.44f), Point2f(0.97f, 0.81f), Point2f(0.55f, 0.5f),
                    Point2f(0.13f, 0.99f), Point2f(0.71f, 0.27f), Point2f(0.44f, 0.66f)};
    // No u[0] is a multiple of 1 / (lobe count): the remapped u[0] would be 0, where pbrt-v3's
    // TrowbridgeReitzSample11 cancels catastrophically (its slope tends to infinity) and the
    // result depends on the compiler's use of FMA.
    for (const Params &p : sets) {
        DisneyMaterial m(S(p.color[0], p.color[1], p.color[2]), F(p.metallic), F(p.eta),
                         F(p.roughness), F(p.speculartint), F(p.anisotropic), F(p.sheen),
                         F(p.sheentint), F(p.clearcoat), F(p.clearcoatgloss), F(p.spectrans),
                         S(0, 0, 0), p.thin, F(p.flatness), F(p.difftrans), nullptr);
        MemoryArena arena;
        SurfaceInteraction s = si;
        m.ComputeScatteringFunctions(&s, arena, TransportMode::Radiance, true);
        BSDF *b = s.bsdf;
        printf("case %s color %g %g %g metallic %g eta %g roughness %g speculartint %g "
               "anisotropic %g sheen %g sheentint %g clearcoat %g clearcoatgloss %g spectrans %g "
               "thin %d flatness %g difftrans %g lobes %d\n",
               p.name, p.color[0], p.color[1], p.color[2], p.metallic, p.eta, p.roughness,
               p.speculartint, p.anisotropic, p.sheen, p.sheentint, p.clearcoat,
               p.clearcoatgloss, p.spectrans, p.thin ? 1 : 0, p.flatness, p.difftrans,
               b->nBxDFs);
        for (int i = 0; i < b->nBxDFs; ++i)
            printf("lobe %d %s\n", i, b->bxdfs[i]->ToString().c_str());
        for (int o = 0; o < nd; ++o) {
            for (int i = 0; i < nd; ++i) {
                Vector3f wo = dirs[o], wi = dirs[i];
                printf("f %d %d", o, i);
                pv("f", b->f(wo, wi));
                printf(" pdf %.9g\n", b->Pdf(wo, wi));
                Vector3f lo = b->WorldToLocal(wo), li = b->WorldToLocal(wi);
                for (int k = 0; k < b->nBxDFs; ++k) {
                    printf("l %d", k);
                    pv("f", b->bxdfs[k]->f(lo, li));
                    printf(" pdf %.9g\n", b->bxdfs[k]->Pdf(lo, li));
                }
            }
            for (const Point2f &u : us) {
                Vector3f wi;
                Float pdf = 0;
                BxDFType t = BxDFType(0);
                Spectrum f = b->Sample_f(dirs[o], &wi, u, &pdf, BSDF_ALL, &t);
                if (pdf == 0) {
                    printf("s %d %.9g %.9g none\n", o, u.x, u.y);
                    continue;
                }
                printf("s %d %.9g %.9g wi %.9g %.9g %.9g", o, u.x, u.y, wi.x, wi.y, wi.z);
                pv("f", f);
                printf(" pdf %.9g type %d\n", pdf, (int)t);
            }
        }
    }
}

#include "core/texture.h"
#include "core/interaction.h"
#include "core/material.h"
#include "shapes/sphere.h"
#include "textures/fbm.h"
#include "textures/scale.h"
#include "textures/constant.h"
#include <cstdio>
using namespace pbrt;
struct M : public Material { void ComputeScatteringFunctions(SurfaceInteraction*, MemoryArena&, TransportMode, bool) const {} };
int main() {
    Transform o2w = Translate(Vector3f(0, 0.9f, 1.2f)), w2o = Inverse(o2w);
    Sphere s(&o2w, &w2o, false, 0.9f, -0.9f, 0.9f, 360.f);
    Transform tex2world = Scale(0.6f, 0.6f, 0.6f);
    auto fbm = std::make_shared<FBmTexture<Float>>(std::unique_ptr<TextureMapping3D>(new IdentityMapping3D(tex2world)), 4, 0.5f);
    auto c = std::make_shared<ConstantTexture<Float>>(0.04f);
    std::shared_ptr<Texture<Float>> bump = std::make_shared<ScaleTexture<Float, Float>>(fbm, c);
    float dirs[][3] = {{0.0f, -0.1f, 1.0f}, {0.1f, -0.12f, 1.0f}, {-0.08f, -0.05f, 1.0f}};
    for (auto &d : dirs) {
        Ray r(Point3f(0, 1.5f, -5), Normalize(Vector3f(d[0], d[1], d[2])));
        Float t; SurfaceInteraction si;
        if (!s.Intersect(r, &t, &si, true)) { printf("miss\n"); continue; }
        printf("p %.6f %.6f %.6f uv %.6f %.6f n %.6f %.6f %.6f dpdu %.5f %.5f %.5f dpdv %.5f %.5f %.5f d %.6f\n", si.p.x, si.p.y, si.p.z, si.uv.x, si.uv.y, si.n.x, si.n.y, si.n.z, si.shading.dpdu.x, si.shading.dpdu.y, si.shading.dpdu.z, si.shading.dpdv.x, si.shading.dpdv.y, si.shading.dpdv.z, bump->Evaluate(si));
        printf("  dndu %.6f %.6f %.6f dndv %.6f %.6f %.6f\n", si.dndu.x, si.dndu.y, si.dndu.z, si.dndv.x, si.dndv.y, si.dndv.z);
        Point3f pt = Inverse(tex2world)(si.p);
        printf("  ptex %.6f %.6f %.6f fbm direct %.6f eval %.6f dpdx %g\n", pt.x, pt.y, pt.z, FBm(pt, Vector3f(0,0,0), Vector3f(0,0,0), 0.5f, 4), fbm->Evaluate(si), si.dpdx.x);
        Material::Bump(bump, &si);
        printf("  bumped ns %.6f %.6f %.6f\n", si.shading.n.x, si.shading.n.y, si.shading.n.z);
    }
}

#include "core/texture.h"
#include "core/interaction.h"
#include "core/material.h"
#include "shapes/triangle.h"
#include "textures/fbm.h"
#include "textures/scale.h"
#include "textures/constant.h"
#include <cstdio>
using namespace pbrt;
int main() {
    Transform id;
    int idx[6] = {0,1,2,0,2,3};
    Point3f P[4] = {{-8,0,-8},{8,0,-8},{8,0,8},{-8,0,8}};
    Normal3f N[4] = {{0,1,0},{0,1,0},{0,1,0},{0,1,0}};
    Point2f UV[4] = {{0,0},{1,0},{1,1},{0,1}};
    auto tris = CreateTriangleMesh(&id, &id, false, 2, idx, 4, P, nullptr, N, UV, nullptr, nullptr);
    Transform tex2world = Scale(1.5f, 1.5f, 1.5f);
    auto fbm = std::make_shared<FBmTexture<Float>>(std::unique_ptr<TextureMapping3D>(new IdentityMapping3D(tex2world)), 3, 0.5f);
    auto c = std::make_shared<ConstantTexture<Float>>(0.08f);
    std::shared_ptr<Texture<Float>> bump = std::make_shared<ScaleTexture<Float, Float>>(fbm, c);
    float xs[][2] = {{0.3f, -1.0f}, {-1.7f, 2.2f}, {2.9f, 0.4f}};
    for (auto &x : xs) {
        Ray r(Point3f(x[0], 3, x[1] - 2), Normalize(Vector3f(0, -3, 2)));
        for (auto &t : tris) {
            Float th; SurfaceInteraction si;
            if (!t->Intersect(r, &th, &si, true)) continue;
            printf("p %.6f %.6f %.6f uv %.6f %.6f n %.6f %.6f %.6f ns %.6f %.6f %.6f sdpdu %.6f %.6f %.6f sdpdv %.6f %.6f %.6f\n", si.p.x, si.p.y, si.p.z, si.uv.x, si.uv.y, si.n.x, si.n.y, si.n.z, si.shading.n.x, si.shading.n.y, si.shading.n.z, si.shading.dpdu.x, si.shading.dpdu.y, si.shading.dpdu.z, si.shading.dpdv.x, si.shading.dpdv.y, si.shading.dpdv.z);
            Material::Bump(bump, &si);
            printf("  bumped ns %.6f %.6f %.6f\n", si.shading.n.x, si.shading.n.y, si.shading.n.z);
        }
    }
}

#include "core/texture.h"
#include "core/interaction.h"
#include "textures/marble.h"
#include "textures/windy.h"
#include "textures/wrinkled.h"
#include "textures/dots.h"
#include "textures/constant.h"
#include <cstdio>
using namespace pbrt;
int main() {
    float pts[][3] = {{0.5f,0.5f,0.5f},{1.3f,2.7f,0.4f},{-3.21f,7.7f,12.05f},{100.25f,-40.5f,3.125f},{0.1f,-1.2f,2.3f}};
    MarbleTexture marble(std::unique_ptr<TextureMapping3D>(new IdentityMapping3D(Transform())), 8, .5f, 1.f, .2f);
    WindyTexture<Float> windy(std::unique_ptr<TextureMapping3D>(new IdentityMapping3D(Transform())));
    WrinkledTexture<Float> wr(std::unique_ptr<TextureMapping3D>(new IdentityMapping3D(Transform())), 8, .5f);
    auto in = std::make_shared<ConstantTexture<Float>>(1.f);
    auto out = std::make_shared<ConstantTexture<Float>>(0.f);
    DotsTexture<Float> dots(std::unique_ptr<TextureMapping2D>(new UVMapping2D(1,1,0,0)), out, in);
    for (auto &q : pts) {
        SurfaceInteraction si(Point3f(q[0],q[1],q[2]), Vector3f(0,0,0), Point2f(q[0], q[1]), Vector3f(0,0,1), Vector3f(1,0,0), Vector3f(0,1,0), Normal3f(0,0,0), Normal3f(0,0,0), 0, nullptr);
        Spectrum m = marble.Evaluate(si);
        Float rgb[3]; m.ToRGB(rgb);
        printf("([%g, %g, %g], [%.9g, %.9g, %.9g], %.9g, %.9g, %.0f),\n", q[0],q[1],q[2], rgb[0], rgb[1], rgb[2], windy.Evaluate(si), wr.Evaluate(si), dots.Evaluate(si));
    }
}

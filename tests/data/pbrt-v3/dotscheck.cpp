#include "core/texture.h"
#include "core/interaction.h"
#include "textures/dots.h"
#include "textures/constant.h"
#include <cstdio>
using namespace pbrt;
int main() {
    auto in = std::make_shared<ConstantTexture<Float>>(1.f);
    auto out = std::make_shared<ConstantTexture<Float>>(0.f);
    DotsTexture<Float> dots(std::unique_ptr<TextureMapping2D>(new UVMapping2D(1,1,0,0)), out, in);
    for (int j = 0; j < 24; ++j) { for (int i = 0; i < 64; ++i) {
        float s = i * 0.25f - 3.1f, t = j * 0.25f - 2.05f;
        SurfaceInteraction si(Point3f(0,0,0), Vector3f(0,0,0), Point2f(s, t), Vector3f(0,0,1), Vector3f(1,0,0), Vector3f(0,1,0), Normal3f(0,0,0), Normal3f(0,0,0), 0, nullptr);
        printf("%d", (int)dots.Evaluate(si)); } printf("\n"); }
}

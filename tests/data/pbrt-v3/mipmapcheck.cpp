// Prints pbrt-v3's MIPMap lookups (core/mipmap.h) for acr's src/mipmap.rs test
// `lookups_match_pbrt_v3`: a 12 x 7 float image (texel (s, t) = 0.1 + ((3 s + 5 t) mod 7) / 7
// + 0.02 s, resampled to 16 x 8 by pbrt-v3) and an 8 x 8 one (no resampling), in the three
// wrap modes, EWA and trilinear, at points and footprints from pbrt-v3's RNG. Written for
// acr (CC0).
//
// Build against a pbrt-v3 build tree, and run from the repository root:
//   B=/work/pbrt-v3-build; F=$(grep CXX_FLAGS $B/build/CMakeFiles/pbrt.dir/flags.make | cut -d= -f2-)
//   I=$(grep CXX_INCLUDES $B/build/CMakeFiles/pbrt.dir/flags.make | cut -d= -f2-)
//   LIBS="$B/build/libpbrt.a $(find $B/build -name '*.a' ! -name libpbrt.a | tr '\n' ' ')"
//   eval g++ $F $I tests/data/pbrt-v3/mipmapcheck.cpp -o /tmp/mipmapcheck $LIBS $LIBS -lpthread -ldl -lz
//   /tmp/mipmapcheck > tests/data/pbrt-v3/mipmap.txt
#include <cmath>
#include <cstdio>
#include <vector>
#include "core/pbrt.h"
#include "core/geometry.h"
#include "core/mipmap.h"
#include "core/rng.h"
#include "core/parallel.h"
using namespace pbrt;

int main() {
    ParallelInit();
    RNG rng(11);
    int sizes[][2] = {{12, 7}, {8, 8}};
    ImageWrap wraps[] = {ImageWrap::Repeat, ImageWrap::Black, ImageWrap::Clamp};
    for (auto &size : sizes) {
        int w = size[0], h = size[1];
        std::vector<Float> img(w * h);
        for (int t = 0; t < h; ++t)
            for (int s = 0; s < w; ++s)
                img[t * w + s] = 0.1f + ((3 * s + 5 * t) % 7) / 7.f + 0.02f * s;
        for (int wi = 0; wi < 3; ++wi) {
            for (int tri = 0; tri < 2; ++tri) {
                MIPMap<Float> mip(Point2i(w, h), img.data(), tri == 1, 8.f, wraps[wi]);
                for (int i = 0; i < 40; ++i) {
                    Point2f st(rng.UniformFloat() * 1.6f - 0.3f, rng.UniformFloat() * 1.6f - 0.3f);
                    Float scale = std::pow(10.f, -3 + 3 * rng.UniformFloat());
                    Vector2f d0(scale * (rng.UniformFloat() - 0.5f), scale * (rng.UniformFloat() - 0.5f));
                    Vector2f d1(scale * (rng.UniformFloat() - 0.5f), scale * (rng.UniformFloat() - 0.5f));
                    if (i % 10 == 0) d1 = d0 * 0.01f;
                    if (i % 10 == 1) d0 = d1 = Vector2f(0, 0);
                    printf("%d %d %d %d %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", w, h, wi, tri, st.x,
                           st.y, d0.x, d0.y, d1.x, d1.y, mip.Lookup(st, d0, d1));
                }
            }
        }
    }
    ParallelCleanup();
    return 0;
}

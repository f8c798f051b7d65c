// Prints pbrt-v3's FourierBSDF (core/reflection.cpp) over scenes/pbrt-v3/textures/tabulated.bsdf
// for acr's src/fourier/tests.rs test `fourier_bsdf_matches_pbrt_v3`: for pairs of local directions,
// f (RGB) and Pdf; for given (wo, u), Sample_f's wi, f and pdf. Written for acr (CC0).
//
// Build against a pbrt-v3 build tree, and run from the repository root:
//   B=/work/pbrt-v3-build; F=$(grep CXX_FLAGS $B/build/CMakeFiles/pbrt.dir/flags.make | cut -d= -f2-)
//   I=$(grep CXX_INCLUDES $B/build/CMakeFiles/pbrt.dir/flags.make | cut -d= -f2-)
//   LIBS="$B/build/libpbrt.a $(find $B/build -name '*.a' ! -name libpbrt.a | tr '\n' ' ')"
//   eval g++ $F $I tests/data/pbrt-v3/fouriercheck.cpp -o /tmp/fouriercheck $LIBS $LIBS -lpthread -ldl -lz
//   /tmp/fouriercheck scenes/pbrt-v3/textures/tabulated.bsdf > tests/data/pbrt-v3/fourier-values.txt
#include <cmath>
#include <cstdio>
#include "core/pbrt.h"
#include "core/geometry.h"
#include "core/spectrum.h"
#include "core/reflection.h"
#include "core/sampling.h"
#include "core/rng.h"
using namespace pbrt;

int main(int argc, char **argv) {
    if (argc < 2) return 1;
    FourierBSDFTable table;
    if (!FourierBSDFTable::Read(argv[1], &table)) return 1;
    FourierBSDF bsdf(table, TransportMode::Radiance);
    RNG rng(7);
    auto dir = [&]() {
        Point2f u(rng.UniformFloat(), rng.UniformFloat());
        return UniformSampleSphere(u);
    };
    for (int i = 0; i < 400; ++i) {
        Vector3f wo = dir(), wi = dir();
        Spectrum f = bsdf.f(wo, wi);
        Float rgb[3];
        f.ToRGB(rgb);
        printf("f %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", wo.x, wo.y, wo.z, wi.x,
               wi.y, wi.z, rgb[0], rgb[1], rgb[2], bsdf.Pdf(wo, wi));
    }
    for (int i = 0; i < 400; ++i) {
        Vector3f wo = dir(), wi;
        Point2f u(rng.UniformFloat(), rng.UniformFloat());
        Float pdf = 0;
        Spectrum f = bsdf.Sample_f(wo, &wi, u, &pdf, nullptr);
        Float rgb[3];
        f.ToRGB(rgb);
        printf("s %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", wo.x, wo.y,
               wo.z, u.x, u.y, wi.x, wi.y, wi.z, rgb[0], rgb[1], rgb[2], pdf);
    }
    return 0;
}

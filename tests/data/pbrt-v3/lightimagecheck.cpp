// Sample_Li and Power of pbrt-v3's goniometric and projection lights, for src/light/tests.rs
// (output: lightimage.txt), and the images they and scenes/pbrt-v3/image-lights.pbrt use.
// Build against a pbrt-v3 build tree B (release):
//   F=$(grep CXX_FLAGS $B/build/CMakeFiles/pbrt.dir/flags.make | cut -d= -f2-)
//   I=$(grep CXX_INCLUDES $B/build/CMakeFiles/pbrt.dir/flags.make | cut -d= -f2-)
//   LIBS="$B/build/libpbrt.a $(find $B/build -name '*.a' ! -name libpbrt.a | tr '\n' ' ')"
//   eval g++ $F $I lightimagecheck.cpp -o lightimagecheck $LIBS $LIBS -lpthread -ldl -lz
// Run from the repository root:
//   lightimagecheck tests/data/pbrt-v3 scenes/pbrt-v3/textures > tests/data/pbrt-v3/lightimage.txt
#include "lights/goniometric.h"
#include "lights/projection.h"
#include "core/imageio.h"
#include "core/interaction.h"
#include "core/parallel.h"
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <string>
#include <vector>
using namespace pbrt;
static uint64_t state = 88172645463325252ull;
static float rnd() { state ^= state << 13; state ^= state >> 7; state ^= state << 17; return (state >> 40) / float(1 << 24); }

static void write(const std::string &name, const std::vector<Float> &rgb, int w, int h) {
    WriteImage(name, rgb.data(), Bounds2i(Point2i(0, 0), Point2i(w, h)), Point2i(w, h));
}

int main(int argc, char **argv) {
    if (argc != 3) { fprintf(stderr, "usage: lightimagecheck TESTDATA_DIR TEXTURE_DIR\n"); return 1; }
    std::string data = argv[1], tex = argv[2];
    PbrtOptions.nThreads = 1;  // the MIP maps are built with ParallelFor
    ParallelInit();
    // Test images: random values (stored as half floats).
    for (auto wh : {std::pair<int, int>(8, 4), std::pair<int, int>(4, 8)}) {
        std::vector<Float> rgb(3 * wh.first * wh.second);
        for (Float &v : rgb) v = 0.05f + 1.95f * rnd();
        write(data + "/lightimage-" + std::to_string(wh.first) + "x" + std::to_string(wh.second) + ".exr",
              rgb, wh.first, wh.second);
    }
    // The scene's goniometric map (64 x 32, phi across, theta down from the light's +y):
    // coloured lobes around the vertical axis, bands in theta, brighter below the horizon.
    {
        int w = 64, h = 32;
        std::vector<Float> rgb(3 * w * h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                Float phi = 2 * Pi * (x + .5f) / w, theta = Pi * (y + .5f) / h;
                Float band = (0.6f + 0.4f * std::cos(8 * theta)) * (theta > Pi / 2 ? 1.f : 0.35f);
                for (int c = 0; c < 3; ++c)
                    rgb[3 * (y * w + x) + c] = band * (0.25f + 0.75f * (0.5f + 0.5f * std::cos(3 * phi + 2.0944f * c)));
            }
        write(tex + "/goniometric.exr", rgb, w, h);
    }
    // The scene's projected slide (64 x 32 PNG): coloured 8-pixel checks inside a grid of
    // white lines.
    {
        int w = 64, h = 32;
        std::vector<Float> rgb(3 * w * h);
        const Float palette[4][3] = {{0.9f, 0.2f, 0.1f}, {0.1f, 0.7f, 0.2f}, {0.15f, 0.3f, 0.9f}, {0.9f, 0.8f, 0.1f}};
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                bool line = x % 8 == 0 || y % 8 == 0;
                int k = ((x / 8) + 2 * (y / 8)) % 4;
                for (int c = 0; c < 3; ++c)
                    rgb[3 * (y * w + x) + c] = line ? 1.f : ((x / 8 + y / 8) % 2 ? palette[k][c] : 0.15f * palette[k][c]);
            }
        write(tex + "/projection-grid.png", rgb, w, h);
    }

    Transform l2w[2] = {Translate(Vector3f(0.3f, -0.2f, 0.5f)) * Rotate(35.f, Vector3f(1, 2, 0.5f)),
                        Translate(Vector3f(-0.4f, 0.6f, 0.1f)) * Rotate(-70.f, Vector3f(0.3f, -1, 0.8f)) *
                            Scale(1.5f, 0.8f, 1.2f)};
    Float rgbI[3] = {1.5f, 0.75f, 2.f};
    Spectrum I = Spectrum::FromRGB(rgbI);
    MediumInterface mi;
    std::string wide = data + "/lightimage-8x4.exr", tall = data + "/lightimage-4x8.exr";
    Light *lights[5] = {
        new GonioPhotometricLight(l2w[0], mi, I, wide),
        new GonioPhotometricLight(l2w[1], mi, I, ""),
        new ProjectionLight(l2w[0], mi, I, wide, 60.f),
        new ProjectionLight(l2w[1], mi, I, tall, 30.f),
        new ProjectionLight(l2w[0], mi, I, "", 45.f),
    };
    // Half the screen window over 1 / tan(fov / 2), in x and y, for the projection lights.
    const Float tanX[5] = {0, 0, 2 * std::tan(Radians(30.f)), std::tan(Radians(15.f)), std::tan(Radians(22.5f))};
    const Float tanY[5] = {0, 0, std::tan(Radians(30.f)), 2 * std::tan(Radians(15.f)), std::tan(Radians(22.5f))};
    const Transform *frame[5] = {&l2w[0], &l2w[1], &l2w[0], &l2w[1], &l2w[0]};
    for (int l = 0; l < 5; ++l) {
        for (int i = 0; i < 300; ++i) {
            // Light-space points: anywhere around a goniometric light, near the poles (the
            // light's +-y) and the phi seam (+x, z -> 0-) first; for a projection light, some
            // behind it and half of those in front within its frustum.
            Point3f q(rnd() * 6 - 3, rnd() * 6 - 3, rnd() * 6 - 3);
            if (l < 2 && i < 4) q = Point3f(0.05f * (i + 1), i % 2 ? -2.f : 2.f, 0.03f);
            else if (l < 2 && i < 8) q = Point3f(2.f, 0.3f * (i - 6), i % 2 ? -1e-3f : 1e-3f);
            else if (l >= 2) {
                Float z = rnd() * 4.5f - 0.5f;
                q = Point3f((rnd() * 2 - 1) * 1.4f * tanX[l] * z, (rnd() * 2 - 1) * 1.4f * tanY[l] * z, z);
            }
            Point3f p = (*frame[l])(q);
            Interaction ref(p, Normal3f(), Vector3f(), Vector3f(0, 0, 1), 0, mi);
            Vector3f wi; Float pdf; VisibilityTester vis;
            Spectrum L = lights[l]->Sample_Li(ref, Point2f(0.5f, 0.5f), &wi, &pdf, &vis);
            Float rgb[3]; L.ToRGB(rgb);
            printf("sample %d %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", l, p.x, p.y, p.z,
                   wi.x, wi.y, wi.z, rgb[0], rgb[1], rgb[2], pdf);
        }
        Float rgb[3]; lights[l]->Power().ToRGB(rgb);
        printf("power %d %.9g %.9g %.9g\n", l, rgb[0], rgb[1], rgb[2]);
    }
}

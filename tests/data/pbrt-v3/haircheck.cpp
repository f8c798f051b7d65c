// pbrt-v3's HairBSDF (materials/hair.{h,cpp}) on random configurations and directions, for
// src/bsdf/hair/tests.rs's `values_match_pbrt_v3` test. Build (from the repository root), with pbrt-v3's
// flags, compiling its hair.cpp and reflection.cpp again without fused multiply-adds (its
// -march=native build fuses them, which moves f and Pdf by up to 2.4e-4 relative in the
// sharpest lobes; without, acr's values are the same floats):
//   B=/work/pbrt-v3-build; F=$(grep CXX_FLAGS $B/build/CMakeFiles/pbrt.dir/flags.make | cut -d= -f2-)
//   I=$(grep CXX_INCLUDES $B/build/CMakeFiles/pbrt.dir/flags.make | cut -d= -f2-)
//   LIBS="$B/build/libpbrt.a $(find $B/build -name '*.a' ! -name libpbrt.a | tr '\n' ' ')"
//   eval g++ $F -ffp-contract=off $I tests/data/pbrt-v3/haircheck.cpp $B/src/materials/hair.cpp \
//     $B/src/core/reflection.cpp -o /tmp/haircheck -Wl,--allow-multiple-definition \
//     $LIBS $LIBS -lpthread -ldl -lz
//   /tmp/haircheck > tests/data/pbrt-v3/hair-values.txt
// Lines (every float with 9 significant digits, so that f32 values round-trip):
//   demux u -> x y                                   DemuxFloat
//   conc ce cp -> r g b                              SigmaAFromConcentration
//   refl r g b beta_n -> r g b                       SigmaAFromReflectance
//   hair h eta sr sg sb beta_m beta_n alpha          a HairBSDF; the lines below use it
//   f wox woy woz wix wiy wiz -> r g b pdf           f and Pdf
//   s wox woy woz u0 u1 -> wix wiy wiz pdf r g b     Sample_f (pdf 0: nothing sampled)
#include "materials/hair.h"
#include "sampling.h"
#include <cstdint>
#include <cstdio>
using namespace pbrt;
static uint64_t state = 0x9E3779B97F4A7C15ull;
static float rnd() {
    state ^= state << 13; state ^= state >> 7; state ^= state << 17;
    return (state >> 40) / float(1 << 24);
}
static Vector3f dir() { Float a = rnd(); return UniformSampleSphere(Point2f(a, rnd())); }
int main() {
    for (int i = 0; i < 20; ++i) {
        Float u = i == 0 ? 0.f : (i == 1 ? 0.99999994f : rnd());
        Point2f d = DemuxFloat(u);
        printf("demux %.9g -> %.9g %.9g\n", u, d.x, d.y);
    }
    for (int i = 0; i < 10; ++i) {
        Float ce = 4 * rnd(), cp = 2 * rnd();
        Spectrum s = HairBSDF::SigmaAFromConcentration(ce, cp);
        Float rgb[3]; s.ToRGB(rgb);
        printf("conc %.9g %.9g -> %.9g %.9g %.9g\n", ce, cp, rgb[0], rgb[1], rgb[2]);
    }
    for (int i = 0; i < 10; ++i) {
        Float c[3] = {rnd(), rnd(), rnd()};
        Float bn = rnd();
        Spectrum s = HairBSDF::SigmaAFromReflectance(RGBSpectrum::FromRGB(c), bn);
        Float rgb[3]; s.ToRGB(rgb);
        printf("refl %.9g %.9g %.9g %.9g -> %.9g %.9g %.9g\n", c[0], c[1], c[2], bn, rgb[0], rgb[1],
               rgb[2]);
    }
    const Float betas_m[] = {0.05f, 0.1f, 0.3f, 0.55f, 1.f};
    const Float betas_n[] = {0.1f, 0.3f, 0.8f};
    const Float etas[] = {1.55f, 1.3f, 2.f};
    const Float alphas[] = {2.f, 0.f, 5.f, -3.f};
    for (int c = 0; c < 30; ++c) {
        Float h = c == 0 ? 0.f : (c == 1 ? 0.999f : (c == 2 ? -1.f : -1 + 2 * rnd()));
        Float eta = etas[c % 3], bm = betas_m[c % 5], bn = betas_n[(c / 5) % 3];
        Float alpha = alphas[(c / 3) % 4];
        Float sig[3];
        if (c % 4 == 0) {
            sig[0] = sig[1] = sig[2] = 0;
        } else if (c % 4 == 1) {
            Spectrum s = HairBSDF::SigmaAFromConcentration(3 * rnd(), rnd());
            s.ToRGB(sig);
        } else {
            Float col[3] = {rnd(), rnd(), rnd()};
            HairBSDF::SigmaAFromReflectance(RGBSpectrum::FromRGB(col), bn).ToRGB(sig);
        }
        HairBSDF hair(h, eta, RGBSpectrum::FromRGB(sig), bm, bn, alpha);
        printf("hair %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", h, eta, sig[0], sig[1], sig[2], bm,
               bn, alpha);
        for (int k = 0; k < 10; ++k) {
            Vector3f wo = dir(), wi = dir();
            if (k == 0) wi = Vector3f(-wo.x, -wo.y, -wo.z);
            if (k == 1) wi = Vector3f(-wo.x, wo.y, wo.z);
            Spectrum f = hair.f(wo, wi);
            Float rgb[3]; f.ToRGB(rgb);
            printf("f %.9g %.9g %.9g %.9g %.9g %.9g -> %.9g %.9g %.9g %.9g\n", wo.x, wo.y, wo.z,
                   wi.x, wi.y, wi.z, rgb[0], rgb[1], rgb[2], hair.Pdf(wo, wi));
        }
        for (int k = 0; k < 10; ++k) {
            Vector3f wo = dir(), wi;
            Point2f u(rnd(), rnd());
            Float pdf = 0;
            BxDFType type;
            Spectrum f = hair.Sample_f(wo, &wi, u, &pdf, &type);
            Float rgb[3]; f.ToRGB(rgb);
            printf("s %.9g %.9g %.9g %.9g %.9g -> %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", wo.x, wo.y,
                   wo.z, u.x, u.y, wi.x, wi.y, wi.z, pdf, rgb[0], rgb[1], rgb[2]);
        }
    }
}

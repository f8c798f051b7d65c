// Prints pbrt-v3's beam-diffusion BSSRDF values (core/bssrdf.cpp, core/interpolation.cpp,
// core/medium.cpp) that acr's src/bssrdf/tests.rs compares with: FresnelMoment1/2,
// BeamDiffusionMS/SS, the table at g = 0, eta = 1.33 (rho_eff, profile, CDF),
// SubsurfaceFromDiffuse, and a TabulatedBSSRDF of Skin1 (Sr, Pdf_Sr, Sample_Sr).
// Written for acr (CC0); its output is tests/data/pbrt-v3/bssrdf-values.txt.
//
// Build against a pbrt-v3 build tree (B=/work/pbrt-v3/build, S=/work/pbrt-v3/src):
//   c++ -O2 -std=gnu++11 -I$S/core -I$S -I$S/ext/glog/src -I$B/src/ext/glog \
//     -I$S/ext/openexr/IlmBase/Imath -I$S/ext/openexr/IlmBase/Half \
//     -I$B/src/ext/openexr/IlmBase/config -DPBRT_CONSTEXPR=constexpr -DPBRT_HAVE_CONSTEXPR \
//     -DPBRT_HAVE_ALIGNAS -DPBRT_THREAD_LOCAL=thread_local tests/data/pbrt-v3/bssrdfcheck.cpp \
//     -o /tmp/bssrdfcheck $B/libpbrt.a $(find $B/src/ext -name '*.a' | tr '\n' ' ') -lz -lpthread
#include "pbrt.h"
#include "bssrdf.h"
#include "interaction.h"
#include "interpolation.h"
#include "medium.h"
#include <cstdio>
#include "parallel.h"
using namespace pbrt;
int main() {
    PbrtOptions.nThreads = 1; ParallelInit();
    BSSRDFTable t(100, 64);
    ComputeBeamDiffusionBSSRDF(0.f, 1.33f, &t);
    int idx[] = {0, 1, 10, 50, 90, 99};
    for (int i : idx) printf("rhoEff[%d] rho=%.9g eff=%.9g\n", i, t.rhoSamples[i], t.rhoEff[i]);
    int pj[] = {1, 10, 30, 63};
    for (int i : {50, 99}) for (int j : pj) printf("profile[%d][%d] r=%.9g p=%.9g cdf=%.9g\n", i, j, t.radiusSamples[j], t.EvalProfile(i, j), t.profileCDF[i*64+j]);
    printf("ms %.9g ss %.9g\n", BeamDiffusionMS(0.7f, 0.3f, 0.f, 1.33f, 0.5f), BeamDiffusionSS(0.7f, 0.3f, 0.f, 1.33f, 0.5f));
    printf("ms_g %.9g ss_g %.9g\n", BeamDiffusionMS(0.7f, 0.3f, 0.4f, 1.5f, 0.2f), BeamDiffusionSS(0.7f, 0.3f, 0.4f, 1.5f, 0.2f));
    printf("fm1 %.9g %.9g fm2 %.9g %.9g\n", FresnelMoment1(1.33f), FresnelMoment1(1/1.33f), FresnelMoment2(1.33f), FresnelMoment2(1/1.33f));
    Spectrum sa, ss;
    Float kd[3] = {0.2f, 0.5f, 0.9f}, mf[3] = {1.f, 0.5f, 2.f};
    SubsurfaceFromDiffuse(t, Spectrum::FromRGB(kd), Spectrum::FromRGB(mf), &sa, &ss);
    printf("sfd sa %.9g %.9g %.9g ss %.9g %.9g %.9g\n", sa[0], sa[1], sa[2], ss[0], ss[1], ss[2]);
    Spectrum a, s;
    GetMediumScatteringProperties("Skin1", &a, &s);
    SurfaceInteraction po(Point3f(0,0,0), Vector3f(0,0,0), Point2f(0,0), Vector3f(0,0,1), Vector3f(1,0,0), Vector3f(0,1,0), Normal3f(0,0,0), Normal3f(0,0,0), 0, nullptr);
    TabulatedBSSRDF b(po, nullptr, TransportMode::Radiance, 1.33f, a, s, t);
    for (Float r : {0.f, 0.05f, 0.5f, 2.f, 10.f}) { Spectrum v = b.Sr(r); printf("Sr(%g) %.9g %.9g %.9g pdf %.9g %.9g %.9g\n", r, v[0], v[1], v[2], b.Pdf_Sr(0, r), b.Pdf_Sr(1, r), b.Pdf_Sr(2, r)); }
    for (Float u : {0.1f, 0.5f, 0.9f, 0.999f}) printf("Sample_Sr(u=%g) %.9g %.9g %.9g\n", u, b.Sample_Sr(0, u), b.Sample_Sr(1, u), b.Sample_Sr(2, u));
    return 0;
}

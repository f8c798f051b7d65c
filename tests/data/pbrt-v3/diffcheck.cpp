// Prints pbrt-v3's ray differentials and what uses them, for acr's test
// `camera_ray_differentials_match_pbrt_v3` (src/differentials_tests.rs): a perspective camera
// (LookAt 0 0.5 -4 at the origin, fov 50, 64x48, and again with lensradius 0.2 focaldistance
// 4), rays for film points scaled by 1/sqrt(16) as pbrt-v3's integrators do, hits on a unit
// sphere at the origin, SurfaceInteraction::ComputeDifferentials, then FBm and Turbulence at
// the hit with its footprint (omega 0.5, 8 octaves), a closed-form Checkerboard2DTexture on
// uv scaled by 64, and Bump's du and dv. Written for acr (CC0).
//
// Build against a pbrt-v3 build tree, and run from the repository root:
//   B=/work/pbrt-v3-build; F=$(grep CXX_FLAGS $B/build/CMakeFiles/pbrt.dir/flags.make | cut -d= -f2-)
//   I=$(grep CXX_INCLUDES $B/build/CMakeFiles/pbrt.dir/flags.make | cut -d= -f2-)
//   LIBS="$B/build/libpbrt.a $(find $B/build -name '*.a' ! -name libpbrt.a | tr '\n' ' ')"
//   eval g++ $F $I tests/data/pbrt-v3/diffcheck.cpp -o /tmp/diffcheck $LIBS $LIBS -lpthread -ldl -lz
//   /tmp/diffcheck > tests/data/pbrt-v3/differentials.txt
#include <cmath>
#include <cstdio>
#include "core/pbrt.h"
#include "core/geometry.h"
#include "core/transform.h"
#include "core/paramset.h"
#include "core/film.h"
#include "core/texture.h"
#include "core/interaction.h"
#include "cameras/perspective.h"
#include "filters/box.h"
#include "shapes/sphere.h"
#include "textures/checkerboard.h"
#include "textures/constant.h"
using namespace pbrt;

int main() {
    Transform worldToCamera = LookAt(Point3f(0, 0.5f, -4), Point3f(0, 0, 0), Vector3f(0, 1, 0));
    Transform cameraToWorld = Inverse(worldToCamera);
    AnimatedTransform c2w(&cameraToWorld, 0, &cameraToWorld, 1);
    Transform identity;
    Sphere sphere(&identity, &identity, false, 1, -1, 1, 360);
    Float pts[][2] = {{32.5f, 24.5f}, {30.2f, 20.7f}, {38.9f, 31.3f}, {25.1f, 14.6f},
                      {41.7f, 22.2f}, {33.3f, 35.8f}, {22.6f, 29.4f}, {35.05f, 17.95f}};
    Float lenses[][2] = {{0, 0}, {0.2f, 4}};
    for (auto &lens : lenses) {
        ParamSet ps;
        Float fov = 50;
        ps.AddFloat("fov", std::unique_ptr<Float[]>(new Float[1]{fov}), 1);
        ps.AddFloat("lensradius", std::unique_ptr<Float[]>(new Float[1]{lens[0]}), 1);
        ps.AddFloat("focaldistance", std::unique_ptr<Float[]>(new Float[1]{lens[1]}), 1);
        Film *film = new Film(Point2i(64, 48), Bounds2f(Point2f(0, 0), Point2f(1, 1)),
                              std::unique_ptr<Filter>(new BoxFilter(Vector2f(0.5f, 0.5f))),
                              35, "unused.exr", 1);
        Camera *camera = CreatePerspectiveCamera(ps, c2w, film, nullptr);
        for (auto &pt : pts) {
            CameraSample cs;
            cs.pFilm = Point2f(pt[0], pt[1]);
            cs.pLens = Point2f(0.3f, 0.7f);
            cs.time = 0;
            RayDifferential ray;
            camera->GenerateRayDifferential(cs, &ray);
            ray.ScaleDifferentials(1 / std::sqrt((Float)16));
            Float tHit;
            SurfaceInteraction si;
            if (!sphere.Intersect(ray, &tHit, &si, false)) continue;
            si.ComputeDifferentials(ray);
            Float fbm = FBm(si.p, si.dpdx, si.dpdy, 0.5f, 8);
            Float turb = Turbulence(si.p, si.dpdx, si.dpdy, 0.5f, 8);
            Checkerboard2DTexture<Float> check(
                std::unique_ptr<TextureMapping2D>(new UVMapping2D(64, 64, 0, 0)),
                std::make_shared<ConstantTexture<Float>>(1.f),
                std::make_shared<ConstantTexture<Float>>(0.f), AAMethod::ClosedForm);
            Float du = .5f * (std::abs(si.dudx) + std::abs(si.dudy));
            Float dv = .5f * (std::abs(si.dvdx) + std::abs(si.dvdy));
            printf("%g %g %g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g "
                   "%.9g %.9g %.9g %.9g %.9g\n",
                   lens[0], pt[0], pt[1], si.p.x, si.p.y, si.p.z, si.dpdx.x, si.dpdx.y, si.dpdx.z,
                   si.dpdy.x, si.dpdy.y, si.dpdy.z, si.dudx, si.dvdx, si.dudy, si.dvdy, fbm, turb,
                   check.Evaluate(si), du, dv, si.uv.x);
        }
    }
    return 0;
}

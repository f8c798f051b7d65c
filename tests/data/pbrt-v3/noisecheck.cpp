#include "core/texture.h"
#include <cstdio>
using namespace pbrt;
int main() {
    float pts[][3] = {{0.5f,0.5f,0.5f},{1.3f,2.7f,0.4f},{-3.21f,7.7f,12.05f},{100.25f,-40.5f,3.125f}};
    for (auto &q : pts) {
        Point3f p(q[0],q[1],q[2]);
        Vector3f z(0,0,0);
        printf("%.9g %.9g %.9g\n", Noise(p), FBm(p, z, z, 0.5f, 8), Turbulence(p, z, z, 0.5f, 8));
    }
}

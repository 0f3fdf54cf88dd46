// libfive_mesher.cc — the libfive side of bench_equal_error.py: builds the bench's five
// surfaces (bench_error.c's formulas) as libfive trees, meshes one with libfive's dual
// contouring (Mesh::render, one worker) at a given min_feature and max_err, times the call
// in process CPU seconds, and writes the mesh as binary PLY (double x y z, uchar + int32
// faces) for bench_error measure. Built by the bench against a libfive built from source in
// a scratch folder (never part of isomesh's build).
//
//   libfive_mesher mesh NAME MIN_FEATURE MAX_ERR OUT.ply [REPEAT]
//                          prints {"cpu_s", "cpu_sd", "runs", "triangles"}: with REPEAT, the
//                          render call REPEAT times (the same mesh), cpu_s their mean and
//                          cpu_sd their standard deviation (bench_error.c's repeat=N)
//   libfive_mesher eval NAME X,Y,Z[;...]                   f at points (float), JSON list
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <ctime>
#include <string>
#include <vector>

#include "libfive.h"
#include "libfive/render/brep/mesh.hpp"
#include "libfive/render/brep/region.hpp"
#include "libfive/render/brep/settings.hpp"

using libfive::Tree;

namespace {

struct Surface {
    const char* name;
    double half;  // the box is [-half, half]^3
};

const Surface SURFACES[] = {
    {"sphere", 1.5}, {"torus", 1.5}, {"gyroid-ball", 1.5}, {"klein-bottle", 4.0},
    {"barth-sextic", 1.6}, {"kummer-4-nodes", 3.0}, {"kummer-16-nodes", 3.0},
};

Tree sq(const Tree& a) { return square(a); }

Tree build(const std::string& name)
{
    Tree x = Tree::X(), y = Tree::Y(), z = Tree::Z();
    Tree r2 = sq(x) + sq(y) + sq(z);
    if (name == "sphere")
        return r2 - Tree(1.0);
    if (name == "torus") {
        const double R = 1, r = 0.3;
        return sq(r2 + Tree(R * R - r * r)) - Tree(4 * R * R) * (sq(x) + sq(y));
    }
    if (name == "gyroid-ball") {
        Tree k(4.0);
        Tree g = sin(k * x) * cos(k * y) + sin(k * y) * cos(k * z) + sin(k * z) * cos(k * x);
        return max(g, r2 - Tree(1.96));
    }
    if (name == "klein-bottle") {
        Tree a = r2 + Tree(2.0) * y - Tree(1.0), b = r2 - Tree(2.0) * y - Tree(1.0);
        return a * (sq(b) - Tree(8.0) * sq(z)) + Tree(16.0) * x * z * b;
    }
    if (name == "barth-sextic") {
        const double phi = 1.6180339887498949, p2 = phi * phi;
        Tree b = Tree(4.0) * (Tree(p2) * sq(x) - sq(y)) * (Tree(p2) * sq(y) - sq(z)) *
                     (Tree(p2) * sq(z) - sq(x)) -
                 Tree(1 + 2 * phi) * sq(r2 - Tree(1.0));
        return max(b, r2 - Tree(2.25));
    }
    if (name == "kummer-4-nodes" || name == "kummer-16-nodes") {
        /* bench_error.c's KUMMER4: mu2 = 0.6667 (4 nodes) or 2 (16), w = 1 */
        const double mu2 = name == "kummer-4-nodes" ? 0.6667 : 2.0, w = 1;
        const double lambda = (3 * mu2 - 1) / (3 - mu2), s2 = std::sqrt(2.0);
        Tree p = Tree(w) - z - Tree(s2) * x, q = Tree(w) - z + Tree(s2) * x;
        Tree r = Tree(w) + z + Tree(s2) * y, s = Tree(w) + z - Tree(s2) * y;
        return sq(r2 - Tree(mu2)) - Tree(lambda) * p * q * r * s;
    }
    return Tree::invalid();
}

double cpu_seconds()
{
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

bool write_ply(const char* path, const libfive::Mesh& m)
{
    FILE* f = std::fopen(path, "wb");
    if (!f)
        return false;
    std::fprintf(f, "ply\nformat binary_little_endian 1.0\ncomment libfive\n"
                    "element vertex %zu\nproperty double x\nproperty double y\n"
                    "property double z\nelement face %zu\n"
                    "property list uchar int vertex_indices\nend_header\n",
                 m.verts.size(), m.branes.size());
    for (const auto& v : m.verts) {
        double p[3] = {v.x(), v.y(), v.z()};
        std::fwrite(p, sizeof p[0], 3, f);
    }
    for (const auto& t : m.branes) {
        unsigned char n = 3;
        int32_t i[3] = {int32_t(t.x()), int32_t(t.y()), int32_t(t.z())};
        std::fwrite(&n, 1, 1, f);
        std::fwrite(i, sizeof i[0], 3, f);
    }
    return std::fclose(f) == 0;
}

int mesh(const Surface& s, double min_feature, double max_err, const char* out, int repeat)
{
    Tree t = build(s.name);
    libfive::Region<3> region({-s.half, -s.half, -s.half}, {s.half, s.half, s.half});
    libfive::BRepSettings settings;
    settings.min_feature = min_feature;
    settings.max_err = max_err;
    settings.workers = 1;
    std::unique_ptr<libfive::Mesh> m;
    double sum = 0, sum2 = 0;
    for (int r = 0; r < repeat; r++) {
        m.reset();  // the last run's mesh is the one written
        double c0 = cpu_seconds();
        m = libfive::Mesh::render(t, region, settings);
        double cpu = cpu_seconds() - c0;
        sum += cpu;
        sum2 += cpu * cpu;
        if (!m)
            break;
    }
    if (!m || !write_ply(out, *m)) {
        std::fprintf(stderr, "libfive_mesher: %s failed\n", s.name);
        return 1;
    }
    double mean = sum / repeat;
    double sd = repeat > 1 ? std::sqrt(std::fmax(0.0, (sum2 - sum * mean) / (repeat - 1))) : 0;
    std::printf("{\"cpu_s\": %.6f, \"cpu_sd\": %.6f, \"runs\": %d, \"triangles\": %zu}\n",
                mean, sd, repeat, m->branes.size());
    return 0;
}

int eval(const Surface& s, const char* text)
{
    Tree t = build(s.name);
    std::printf("[");
    for (int n = 0; *text; n++) {
        float p[3];
        int used;
        if (std::sscanf(text, "%f,%f,%f%n", &p[0], &p[1], &p[2], &used) != 3)
            return 1;
        std::printf("%s%.9g", n ? ", " : "", libfive_tree_eval_f(t.get(), {p[0], p[1], p[2]}));
        text += used;
        text += *text == ';';
    }
    std::printf("]\n");
    return 0;
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc < 4) {
        std::fprintf(stderr, "usage: libfive_mesher mesh NAME MIN_FEATURE MAX_ERR OUT.ply [REPEAT] | "
                             "eval NAME X,Y,Z[;...]\n");
        return 2;
    }
    for (const Surface& s : SURFACES) {
        if (std::strcmp(s.name, argv[2]) != 0)
            continue;
        int repeat = argc == 7 ? std::atoi(argv[6]) : 1;
        if (std::strcmp(argv[1], "mesh") == 0 && (argc == 6 || argc == 7) && repeat >= 1 &&
            repeat <= 1000)
            return mesh(s, std::atof(argv[3]), std::atof(argv[4]), argv[5], repeat);
        if (std::strcmp(argv[1], "eval") == 0)
            return eval(s, argv[3]);
        return 2;
    }
    std::fprintf(stderr, "libfive_mesher: unknown surface %s\n", argv[2]);
    return 2;
}
